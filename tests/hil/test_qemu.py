"""The emulated board: the qemu-m7 protocol image in QEMU, UART0 on a TCP socket (hil/qemu.py).

For every strategy of both examples, the bench trajectory
(``trajectory_states(model, 2000)``, the states ``mpcgen bench --emulated``
times) goes through the protocol image and must match the Python reference
bit for bit.  The self-test image of the same model (the one bench runs,
``emulate.run_and_check``) times the same states; its CYC values are SysTick
ticks, converted by bench to instructions (ticks * 40 / 2**10, within
+-0.04 of a whole number).  Both images time the same sequence
(mpc_timed_call around the step, minus the same sequence around an empty
function), so the protocol image's instruction count must EQUAL the self-test's
count rounded to the nearest instruction, state by state, with no constant
overhead in between: the protocol's extra code (framing, CRC, the port's
tick-to-instruction conversion) lies outside the timed window or cancels in
the overhead subtraction.
"""
from __future__ import annotations

import json
import socket

import numpy as np
import pytest
from hil_support import CASE_IDS, CASES, SPMSM, example

from codegen.compare import mismatch_mask
from codegen.stages import emulate
from codegen.stages.fwdata import N_BENCH, trajectory_states
from codegen.topology import topology_of
from hil.boards import open_board
from hil.cli import main
from hil.messages import split_results
from hil.qemu import TIMEOUT_S, QemuBoard, build_qemu_board
from hil.schema import Schema
from hil.session import Session

from conftest import require_tool

pytestmark = pytest.mark.slow


@pytest.fixture(autouse=True)
def _tools():
    require_tool("qemu-system-arm", "qemu-system-arm")
    require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi")


@pytest.mark.parametrize("config,strategy", CASES, ids=CASE_IDS)
def test_qemu_replays_the_bench_set_with_bench_instruction_counts(config, strategy, tmp_path):
    model, tables = example(config, strategy)
    schema = Schema.of(model)
    states = trajectory_states(model, N_BENCH)
    with open_board(model, tables, None, board="qemu-m7") as link:
        session = Session(link, schema, timeout_s=TIMEOUT_S)
        info = session.handshake()
        assert info.target == "qemu-m7" and info.cycle_unit == "instructions"
        res = session.run(states)
    assert res.answered.all() and not res.lost
    cycles, got = split_results(schema, res.payloads)
    bad, per_field = mismatch_mask(topology_of(model).step_batch(tables, states), got)
    assert not bad.any(), per_field
    # the same states timed by the self-test image (what bench --emulated reports)
    counts = emulate.run_and_check(model, tables, tmp_path / "selftest", n_selftest=1, n_bench=N_BENCH)
    assert counts.mismatches == 0 and counts.digests_match
    bench = emulate.ticks_to_instructions(emulate.parse_console(counts.uart).sets["bench"].cycles)
    assert len(bench) == N_BENCH
    assert np.abs(bench - np.rint(bench)).max() < 0.05  # ticks resolve whole instructions
    assert np.array_equal(cycles.astype(np.int64), np.rint(bench).astype(np.int64))
    assert float(np.median(cycles)) == pytest.approx(counts.instr_median, abs=0.05)


def test_hil_command_on_qemu(tmp_path, capsys):
    out = tmp_path / "hil.json"
    sets = ["--set", "controller.tables=published", "--set", "controller.strategy=s2", "--set", "target.name=stm32h743"]
    rc = main(["hil", str(SPMSM), *sets, "--board", "qemu-m7", "--states", "2100", "--json", str(out)])
    data = json.loads(out.read_text())
    assert rc == 0, capsys.readouterr().err
    # the JSON names the C the emulated STM32H743 runs: the hash generate's manifest names for that target
    assert main(["generate", str(SPMSM), *sets, "--target", "stm32h743", "-o", str(tmp_path / "c"), "-q"]) == 0
    manifest = json.loads(next((tmp_path / "c").glob("*_manifest.json")).read_text())
    assert (data["c_hash"], data["c_hash_target"]) == (manifest["c_hash"], "stm32h743")
    assert data["states"] == 2100 and data["mismatches"] == 0 and data["lost"] == 0
    assert data["cycle_unit"] == "instructions" and data["board"]["target"] == "qemu-m7"
    assert data["wire"]["resent_states"] == 0
    # QEMU counts instructions (-icount): instructions_* keys, no cycles_*, and no clock printed
    assert 0 < data["instructions_min"] <= data["instructions_median"] <= data["instructions_max"]
    assert not [k for k in data if k.startswith("cycles_")]
    err = capsys.readouterr().err
    assert "timings in instructions" in err and " Hz" not in err


def test_qemu_is_killed_and_its_port_freed(tmp_path):
    model, tables = example("spmsm", "s1")
    with QemuBoard(build_qemu_board(model, tables)) as qemu:
        proc = qemu.proc
        port = qemu.port
        assert proc is not None and proc.poll() is None
    assert proc.poll() is not None
    with socket.socket() as s:  # nothing listens there any more
        assert s.connect_ex(("127.0.0.1", port)) != 0
