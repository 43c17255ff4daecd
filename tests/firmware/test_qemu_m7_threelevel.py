"""Three-level (T-type) qemu-m7 images in QEMU: bit-identical to the Python reference.

The same firmware runtime as the two-level images; ``codegen.fwdata.topology_of``
picks the three-level records, reference, self-test states (guard cases +
adversarial + random, codegen.threelevel.states) and the bench trajectory
(the 27-MPDTC run at rated speed).  The host recomputes every digest from
freshly generated states and a fresh reference run.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from codegen import emulate
from codegen import fwproject as firmware
from codegen.errors import MpcgenError
from codegen.fwdata import (TWO_LEVEL, canonical_bytes, guard_cases3, selftest_states, topology_of,
                            trajectory_states, values_crc)
from codegen.threelevel.interface import FAULT_BITS, INPUT_DTYPE, INPUT_FIELDS, OUTPUT_FIELDS
from codegen.threelevel.reference import step_batch

from fw_support import THREE_LEVEL_STRATEGIES, TLEVEL, needs_arm, needs_qemu, spmsm, tlevel

N_SELFTEST = 10_000
N_BENCH = 2_000


def _octets(x: np.ndarray) -> np.ndarray:
    """Values of the records (NaN compared by bits, struct padding ignored)."""
    return canonical_bytes(x, INPUT_FIELDS)


def test_topology_adapter():
    m, _ = tlevel("mpdtc27")
    topo = topology_of(m)
    assert topo.name == "t-type" and topo.input_fields is INPUT_FIELDS and topo.output_fields is OUTPUT_FIELDS
    assert topology_of(spmsm("conventional")[0]) is TWO_LEVEL


@pytest.mark.parametrize("strategy", THREE_LEVEL_STRATEGIES)
def test_selftest_states_cover_every_guard(strategy):
    m, t = tlevel(strategy)
    x = selftest_states(m, t, N_SELFTEST)
    assert x.dtype == INPUT_DTYPE and len(x) == N_SELFTEST
    g = guard_cases3(m, t)
    assert np.array_equal(_octets(x[: len(g)]), _octets(g))
    assert np.array_equal(_octets(x), _octets(selftest_states(m, t, N_SELFTEST)))  # deterministic
    y = step_batch(t, x)
    for _, bit, _ in FAULT_BITS:
        assert np.any(y["fault"] == bit), f"no state trips only fault bit {bit}"
    ok = y["fault"] == 0
    assert ok.mean() > 0.5
    assert np.any(y["vector"][ok] < 27)
    if strategy == "mpdtc63":  # virtual vectors too
        assert np.any(y["vector"][ok] >= 27)
    for f in OUTPUT_FIELDS:
        if f.ctype == "float":
            assert np.all(np.isfinite(y[f.name]))


@pytest.fixture(scope="module")
def images(tmp_path_factory):
    cache: dict[str, firmware.BuildResult] = {}

    def get(strategy: str) -> firmware.BuildResult:
        if strategy not in cache:
            m, t = tlevel(strategy)
            out = tmp_path_factory.mktemp(f"qemu3_{strategy}")
            firmware.write_firmware_project(m, t, "qemu-m7", out, N_SELFTEST, n_bench=N_BENCH)
            cache[strategy] = firmware.build_firmware(out, "qemu-m7")
        return cache[strategy]

    return get


@needs_qemu
@pytest.mark.slow
@pytest.mark.parametrize("strategy", THREE_LEVEL_STRATEGIES)
def test_three_level_selftest_bit_exact_in_qemu(images, strategy):
    m, t = tlevel(strategy)
    build = images(strategy)
    assert "mpc_selftest_run" in build.log or build.stack_depth > 0
    run = emulate.run_qemu(build.image, timeout_s=300)
    assert not run.timed_out, run.uart[-500:]
    rep = emulate.parse_console(run.uart)
    assert run.returncode == 0 and rep.exit_code == 0 and rep.result == "PASS", run.uart[-2000:]
    assert rep.errors == []
    assert rep.hello["config"] == m.config_hash() and rep.hello["strategy"] == strategy
    emulate.check_calibration(rep)

    x = selftest_states(m, t, N_SELFTEST)
    b = trajectory_states(m, t, N_BENCH)
    for name, states in (("selftest", x), ("bench", b)):
        s = rep.sets[name]
        assert s.n == len(states) and s.mismatches == 0, s.details[:20]
        assert s.crc_in == values_crc(states, INPUT_FIELDS)
        assert s.crc_out == values_crc(step_batch(t, states), OUTPUT_FIELDS)
    assert rep.sets["selftest"].n >= 2000
    bench = rep.sets["bench"]
    assert len(bench.cycles) == N_BENCH and min(bench.cycles) > 0
    # the bench trajectory is the 27-MPDTC run at rated speed, whatever the strategy
    assert np.array_equal(_octets(b), _octets(trajectory_states(*tlevel("mpdtc27"), N_BENCH)))


@needs_qemu
@pytest.mark.slow
def test_three_level_mismatch_is_detected(tmp_path, monkeypatch):
    """A wrong expectation in an array field (costs, cand) is reported per value."""
    m, t = tlevel("mpdtc27")
    real = firmware.make_test_sets

    def corrupted(*args, **kwargs):
        sets = real(*args, **kwargs)
        e = sets[0].expected
        e["costs"][150][18] = np.nextafter(e["costs"][150][18], np.float32(np.inf))
        e["cand"][160][3] ^= 1
        return sets

    monkeypatch.setattr(firmware, "make_test_sets", corrupted)
    firmware.write_firmware_project(m, t, "qemu-m7", tmp_path, 300, n_bench=0)
    run = emulate.run_qemu(firmware.build_firmware(tmp_path, "qemu-m7").image, timeout_s=120)
    rep = emulate.parse_console(run.uart)
    assert run.returncode == 1 and rep.result == "FAIL"
    s = rep.sets["selftest"]
    assert s.mismatches == 2
    assert any("i=150 field=costs[18]" in d for d in s.details)
    assert any("i=160 field=cand[3]" in d for d in s.details)


def test_three_level_board_budgets(tmp_path):
    """27-MPDTC outputs are 204 octets: the STM32H743 gets compact CRCs, the C2000 refuses 12 000 states."""
    m, t = tlevel("mpdtc27")
    firmware.write_firmware_project(m, t, "stm32h743", tmp_path / "h7", 10_000, n_bench=0)
    data = (tmp_path / "h7/gen/mpc_selftest_data.c").read_text()
    assert "selftest_expected_crc" in data and "codegen.threelevel.reference.step_batch" in data
    firmware.write_firmware_project(m, t, "stm32h743", tmp_path / "h7full", 5000, n_bench=0)
    assert "selftest_expected_crc" not in (tmp_path / "h7full/gen/mpc_selftest_data.c").read_text()
    with pytest.raises(MpcgenError) as err:
        firmware.write_firmware_project(m, t, "tms320f28377", tmp_path / "c2000", 20_000, n_bench=0)
    assert "lower n_selftest" in str(err.value)


@needs_arm
@pytest.mark.slow
def test_three_level_stm32h743_builds(tmp_path):
    m, t = tlevel("mpdtc63")
    firmware.write_firmware_project(m, t, "stm32h743", tmp_path, 2000, n_bench=0)
    b = firmware.build_firmware(tmp_path, "stm32h743")
    assert b.text > 0 and 0 < b.stack_depth < 8192


@needs_qemu
@pytest.mark.slow
def test_three_level_emulated_bench(tmp_path):
    from codegen.cli import main

    js = tmp_path / "bench3.json"
    assert main(["bench", str(TLEVEL), "--emulated", "--json", str(js), "--repeats", "1", "-q"]) == 0
    data = json.loads(js.read_text())
    s27, s63 = data["strategies"]["mpdtc27"], data["strategies"]["mpdtc63"]
    assert s27["m7_instructions_per_step"] > 100 and s27["ratio_to_conventional"] == 1.0
    # 63-MPDTC evaluates 3..7 voltage groups instead of 19: fewer instructions
    assert s63["m7_instructions_per_step"] < s27["m7_instructions_per_step"]
