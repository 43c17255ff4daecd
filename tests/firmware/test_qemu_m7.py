"""qemu-m7 images in QEMU, every strategy of both topologies: bit-identical to the Python reference.

The firmware compares each output value with its embedded expected outputs
(from the reference) and prints CRC-32 digests of all inputs and outputs;
the host recomputes both digests here from freshly generated states and a
fresh reference run, so an image that only printed 'PASS' could not pass.
"""
from __future__ import annotations

import json
import os

import numpy as np
import pytest

from codegen.errors import MpcgenError
from codegen.records import REAL
from codegen.stages import emulate
from codegen.stages import firmware as firmware
from codegen.stages.fwdata import N_BENCH, layouts, selftest_states, trajectory_states
from codegen.topology import topology_of

from fw_support import CASE_IDS, CASES, SPMSM, TTYPE, example, needs_arm, needs_qemu

N_SELFTEST = 10_000
#: a corrupted expectation per topology: (set index, field, record, element or None)
CORRUPT = {"spmsm": ("s3", [(5, "te_est_nm", None), (7, "cand", 1)]),
           "tlevel": ("mpdtc27", [(150, "costs", 18), (160, "cand", 3)])}


def _gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    return False


@pytest.fixture(scope="module")
def images(tmp_path_factory):
    """Built qemu-m7 project per (config, strategy), built lazily, once."""
    cache: dict[tuple[str, str], firmware.BuildResult] = {}

    def get(config: str, strategy: str) -> firmware.BuildResult:
        if (config, strategy) not in cache:
            m, t = example(config, strategy)
            out = tmp_path_factory.mktemp(f"qemu_{config}_{strategy}")
            firmware.write_firmware_project(m, t, "qemu-m7", out, N_SELFTEST, n_bench=N_BENCH)
            cache[config, strategy] = firmware.build_firmware(out, "qemu-m7")
        return cache[config, strategy]

    return get


@pytest.mark.parametrize("config,strategy", CASES, ids=CASE_IDS)
def test_selftest_states_cover_every_guard(config, strategy):
    """Guard cases first, deterministic, every fault bit alone, finite reference outputs."""
    m, t = example(config, strategy)
    topo = topology_of(m)
    inp, _ = layouts(m)
    x = selftest_states(m, t, N_SELFTEST)
    assert x.dtype == inp.dtype and len(x) == N_SELFTEST
    assert np.array_equal(inp.pack(x), inp.pack(selftest_states(m, t, N_SELFTEST)))
    y = topo.step_batch(t, x)
    bits = sorted({int(b) for b in y["fault"] if b and not (b & (b - 1))})
    assert len(bits) >= 7, f"single fault bits seen: {bits}"
    assert (y["fault"] == 0).mean() > 0.5
    for f in topo.output_record(m).fields:
        if f.kind == REAL:
            assert np.all(np.isfinite(y[f.name]))


@needs_qemu
@pytest.mark.slow
@pytest.mark.parametrize("config,strategy", CASES, ids=CASE_IDS)
def test_selftest_bit_exact_in_qemu(images, config, strategy):
    m, t = example(config, strategy)
    inp, out = layouts(m)
    topo = topology_of(m)
    build = images(config, strategy)
    run = emulate.run_qemu(build.image, timeout_s=300)
    assert _gone(run.pid), "QEMU still running after run_qemu returned"
    assert not run.timed_out, run.uart[-500:]
    rep = emulate.parse_console(run.uart)
    assert run.returncode == 0 and rep.exit_code == 0 and rep.result == "PASS", run.uart[-2000:]
    assert rep.errors == []
    assert rep.hello["config"] == m.config_hash() and rep.hello["strategy"] == strategy
    emulate.check_calibration(rep)

    # independent host recomputation: states regenerated, reference rerun
    x = selftest_states(m, t, N_SELFTEST)
    b = trajectory_states(m, N_BENCH)
    for name, states in (("selftest", x), ("bench", b)):
        s = rep.sets[name]
        assert s.n == len(states) and s.mismatches == 0, s.details[:20]
        assert s.crc_in == inp.crc(states)
        assert s.crc_out == out.crc(topo.step_batch(t, states))
    assert rep.sets["selftest"].n >= 10_000
    bench = rep.sets["bench"]
    assert len(bench.cycles) == N_BENCH and min(bench.cycles) > 0
    # every strategy is benchmarked on the baseline's trajectory
    base_m, _ = example(config, topo.strategies[0])
    assert np.array_equal(inp.pack(b), inp.pack(trajectory_states(base_m, N_BENCH)))


