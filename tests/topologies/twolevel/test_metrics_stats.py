"""Ripple statistics (std, peak-to-peak, 1st-99th percentile span) and THD with the nominal fundamental
on synthetic signals (codegen.metrics)."""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from codegen.metrics import nominal_fundamental_hz, percentile_span, ripple_stats, thd


def test_ripple_stats_on_a_synthetic_signal() -> None:
    # error = 0.5 + a uniform ramp over [-1, 1] (10 001 points): every statistic known in closed form
    e = np.linspace(-1.0, 1.0, 10001)
    ref = np.full_like(e, 2.0)
    st = ripple_stats(ref + 0.5 + e, ref)
    assert st["mean"] == pytest.approx(0.5, abs=1e-12)
    assert st["pp"] == pytest.approx(2.0, abs=1e-12)
    assert st["std"] == pytest.approx(math.sqrt(np.mean(e * e)), rel=1e-12)  # ~ 1/sqrt(3)
    assert st["std"] == pytest.approx(1.0 / math.sqrt(3.0), rel=1e-3)
    assert st["rmse"] == pytest.approx(math.sqrt(0.25 + np.mean(e * e)), rel=1e-12)
    # percentiles of a uniform ramp: p1 = -0.98, p99 = 0.98 (linear interpolation, exact on this grid)
    assert percentile_span(ref + 0.5 + e, ref) == pytest.approx(1.96, abs=1e-12)


def test_p1_p99_span_ignores_rare_spikes() -> None:
    rng = np.random.default_rng(1)
    x = 0.1 * np.sin(np.linspace(0, 200 * math.pi, 20000))
    spikes = rng.choice(x.size, 40, replace=False)  # 0.2 % of the samples
    x[spikes] += 5.0
    assert ripple_stats(x, 0.0)["pp"] > 5.0
    assert percentile_span(x, 0.0) == pytest.approx(0.2, rel=0.01)  # the sine's own span, spikes ignored


def test_ripple_stats_mask_and_empty() -> None:
    x = np.array([0.0, 1.0, 3.0, 10.0])
    m = np.array([True, True, True, False])
    assert ripple_stats(x, 0.0, m)["pp"] == 3.0
    assert percentile_span(x, 0.0, m) == pytest.approx(np.percentile([0, 1, 3], 99) - np.percentile([0, 1, 3], 1))
    assert all(math.isnan(v) for v in ripple_stats(x, 0.0, np.zeros(4, bool)).values())
    assert math.isnan(percentile_span(x, 0.0, np.zeros(4, bool)))


def _ia(f1: float, dt: float, n: int, h5: float) -> np.ndarray:
    t = np.arange(n) * dt
    return 10.0 * np.sin(2 * math.pi * f1 * t) + 10.0 * h5 * np.sin(2 * math.pi * 5 * f1 * t + 0.3)


def test_thd_with_the_nominal_fundamental() -> None:
    dt, pole_pairs = 50e-6, 4
    speed_ref_rpm = 750.0  # f1 = 4 * 750 / 60 = 50 Hz
    n = 8000  # 0.4 s = 20 periods
    w_ref = speed_ref_rpm * 2 * math.pi / 60
    trace = SimpleNamespace(dt_s=dt, n=n, speed_ref_rad_s=np.full(n, -w_ref), ia_a=_ia(50.0, dt, n, 0.05))
    f1 = nominal_fundamental_hz(trace, pole_pairs, 0.0, 0.4)
    assert f1 == pytest.approx(50.0, rel=1e-12)  # |n*|: the sign of the reference does not matter
    value, info = thd(trace.ia_a, dt, 0.0, 0.4, f1)
    assert value == pytest.approx(5.0, rel=1e-9)
    assert info["n_periods"] == 20 and info["harmonics"] == [2, 200] and info["f1_hz"] == pytest.approx(50.0)


def test_nominal_and_measured_fundamentals_differ_when_the_speed_is_off() -> None:
    # the current runs at 51 Hz (speed 2 % above its 50 Hz reference): analysed at the nominal 50 Hz
    # the harmonic bins miss the 51 Hz harmonics and the THD reads about 1.9 %, not the waveform's 5 %
    dt, n = 50e-6, 8000
    ia = _ia(51.0, dt, n, 0.05)
    at_measured, _ = thd(ia, dt, 0.0, 0.4, 51.0)
    at_nominal, _ = thd(ia, dt, 0.0, 0.4, 50.0)
    assert at_measured == pytest.approx(5.0, rel=1e-2)
    assert at_nominal < 0.5 * at_measured
