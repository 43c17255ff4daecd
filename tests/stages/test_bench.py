"""`mpcgen bench`: host ns/step for every strategy side by side, sim throughput (both plant integrators);
emulated M7 counts."""
from __future__ import annotations

import json

import pytest

from codegen.cli import main
from codegen.stages.fwdata import N_BENCH

from conftest import SPMSM, TWO_LEVEL, require_tool


def test_host_bench(tmp_path, capsys):
    js = tmp_path / "bench.json"
    assert main(["bench", str(SPMSM), "--json", str(js), "--repeats", "2", "-q"]) == 0
    data = json.loads(js.read_text())
    assert data["trajectory_states"] == 80_000
    assert data["sim_periods_per_s"] > 0
    for s in TWO_LEVEL:
        e = data["strategies"][s]
        assert e["host_ns_per_step"] > 0 and e["ratio_to_conventional"] > 0
        # CPU time, interleaved rounds: the fastest round, the median beside it and their spread
        assert e["host_ns_median"] >= e["host_ns_per_step"] and e["host_ns_spread"] >= 0
    assert data["strategies"]["conventional"]["ratio_to_conventional"] == 1.0
    assert "thread_time_ns" in data["host_timing"] and "2 rounds" in data["host_timing"]
    # the plant's integrators side by side: periods/s of the scenario, current error against DOP853
    sim = data["simulator"]
    assert sim["periods"] == 80_000 and sim["error_periods"] == 1000 and sim["rounds"] == 2
    assert set(sim["integrators"]) == {"rk4", "exact"}
    for e in sim["integrators"].values():
        assert e["periods_per_s"] > 0 and 0 <= e["max_current_error_a"] < 1e-9 and e["decisions_identical"]
    out = capsys.readouterr().out
    assert "host ns/step" in out and "simulator periods/s" in out and "exact" in out
    assert "host timing: CPU time of the timing thread" in out and "spread" in out


@pytest.mark.slow
def test_emulated_bench(tmp_path, capsys):
    require_tool("qemu-system-arm", "qemu-system-arm")
    require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi")
    js = tmp_path / "benchm7.json"
    assert main(["bench", str(SPMSM), "--emulated", "--json", str(js), "--repeats", "1", "-q"]) == 0
    data = json.loads(js.read_text())
    # one state set for every M7 figure: the instructions (QEMU) and the cycle estimate (every state
    # traced) over the same N_BENCH bench states, the count stated in the output
    assert data["m7_states"] == N_BENCH
    assert f"the same {N_BENCH} bench states" in capsys.readouterr().out
    for s in TWO_LEVEL:
        e = data["strategies"][s]
        assert e["m7_states"] == e["m7_cycles_est_states"] == N_BENCH
        # the traced paths are the steps QEMU counted: the same median instruction count
        assert e["m7_cycles_est_path_instructions_median"] == pytest.approx(e["m7_instructions_per_step"], abs=0.5)
        assert e["m7_instructions_per_step"] > 50 and e["ratio_to_conventional"] > 0
        # the cycle estimate (traced path through the M7 pipeline model) and the lower bound beside it
        assert e["m7_cycles_est_min"] <= e["m7_cycles_est_median"] <= e["m7_cycles_est_max"]
        # (every traced state's estimate at least its model bound, else strategy_cycles raises)
        assert 0 < e["m7_cycles_bound_min"] <= e["m7_cycles_bound"] <= e["m7_cycles_est_median"]
        assert e["m7_cycles_est_over_bound"] == e["m7_cycles_est_median"] / e["m7_cycles_bound"]
        # the overlap bound (every unit overlapping): lower than the model's for these float32 steps
        assert 0 < e["m7_cycles_bound_overlap"] < e["m7_cycles_bound"]
        assert e["m7_cycles_est_over_bound_overlap"] == e["m7_cycles_est_median"] / e["m7_cycles_bound_overlap"]
        # a step cannot take fewer cycles than half its instructions (two-wide issue)
        assert e["m7_cycles_est_median"] >= e["m7_instructions_per_step"] / 2
    # every simplified strategy holds the zero vector on most samples: cheaper median
    assert data["strategies"]["s3"]["m7_instructions_per_step"] < data["strategies"]["conventional"]["m7_instructions_per_step"]