@needs_qemu
@pytest.mark.slow
@pytest.mark.parametrize("config", sorted(CORRUPT))
def test_mismatch_is_detected_and_reported(tmp_path, monkeypatch, config):
    """A wrong embedded expectation (scalar or array element) fails the run, reported per value."""
    strategy, edits = CORRUPT[config]
    m, t = example(config, strategy)
    real = firmware.make_test_sets

    def corrupted(*args, **kwargs):
        sets = real(*args, **kwargs)
        e = sets[0].expected
        for i, name, j in edits:
            col = e[name]
            if col.dtype.kind == "f":
                if j is None:
                    col[i] = np.nextafter(col[i], np.float32(np.inf))
                else:
                    col[i][j] = np.nextafter(col[i][j], np.float32(np.inf))
            else:
                col[i][j] ^= 1
        return sets

    monkeypatch.setattr(firmware, "make_test_sets", corrupted)
    firmware.write_firmware_project(m, t, "qemu-m7", tmp_path, 300, n_bench=0)
    run = emulate.run_qemu(firmware.build_firmware(tmp_path, "qemu-m7").image, timeout_s=120)
    rep = emulate.parse_console(run.uart)
    assert run.returncode == 1 and rep.result == "FAIL" and rep.exit_code == 1
    s = rep.sets["selftest"]
    assert s.mismatches == 2
    for i, name, j in edits:
        field = name if j is None else f"{name}[{j}]"
        assert any(f"i={i} field={field}" in d for d in s.details), s.details
    assert any(d.startswith(f"STATE set=selftest i={edits[0][0]} ") for d in s.details)
    # the firmware's digest is of what it computed: still the true reference
    monkeypatch.undo()
    _, out = layouts(m)
    assert s.crc_out == out.crc(topology_of(m).step_batch(t, selftest_states(m, t, 300)))


@needs_qemu
@pytest.mark.slow
def test_systick_scaling_and_timeout_cleanup(images):
    """ticks = instructions * 2^shift / 40 at another shift; a timed-out QEMU is killed."""
    build = images("spmsm", "s3")
    for shift in (6, 8):
        rep = emulate.parse_console(emulate.run_qemu(build.image, icount_shift=shift).uart)
        assert abs(emulate.check_calibration(rep, shift) - 1024) <= 0.5
    run = emulate.run_qemu(build.image, timeout_s=0)
    assert run.timed_out and run.returncode is None
    assert _gone(run.pid)


def test_board_budgets(tmp_path):
    """27-MPDTC outputs are 204 octets: the STM32H743 gets compact CRCs, the C2000 refuses 20 000 states."""
    m, t = example("tlevel", "mpdtc27")
    firmware.write_firmware_project(m, t, "stm32h743", tmp_path / "h7", 10_000, n_bench=0)
    data = (tmp_path / "h7/gen/mpc_selftest_data.c").read_text()
    assert "selftest_expected_crc" in data and "codegen.topologies.ttype.reference.step_batch" in data
    firmware.write_firmware_project(m, t, "stm32h743", tmp_path / "h7full", 5000, n_bench=0)
    assert "selftest_expected_crc" not in (tmp_path / "h7full/gen/mpc_selftest_data.c").read_text()
    with pytest.raises(MpcgenError) as err:
        firmware.write_firmware_project(m, t, "tms320f28377", tmp_path / "c2000", 20_000, n_bench=0)
    assert "lower n_selftest" in str(err.value)


