"""T-type metrics (codegen/topologies/ttype/metrics.py) on synthetic waveforms with known answers."""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from codegen.topologies.ttype.metrics import (
    leg_level_changes,
    line_jump_histogram,
    resample_piecewise,
    three_level_metrics,
    uab_thd,
)
from codegen.topologies.ttype.plots import plot_three_level
from codegen.topologies.ttype.sim import run_closed_loop

from .conftest import seed000_model

TS = 50e-6
UDC = 220.0


def test_jump_histogram_of_a_known_sequence():
    h = UDC / 2
    # u_ab levels in units of Udc/2 (with a little V_o offset on the nonzero ones):
    #   start 0 (OOO) -> 1 -> 1 -> 2 -> 0 -> -2 -> -1 -> 1 -> 1(empty seg: skipped) -> -1
    # jumps: 1, 0, 1, 2, 2, 1, 2, 0, 2
    levels = np.array([1, 1, 2, 0, -2, -1, 1, 3, 1, -1], dtype=float)
    seg = np.full(levels.shape, 10e-6)
    seg[7] = 0.0  # a zero-length segment (its u_ab must not count)
    uab = levels * h + np.where(levels != 0, 0.3, 0.0)
    r = line_jump_histogram(uab, seg, UDC, uab_before=0.0)
    assert r["counts"] == [2, 3, 4, 0, 0]
    assert r["n_boundaries"] == 9 and r["n_jumps"] == 7 and r["max_udc2"] == 2
    # a full +-Udc reversal is 4 units; no initial state: first boundary not counted
    r = line_jump_histogram(np.array([2.0, -2.0, 2.0]) * h, np.full(3, 1e-6), UDC, uab_before=None)
    assert r["counts"] == [0, 0, 0, 0, 2] and r["max_udc2"] == 4
    # (n, 7) shaped input reads row by row
    r2 = line_jump_histogram(uab.reshape(2, 5), seg.reshape(2, 5), UDC)
    assert r2["counts"] == [2, 3, 4, 0, 0]


def test_leg_level_changes_known():
    ooo, poo, onn, pnn, nnn = 13, 22, 9, 18, 0
    st = np.array([[poo, poo, ooo, ooo, ooo, ooo, ooo],   # OOO->POO (1), POO->OOO (1)
                   [pnn, onn, onn, onn, onn, onn, nnn],   # OOO->PNN (1+1+1=3), PNN->ONN (1), ONN->NNN (1)
                   [poo, ooo, ooo, ooo, ooo, ooo, ooo]])  # NNN->POO (2+1+1=4), the OOO: empty
    seg = np.full(st.shape, TS / 7)
    seg[2, 1:] = 0.0
    np.testing.assert_array_equal(leg_level_changes(st, seg), [2, 5, 4])


def test_resample_piecewise_is_exact_box_average():
    v = np.array([1.0, 5.0, 0.0, -2.0])
    d = np.array([1.5e-6, 0.0, 2.25e-6, 0.25e-6])
    x = resample_piecewise(v, d, 1e-6, 4)
    np.testing.assert_allclose(x, [1.0, 0.5, 0.0, -0.5], atol=1e-12)


def _fake_trace(uab, seg, dt=TS):
    n = uab.shape[0]
    return SimpleNamespace(dt_s=dt, n=n, uab_v=uab, seg_s=seg)


def _random_split(n, rng):
    w = rng.dirichlet(np.ones(7), n)
    w[rng.random((n, 7)) < 0.3] = 0.0
    w[:, 3] += 1e-3
    return w / w.sum(axis=1, keepdims=True) * TS


def test_thd_uab_of_a_square_wave_is_analytic():
    """Square wave, f1 = 250 Hz (80 control periods), cut into random 7-segment
    periods: odd harmonics 4U/(pi h), THD = 100*sqrt(sum_{odd h=3..199} 1/h^2)
    up to 50 kHz (h <= 200); the 1 us grid holds whole half-periods, so the
    resampling is exact and only DFT aliasing (< 1e-3 relative) remains."""
    rng = np.random.default_rng(0)
    n = 80 * 10  # 10 fundamental periods
    seg = _random_split(n, rng)
    k = np.arange(n)
    uab = np.where((k % 80) < 40, UDC, -UDC)[:, None] * np.ones((1, 7))
    value, info = uab_thd(_fake_trace(uab, seg), 0.0, n * TS, 250.0)
    expected = 100.0 * math.sqrt(sum(1.0 / h**2 for h in range(3, 200, 2)))
    assert value == pytest.approx(expected, rel=1e-3)
    assert info["n_periods"] == 10 and info["harmonics"] == [2, 200]
    assert info["cells_per_period"] == 4000 and info["grid_s"] == pytest.approx(1e-6)
    assert info["i1_peak"] == pytest.approx(4 * UDC / math.pi, rel=1e-3)