@pytest.mark.slow
def test_emulated_bench_fixed_point_beside_float32(tmp_path, capsys):
    """A fixed-point config: its own column (self-test bit-exact on the emulated M7, else the bench
    fails) and the float32 variant's beside it; its cycle estimate and its bound in integer instructions."""
    require_tool("qemu-system-arm", "qemu-system-arm")
    require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi")
    js = tmp_path / "benchfx.json"
    assert main(["bench", str(SPMSM), "--number-format", "fixed", "--strategies", "conventional,s3",
                 "--emulated", "--json", str(js), "--repeats", "1"]) == 0
    data = json.loads(js.read_text())
    for s in ("conventional", "s3"):
        e = data["strategies"][s]
        assert e["m7_instructions_per_step"] == e["m7_instructions_per_step_fixed"] > 50
        assert e["m7_instructions_per_step_float32"] > 50
        by = e["m7_by_number_format"]
        assert by["fixed"]["states_checked"] == 1000 + N_BENCH  # every one bit-exact, or bench raises
        assert by["float32"]["states_checked"] == 1000 + N_BENCH
        # the bound in integer instructions (each operation its helper's shortest sequence): every traced
        # state's estimate at least its bound (else strategy_cycles raises), the estimate within a few
        # times it (the float-style count, one instruction an operation, left it 7-9 times below)
        assert 0 < e["m7_cycles_bound_min"] <= e["m7_cycles_bound"] <= e["m7_cycles_est_median"]
        assert e["m7_cycles_est_over_bound"] < 4
        assert 0 < e["m7_cycles_bound_overlap"] <= e["m7_cycles_bound"]
    out = capsys.readouterr().out
    assert "fixed" in out and "float32" in out


def test_every_number_format_replays_the_same_states():
    """The bench and HIL states are the float32 controller's trajectory whatever the model's number
    format, so a fixed-point image is measured on the very states a float32 one is."""
    import numpy as np

    from codegen.config import load_config
    from codegen.stages.fwdata import trajectory_states

    m = load_config(SPMSM, {"controller.strategy": "s1"})
    a = trajectory_states(m, N_BENCH)
    b = trajectory_states(m.with_controller(number_format="fixed"), N_BENCH)
    assert len(a) == len(b) == N_BENCH and np.isfinite(a["ia_a"]).all()
    for name in a.dtype.names:  # field by field, bit for bit (the records' padding is not data)
        assert a[name].tobytes() == b[name].tobytes(), name


