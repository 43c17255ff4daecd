"""qemu-m3 (QEMU mps2-an385, Cortex-M3, no FPU): the fixed-point self-test of every strategy of both
topologies passes bit for bit in an image that holds no floating-point instruction.

The image is built with -mfloat-abi=soft; the step's products are SMLAL/UMULL, its quotients and square
roots 32-bit UDIVs: no libgcc routine, 64-bit or software-float, is called from the step (issue 30; it
called __aeabi_ldivmod before).  As for qemu-m7, the host recomputes the CRC-32 digests of every input and
output from freshly generated states and a fresh reference run.
"""
from __future__ import annotations

import subprocess

import pytest

from codegen.stages import emulate
from codegen.stages import firmware as firmware
from codegen.stages.fwdata import N_BENCH, in_step_format, layouts, selftest_states, trajectory_states
from codegen.topology import topology_of

from fw_support import CASE_IDS, CASES, example, needs_qemu

N_SELFTEST = 10_000
BOARD = firmware.NOFPU_BOARD


def test_board_is_a_core_without_fpu():
    b = firmware.board_spec(BOARD)
    assert b.qemu == ("mps2-an385", "cortex-m3") and "-mfloat-abi=soft" in b.cpu_flags
    assert not any(f.startswith("-mfpu") for f in b.cpu_flags)


@needs_qemu
@pytest.mark.slow
@pytest.mark.parametrize("config,strategy", CASES, ids=CASE_IDS)
def test_fixed_selftest_bit_exact_without_fpu(tmp_path, config, strategy):
    m, t = example(config, strategy, "fixed")
    inp, out = layouts(m)
    topo = topology_of(m)
    firmware.write_firmware_project(m, t, BOARD, tmp_path, N_SELFTEST, n_bench=N_BENCH)
    build = firmware.build_firmware(tmp_path, BOARD)
    assert build.text > 0 and build.stack_depth > 0
    # no floating-point instruction or register anywhere in the image, no software-float call in the step
    dis = subprocess.run(["arm-none-eabi-objdump", "-d", str(build.image)], capture_output=True, text=True).stdout
    assert not any(w in dis for w in ("\tvmov", "\tvadd", "\tvmul", "\tvldr", "\tvstr", "\tvcvt"))
    step = subprocess.run(["arm-none-eabi-objdump", "-d", str(tmp_path / "build" / "gen" / f"{m.prefix}_mpc.o")],
                          capture_output=True, text=True).stdout
    assert "__aeabi_f" not in step and "__aeabi_d" not in step
    assert not any(f"__aeabi_{r}" in step for r in ("lmul", "ldivmod", "uldivmod", "llsl", "llsr", "lasr"))

    run = emulate.run_qemu(build.image, timeout_s=600, board=BOARD)
    assert not run.timed_out, run.uart[-500:]
    rep = emulate.parse_console(run.uart)
    assert run.returncode == 0 and rep.exit_code == 0 and rep.result == "PASS", run.uart[-2000:]
    assert rep.errors == [] and rep.hello["board"] == BOARD
    assert rep.hello["config"] == m.config_hash() and rep.hello["strategy"] == strategy
    emulate.check_calibration(rep)
    x = selftest_states(m, t, N_SELFTEST)
    b = in_step_format(m, t, trajectory_states(m, N_BENCH))
    for name, states in (("selftest", x), ("bench", b)):
        s = rep.sets[name]
        assert s.n == len(states) and s.mismatches == 0, s.details[:20]
        assert s.crc_in == inp.crc(states)
        assert s.crc_out == out.crc(topo.step_batch(t, states))