def test_thd_uab_of_a_held_sine_is_analytic():
    """A sine held constant over each control period (zero-order hold of its
    mid-period samples, as PWM-averaged inverters produce): the images at
    h = kN +- 1 (N = 80 periods per fundamental) have relative amplitude
    |sinc(h/N)/sinc(1/N)|; up to 50 kHz (h <= 200): k = 1, 2."""
    n = 80 * 8
    k = np.arange(n)
    u = 300.0 * np.sin(2 * np.pi * 250.0 * (k + 0.5) * TS)
    seg = _random_split(n, np.random.default_rng(1))
    uab = u[:, None] * np.ones((1, 7))
    value, _ = uab_thd(_fake_trace(uab, seg), 0.0, n * TS, 250.0)
    N = 80
    rel = [np.sinc(h / N) / np.sinc(1 / N) for kk in (1, 2) for h in (kk * N - 1, kk * N + 1)]
    expected = 100.0 * math.sqrt(sum(r * r for r in rel))
    # the 1 us box-average grid costs O(grid^2): +0.1 % here, -> 0 as the grid shrinks
    assert value == pytest.approx(expected, rel=2e-3)
    fine, _ = uab_thd(_fake_trace(uab, seg), 0.0, n * TS, 250.0, grid_s=0.25e-6)
    assert fine == pytest.approx(expected, rel=1e-4)
    assert 1.0 < value < 3.0
    # the piecewise-constant switching of the same average (three-level-like
    # pulses within each period) has a much larger THD than its average
    pulses = np.zeros((n, 7))
    seg2 = np.tile(np.array([1, 1, 1, 1, 1, 1, 1.0]) * TS / 7, (n, 1))
    lvl = np.sign(u) * UDC / 2
    duty = np.clip(np.abs(u) / (UDC / 2), 0, 1)
    seg2[:, 3] = duty * TS          # "on" segment carries the average
    seg2[:, [0, 1, 2, 4, 5, 6]] = ((1 - duty) * TS / 6)[:, None]
    pulses[:, 3] = lvl
    pwm, _ = uab_thd(_fake_trace(pulses, seg2), 0.0, n * TS, 250.0)
    assert pwm > 5 * value


def test_metrics_and_plots_of_a_run(stub, tmp_path):
    ffi, lib, mode = stub
    results = {}
    for m_ in (27, 63):
        mode(m_)
        model = seed000_model(3000.0, 0.3)
        tr = run_closed_loop(ffi, lib, model)
        r = three_level_metrics(tr, model, window_s=0.1)
        results[m_] = r
        for key in ("T_rip_RMSE_nm", "psi_rip_RMSE_wb", "THD_ia_percent", "THD_uab_percent", "Vo_std_v", "Vo_pp_v", "f_ave_hz", "Cal_ave"):
            assert math.isfinite(r[key]) and r[key] >= 0, key
        assert r["Cal_ave"] == m_
        assert r["f_ave_hz"] == pytest.approx(tr.leg_changes.sum() / (3 * tr.duration_s))
        assert sum(r["jump_hist_udc2"]) == np.count_nonzero(tr.seg_s > 0)
        assert r["max_line_jump_udc2"] in (1, 2, 3, 4)
        assert r["window"]["THD_uab_percent"]["harmonics"][1] == 200  # 200 * 250 Hz = 50 kHz
        # window statistics: the psi reference is the controller's
        psi_ref = tr.psi_ref_wb.astype(float)
        assert r["psi_rip_RMSE_wb"] == pytest.approx(float(np.sqrt(np.mean((tr.psi_wb - psi_ref) ** 2))))
        paths = plot_three_level(tr, model, f"stub{m_}_3000rpm", "3000 r/min", tmp_path, r)
        assert sorted(p.name for p in paths) == sorted(
            f"stub{m_}_3000rpm_{w}.png" for w in ("speed", "torque", "flux", "locus", "currents", "spectrum", "vo",
                                                 "uab"))
        for p in paths:
            data = p.read_bytes()
            assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 5_000
    # the stub's virtual vectors reduce the torque ripple (sanity, not a product claim)
    assert results[63]["T_rip_RMSE_nm"] < results[27]["T_rip_RMSE_nm"]
    # stats window
    r = three_level_metrics(tr, model, stats_window=(0.2, 0.3))
    assert r["window"]["T_rip_RMSE_nm"]["n_samples"] == 2000