@pytest.mark.slow
def test_emulated_bench_without_fpu(tmp_path, capsys):
    """``--board qemu-m3``: every strategy in fixed point and in float32 compiled for soft float on the
    Cortex-M3 (no FPU), both bit-exact on the board (else bench fails); fixed point the faster there by
    the ratio float32/fixed, the Cortex-M7's fixed/float32 beside it, each image named by its C hash."""
    require_tool("qemu-system-arm", "qemu-system-arm")
    require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi")
    js = tmp_path / "benchm3.json"
    assert main(["bench", str(SPMSM), "--emulated", "--board", "qemu-m3", "--json", str(js), "--repeats", "1",
                 "-q"]) == 0
    data = json.loads(js.read_text())
    assert data["board"] == "qemu-m3" and "-mfloat-abi=soft" in data["m3_cpu_flags"]
    assert data["c_hash_definition"].startswith("sha256 of the lines")
    assert data["m3_states"] == N_BENCH and data["m3_selftest_states"] == 1000
    for s in TWO_LEVEL:
        e = data["strategies"][s]
        for fmt in ("fixed", "float32"):
            st = e["m3_by_number_format"][fmt]
            assert st["states_checked"] == 1000 + N_BENCH and st["bench_states"] == N_BENCH
            assert 0 < st["min"] <= st["median"] <= st["max"] and st["min"] <= st["mean"] <= st["max"]
            sf = st["selftest"]
            assert sf["states"] == 1000 and sf["min"] <= sf["median"] <= sf["max"]
            assert len(st["c_hash"]) == 64 and st["c_hash_target"] == "host"
            m7 = e["m7_by_number_format"][fmt]
            assert m7["median"] > 50 and len(m7["c_hash"]) == 64 and m7["c_hash_target"] == "stm32h743"
            assert m7["c_hash"] != st["c_hash"]  # another target profile: other C (placement attributes)
        assert e["m3_instructions_per_step_fixed"] == e["m3_by_number_format"]["fixed"]["median"]
        # without an FPU, fixed point is the faster, by every measure
        assert e["m3_float32_over_fixed"] > 1 and e["m3_float32_over_fixed_mean"] > 1
        assert e["m3_float32_over_fixed_max"] > 1 and e["m3_selftest_float32_over_fixed"] > 1
        assert e["m3_instructions_per_step_fixed"] < e["m3_instructions_per_step_float32"]
        assert e["m3_float32_over_fixed"] == (e["m3_instructions_per_step_float32"]
                                              / e["m3_instructions_per_step_fixed"])
        # with one, float32 is
        assert e["m7_fixed_over_float32"] == e["m7_instructions_per_step_fixed"] / e["m7_instructions_per_step_float32"]
        assert e["m7_fixed_over_float32"] > 1
    assert data["strategies"]["conventional"]["ratio_to_conventional"] == 1.0
    out = capsys.readouterr().out
    assert "M3 fixed instr/step" in out and "float32/fixed" in out and "M7 fx/fl" in out


def test_bench_board_needs_emulated(capsys):
    assert main(["bench", str(SPMSM), "--board", "qemu-m3", "-q"]) == 2
    assert "--board = qemu-m3: the board of --emulated" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.parametrize("config", ["mpcc_spmsm", "mpcc_tlevel"])
def test_emulated_bench_long_horizon(tmp_path, capsys, config):
    """The long-horizon family (docs/mpcc.md): host ns/step, M7 instructions and estimated cycles over the
    bench states with the bound of codegen/mpcc/opcount.py (every traced state's estimate at least its
    bound, else strategy_cycles raises); its fixed-point column says why it is not measured (the family
    runs in float32 only) instead of failing."""
    require_tool("qemu-system-arm", "qemu-system-arm")
    require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi")
    from conftest import EXAMPLES

    js = tmp_path / "bench-mpcc.json"
    assert main(["bench", str(EXAMPLES / f"{config}.toml"), "--emulated", "--set", "controller.horizon=2",
                 "--json", str(js), "--repeats", "1", "-q"]) == 0
    data = json.loads(js.read_text())
    e = data["strategies"]["mpcc"]
    assert e["host_ns_per_step"] > 0 and e["m7_states"] == e["m7_cycles_est_states"] == N_BENCH
    assert 0 < e["m7_instructions_min"] <= e["m7_instructions_per_step"] <= e["m7_instructions_max"]
    assert e["m7_cycles_est_min"] <= e["m7_cycles_est_median"] <= e["m7_cycles_est_max"]
    # the bound varies with the nodes the decoder enters: a range, below the estimate
    assert 0 < e["m7_cycles_bound_min"] < e["m7_cycles_bound_max"]
    assert e["m7_cycles_bound"] <= e["m7_cycles_est_median"] and e["m7_cycles_est_over_bound"] >= 1
    assert e["m7_instructions_per_step_fixed"] is None
    assert "float32 only" in e["m7_by_number_format"]["fixed"]["error"]
    assert "n/a" in capsys.readouterr().out
