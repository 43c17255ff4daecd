"""qemu-m7 images in QEMU: every self-test result bit-identical to the Python reference.

The firmware compares each output value with its embedded expected outputs
(from the reference) and prints CRC-32 digests of all inputs and outputs;
the host recomputes both digests here from freshly generated states and a
fresh reference run, so an image that only printed 'PASS' could not pass.
"""
from __future__ import annotations

import os

import numpy as np
import pytest

from codegen import emulate
from codegen import fwproject as firmware
from codegen.fwdata import selftest_states, trajectory_states, values_crc
from codegen.twolevel.interface import INPUT_FIELDS, OUTPUT_FIELDS
from codegen.twolevel.reference import step_batch

from fw_support import STRATEGIES, needs_qemu, spmsm

N_SELFTEST = 10_000
N_BENCH = 2_000


def _gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    return False


@pytest.fixture(scope="module")
def images(tmp_path_factory):
    """Built qemu-m7 project per strategy (built lazily, once)."""
    cache: dict[str, firmware.BuildResult] = {}

    def get(strategy: str) -> firmware.BuildResult:
        if strategy not in cache:
            m, t = spmsm(strategy)
            out = tmp_path_factory.mktemp(f"qemu_{strategy}")
            firmware.write_firmware_project(m, t, "qemu-m7", out, N_SELFTEST, n_bench=N_BENCH)
            cache[strategy] = firmware.build_firmware(out, "qemu-m7")
        return cache[strategy]

    return get


@needs_qemu
@pytest.mark.slow
@pytest.mark.parametrize("strategy", STRATEGIES)
def test_selftest_bit_exact_in_qemu(images, strategy):
    m, t = spmsm(strategy)
    build = images(strategy)
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
    b = trajectory_states(m, t, N_BENCH)
    for name, states in (("selftest", x), ("bench", b)):
        s = rep.sets[name]
        assert s.n == len(states) and s.mismatches == 0, s.details[:20]
        assert s.crc_in == values_crc(states, INPUT_FIELDS)
        assert s.crc_out == values_crc(step_batch(t, states), OUTPUT_FIELDS)
    assert rep.sets["selftest"].n >= 10_000
    bench = rep.sets["bench"]
    assert len(bench.cycles) == N_BENCH and min(bench.cycles) > 0


@needs_qemu
@pytest.mark.slow
def test_mismatch_is_detected_and_reported(tmp_path, monkeypatch):
    """A wrong embedded expectation must fail the run with per-mismatch details."""
    m, t = spmsm("s3")
    real = firmware.make_test_sets

    def corrupted(*args, **kwargs):
        sets = real(*args, **kwargs)
        e = sets[0].expected
        e["te_nm"][5] = np.nextafter(e["te_nm"][5], np.float32(np.inf))
        e["cand"][7][1] ^= 1
        return sets

    monkeypatch.setattr(firmware, "make_test_sets", corrupted)
    firmware.write_firmware_project(m, t, "qemu-m7", tmp_path, 300, n_bench=0)
    run = emulate.run_qemu(firmware.build_firmware(tmp_path, "qemu-m7").image, timeout_s=120)
    rep = emulate.parse_console(run.uart)
    assert run.returncode == 1 and rep.result == "FAIL" and rep.exit_code == 1
    s = rep.sets["selftest"]
    assert s.mismatches == 2
    assert any("i=5 field=te_nm" in d for d in s.details)
    assert any("i=7 field=cand[1]" in d for d in s.details)
    assert any(d.startswith("STATE set=selftest i=5 ") for d in s.details)
    # the firmware's digest is of what it computed: still the true reference
    monkeypatch.undo()
    assert s.crc_out == values_crc(step_batch(t, selftest_states(m, t, 300)), OUTPUT_FIELDS)


@needs_qemu
@pytest.mark.slow
def test_systick_scaling_and_timeout_cleanup(images):
    """ticks = instructions * 2^shift / 40 at another shift; a timed-out QEMU is killed."""
    build = images("s3")
    for shift in (6, 8):
        rep = emulate.parse_console(emulate.run_qemu(build.image, icount_shift=shift).uart)
        assert abs(emulate.check_calibration(rep, shift) - 1024) <= 0.5
    run = emulate.run_qemu(build.image, timeout_s=0)
    assert run.timed_out and run.returncode is None
    assert _gone(run.pid)