@needs_arm
@pytest.mark.slow
def test_ttype_stm32h743_builds(tmp_path):
    m, t = example("tlevel", "mpdtc63")
    firmware.write_firmware_project(m, t, "stm32h743", tmp_path, 2000, n_bench=0)
    b = firmware.build_firmware(tmp_path, "stm32h743")
    assert b.text > 0 and 0 < b.stack_depth < 8192


@needs_qemu
@pytest.mark.slow
def test_ttype_emulated_bench(tmp_path):
    from codegen.cli import main

    js = tmp_path / "bench3.json"
    assert main(["bench", str(TTYPE), "--emulated", "--json", str(js), "--repeats", "1", "-q"]) == 0
    data = json.loads(js.read_text())
    s27, s63 = data["strategies"]["mpdtc27"], data["strategies"]["mpdtc63"]
    assert s27["m7_instructions_per_step"] > 100 and s27["ratio_to_conventional"] == 1.0
    # 63-MPDTC evaluates 3..7 voltage groups instead of 19: fewer instructions
    assert s63["m7_instructions_per_step"] < s27["m7_instructions_per_step"]


@needs_qemu
@pytest.mark.slow
def test_ttype_firmware_command_builds_and_runs(tmp_path):
    """`mpcgen firmware` on a t-type config writes a qemu-m7 project that builds (no two-level fallback)
    and whose `make run` passes its self-test in QEMU."""
    import subprocess

    from codegen.cli import main

    out = tmp_path / "fw3"
    assert main(["firmware", str(TTYPE), "--board", "qemu-m7", "-o", str(out), "-q"]) == 0
    r = subprocess.run(["make", "-C", str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    assert "tlevel_step" in (out / "gen" / "tlevel_mpc.c").read_text()
    r = subprocess.run(["make", "-s", "-C", str(out), "run"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0 and "RESULT PASS" in r.stdout, r.stdout[-2000:] + r.stderr[-2000:]



FIXED_CONFIGS = ("seed001_spmsm", "seed001_ipmsm", "seed000_tlevel")


@needs_qemu
@pytest.mark.slow
@pytest.mark.parametrize("config", FIXED_CONFIGS)
def test_fixed_point_firmware_is_bit_exact(tmp_path, config):
    """`mpcgen firmware --number-format fixed --board qemu-m7`: int32 records, built warning-free
    (-Werror), every self-test and bench state bit for bit in QEMU; the host recomputes the digests
    from freshly generated fixed-point states and the fixed-point reference."""
    from codegen.cli import main
    from codegen.config import load_config

    cfg = SPMSM.parent / f"{config}.toml"
    assert main(["firmware", str(cfg), "--number-format", "fixed", "--board", "qemu-m7", "-o", str(tmp_path)]) == 0
    b = firmware.build_firmware(tmp_path, "qemu-m7")
    assert "warning" not in b.log
    run = emulate.run_qemu(b.image, timeout_s=300)
    rep = emulate.parse_console(run.uart)
    assert run.returncode == 0 and rep.result == "PASS", run.uart[-2000:]
    m = load_config(cfg, {"controller.number_format": "fixed"})
    t = topology_of(m).derive(m)
    sets = firmware.make_test_sets(m, t, N_SELFTEST, N_BENCH)
    inp, out = layouts(m)
    assert sets[0].states["ia_a"].dtype == np.int32 and sets[1].states["ia_a"].dtype == np.int32
    for ts in sets:
        s = rep.sets[ts.name]
        assert s.n == len(ts.states) and s.mismatches == 0, s.details[:20]
        assert s.crc_in == inp.crc(ts.states) and s.crc_out == out.crc(ts.expected)
