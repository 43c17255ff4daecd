"""Metrics (codegen/metrics.py) on synthetic signals with known answers."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from codegen.metrics import (
    amplitude_spectrum,
    cal_ave,
    f_ave_hz,
    leg_commutations,
    ripple_stats,
    rmse,
    steady_windows,
    thd,
    window_mask,
)
from codegen.topologies.twolevel.metrics import switching_f_ave_hz, two_level_metrics

DT = 50e-6


def _sines(f1, amps, n, phases=None, dc=0.0):
    t = np.arange(n) * DT
    phases = phases or {h: 0.3 * h for h in amps}
    return dc + sum(a * np.sin(2 * np.pi * h * f1 * t + phases[h]) for h, a in amps.items())


def test_thd_of_known_harmonics_is_analytic():
    # 50 Hz fundamental, 5th and 7th harmonics, 0.2 s at 20 kHz (400 samples/period)
    amps = {1: 10.0, 5: 0.8, 7: 0.35}
    x = _sines(50.0, amps, 4000, dc=0.7)
    value, info = thd(x, DT, 0.0, 0.2, 50.0)
    expected = 100.0 * math.hypot(0.8, 0.35) / 10.0
    assert value == pytest.approx(expected, rel=1e-6)
    assert info["n_periods"] == 10 and info["n_samples"] == 4000
    assert info["harmonics"] == [2, 200]  # 200 * 50 Hz = 10 kHz
    assert info["i1_peak"] == pytest.approx(10.0, rel=1e-9)
    assert (info["t0_s"], info["t1_s"]) == (0.0, 0.2)


def test_thd_window_uses_whole_periods_only():
    # 33.333 Hz (600 samples/period): 0.19 s holds 6 whole periods (3600 of 3800 samples)
    f1 = 100.0 / 3.0
    x = _sines(f1, {1: 5.0, 11: 0.25, 13: 0.1}, 6000)
    value, info = thd(x, DT, 0.1, 0.29, f1)
    assert info["n_periods"] == 6 and info["n_samples"] == 3600
    assert (info["t0_s"], info["t1_s"]) == (0.1, 0.28)
    assert value == pytest.approx(100.0 * math.hypot(0.25, 0.1) / 5.0, rel=1e-6)
    assert info["harmonics"] == [2, 300]
    # interharmonics (2.5*f1 falls between harmonic bins) do not count ...
    y = x + _sines(f1, {2.5: 1.0}, 6000)
    assert thd(y, DT, 0.1, 0.29, f1)[0] == pytest.approx(value, rel=1e-6)
    # ... nor do harmonics above f_max_hz (250*f1 = 8.33 kHz > 8 kHz)
    z = x + _sines(f1, {250: 1.0}, 6000)
    v8, info8 = thd(z, DT, 0.1, 0.29, f1, f_max_hz=8e3)
    assert info8["harmonics"] == [2, 240] and v8 == pytest.approx(value, rel=1e-6)
    assert thd(z, DT, 0.1, 0.29, f1)[0] == pytest.approx(100.0 * math.sqrt(0.25**2 + 0.1**2 + 1.0) / 5.0, rel=1e-6)


def test_thd_needs_one_period():
    with pytest.raises(ValueError, match="less than one fundamental period"):
        thd(np.zeros(100), DT, 0.0, 0.005, 50.0)


def test_spectrum_amplitudes():
    x = _sines(50.0, {1: 3.0, 3: 1.0}, 4000, dc=2.0)
    f, a, info = amplitude_spectrum(x, DT, 0.0, 0.2, 50.0)
    assert f[10] == pytest.approx(50.0) and a[10] == pytest.approx(3.0)
    assert a[30] == pytest.approx(1.0) and a[0] == pytest.approx(2.0)


def test_f_ave_counts_leg_changes():
    # 000 -> 100 -> 110 -> 111 -> 000 -> 011: 1 + 1 + 1 + 3 + 2 = 8 leg changes
    sw = [4, 6, 7, 0, 3]
    assert leg_commutations(sw) == 8
    assert leg_commutations(sw, sw_initial=4) == 7
    assert f_ave_hz(sw, 2.0) == pytest.approx(8 / (3 * 2.0))
    # one leg toggling every sample for 1 s at 20 kHz: 20 000 leg changes over 3 legs
    tog = np.tile([4, 0], 10_000)
    assert f_ave_hz(tog, 1.0) == pytest.approx(20_000 / 3)
    # seed eq. (9): N_switching (6 switches, each leg change = 2 switch changes) / (6 t)
    n_switching = 2 * leg_commutations(tog)
    assert f_ave_hz(tog, 1.0) == pytest.approx(n_switching / (6 * 1.0))


def test_f_ave_leaves_out_open_inverter_periods():
    """Gates off (the inverter open after a guard trip): the changes into and out of the open periods
    and their time are not part of f_ave; without open periods it is eq. (9) exactly."""
    sw = [4, 6, 0, 0, 6, 7]
    is_open = [0, 0, 1, 1, 0, 0]
    # 000 -> 100 (1), 100 -> 110 (1), into the open periods and out of them: not counted, 110 -> 111 (1)
    f, n_open = switching_f_ave_hz(sw, is_open, 1.0)
    assert (f, n_open) == (3 / (3 * 4.0), 2)
    # the period before the window was open: the change into the first period is not counted
    assert switching_f_ave_hz([4, 6], [0, 0], 1.0, sw_initial=0, open_initial=1) == (1 / (3 * 2.0), 0)
    closed = [0] * len(sw)
    assert switching_f_ave_hz(sw, closed, DT) == (f_ave_hz(sw, len(sw) * DT), 0)
    assert math.isnan(switching_f_ave_hz([0, 0], [1, 1], DT)[0])


def test_two_level_metrics_f_ave_excludes_gates_off_periods(stub, spmsm_model):
    from codegen.topologies.twolevel.sim import run_closed_loop

    ffi, lib = stub
    lib.stub_twolevel_set_echo(0)
    tr = run_closed_loop(ffi, lib, spmsm_model)
    r = two_level_metrics(tr, spmsm_model)
    assert not tr.inverter_open.any()
    assert r["f_ave_hz"] == f_ave_hz(tr.applied_sw, len(tr.applied_sw) * tr.dt_s)
    # the same run with periods 1000..2999 open, the safe state 000 held there (as after a trip)
    is_open = np.zeros(len(tr.applied_sw), dtype=np.uint16)
    is_open[1000:3000] = 1
    sw = np.where(is_open == 1, 0, tr.applied_sw).astype(tr.applied_sw.dtype)
    faulted = dataclasses.replace(tr, inverter_open=is_open, applied_sw=sw)
    rf = two_level_metrics(faulted, spmsm_model)
    assert switching_f_ave_hz(faulted.applied_sw, faulted.inverter_open, tr.dt_s)[1] == 2000
    changes = leg_commutations(sw[:1000]) + leg_commutations(sw[3000:], sw_initial=int(sw[2999])) \
        - leg_commutations(sw[3000:3001], sw_initial=int(sw[2999]))  # the change out of the open periods
    assert rf["f_ave_hz"] == pytest.approx(changes / (3 * (len(sw) - 2000) * tr.dt_s), rel=1e-12)
    # eq. (9) over the whole run would count the changes into and out of the safe state 000
    assert leg_commutations(sw) > changes


def test_cal_ave_rmse_ripple():
    assert cal_ave([7, 0, 4, 3]) == pytest.approx(3.5)
    x = np.array([1.0, 3.0, 1.0, 3.0])
    assert rmse(x, 2.0) == pytest.approx(1.0)
    assert rmse(x, np.array([1.0, 3.0, 0.0, 0.0]), np.array([True, True, False, False])) == 0.0
    st = ripple_stats(x, 1.0)
    assert st == pytest.approx({"rmse": math.sqrt(2.0), "std": 1.0, "pp": 2.0, "mean": 1.0})


def test_steady_windows_spmsm(spmsm_model):
    assert steady_windows(spmsm_model) == [(0.8, 1.0), (1.8, 2.0), (2.8, 3.0), (3.8, 4.0)]
    assert steady_windows(spmsm_model, 0.5) == [(0.5, 1.0), (1.5, 2.0), (2.5, 3.0), (3.5, 4.0)]
    # a step that does not change the value does not split; a short segment gives all of it
    sc = dataclasses.replace(spmsm_model.scenario, duration_s=1.1,
                             load_nm=((0.0, 1.0), (0.5, 1.0), (1.0, 2.0)), speed_ref_rpm=((0.0, 100.0),))
    m = spmsm_model.replace(scenario=sc)
    assert steady_windows(m) == [(0.8, 1.0), (1.0, 1.1)]
    mask = window_mask(80_000, DT, steady_windows(spmsm_model))
    assert mask.sum() == 16_000 and mask[76_000] and not mask[75_999] and mask[-1]


def test_two_level_metrics_keys_and_windows(stub, spmsm_model):
    from codegen.topologies.twolevel.sim import run_closed_loop

    ffi, lib = stub
    lib.stub_twolevel_set_echo(0)
    tr = run_closed_loop(ffi, lib, spmsm_model)
    r = two_level_metrics(tr, spmsm_model)
    for k in ("T_rip_RMSE_nm", "psi_rip_RMSE_wb", "T_rip_std_nm", "T_rip_pp_nm", "psi_rip_std_wb", "psi_rip_pp_wb",
              "THD_ia_percent", "f_ave_hz", "Cal_ave", "window", "steady"):
        assert k in r
    assert r["T_rip_RMSE_nm"] == pytest.approx(rmse(tr.te_nm, tr.torque_ref_nm))
    assert r["psi_rip_RMSE_wb"] == pytest.approx(rmse(tr.psi_wb, 0.3))
    assert r["f_ave_hz"] == pytest.approx(leg_commutations(tr.sw) / 12.0)
    assert r["Cal_ave"] == pytest.approx(np.mean(tr.n_eval))
    assert r["window"]["T_rip_RMSE_nm"]["n_samples"] == 80_000
    assert r["window"]["ripple_std_pp"]["windows_s"] == [[0.8, 1.0], [1.8, 2.0], [2.8, 3.0], [3.8, 4.0]]
    w = r["window"]["THD_ia_percent"]
    assert w["t0_s"] == 3.8 and w["n_periods"] >= 5 and w["harmonics"][0] == 2
    assert 0.0 < r["THD_ia_percent"] < 20.0
    assert len(r["steady"]) == 4
    # a caller-given window applies to all ripple statistics
    r2 = two_level_metrics(tr, spmsm_model, stats_window=(3.8, 4.0))
    assert r2["T_rip_RMSE_nm"] == pytest.approx(r["steady"][3]["T_rip_RMSE_nm"])
    assert r2["window"]["Cal_ave"]["n_samples"] == 4000
