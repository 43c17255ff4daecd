"""Metrics of closed-loop runs shared by every topology, with the names of seed 001.

Definitions (docs/simulation.md "Metrics"; seed 001 = Li Yaohua
et al., Control Theory & Applications 40(10), 2023, eq. (7)-(10)):

* ``T_rip_RMSE = sqrt(sum_i (Te_i - T*_i)^2 / n)``            seed eq. (7)
* ``psi_rip_RMSE = sqrt(sum_i (|psi_s|_i - psi*)^2 / n)``      seed eq. (8)
* ``f_ave = N_switching / (6 t)``                              seed eq. (9)
  N_switching counts the on/off changes of the six switches (upper and lower
  of each leg); every change of a leg's state turns one switch on and its
  complement off, i.e. 2 switch changes, so f_ave = (leg state changes) /
  (3 legs * t): leg commutations per second per leg, as the spec words it.
* ``Cal_ave = Cal / n``                                        seed eq. (10)
* Ripple statistics of the error e = x - ref besides the RMSE: ``std`` (about
  its mean), ``pp`` (peak to peak, max - min) and ``p1_p99`` (the span between
  the 1st and the 99th percentile of e, linear interpolation between order
  statistics: a peak-to-peak that ignores the 2 % most extreme samples, as a
  bench's scope statistics do).
* THD of i_a: FFT over an integer number of fundamental periods inside a
  steady window, ``THD = sqrt(sum_{h>=2} I_h^2) / I_1`` over the harmonics up
  to 10 kHz (or fs/2, whichever is lower).  Two fundamentals: the measured one
  (mean electrical speed of the plant over the window, ``THD_ia_percent``) and
  the nominal one (the speed reference over the window, p * |n*| / 60,
  ``THD_ia_nominal_percent``, what a bench analyser locked to the commanded
  frequency reports).  Both state their window and harmonic range.
* THD of i_a over all bins (``THD_ia_all_bins_percent``, :func:`thd_all_bins`):
  the same FFT window and measured fundamental, ``sqrt(sum_{k != k1} A_k^2) /
  A_1`` over every bin k = 1 .. f_lim / df (df = 1 / window length; k1 the
  fundamental's bin): integer harmonics, interharmonics and subharmonics up to
  min(10 kHz, fs/2).  ``THD_ia_interharmonic_percent`` is the part of it off the
  integer harmonics.  A run whose decisions repeat with a period of several
  fundamental periods puts lines between the harmonics, which the integer
  THD does not see.
* Drive figures (:func:`drive_figures`, reported with the tracking verdict):
  peak phase current over the run and over the steady windows against the
  rated current ``T_rated / (1.5 p psi_f)``, the smallest |psi_s| over the
  steady windows against its mean there, the locked-cycle flag (the decision
  sequence over the THD window repeats exactly, :func:`cycle_period`) and
  ``anomalies``: one line per misbehaviour (peak current above
  :data:`ANOMALY_PEAK_PER_RATED` x rated, or |psi_s| below
  :data:`ANOMALY_FLUX_SHARE` x its mean, in a steady window).

Te and |psi_s| are the plant's (float64) values at the sample instants; T*
is the torque reference given to the controller; psi* = controller.psi_ref_wb, or the MTPA flux
of each sample's T* (controller.psi_ref = "mtpa").
Everything is vectorised numpy; nothing loops over samples in Python.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from codegen.model import Model

__all__ = [
    "steady_windows",
    "window_slice",
    "window_mask",
    "rmse",
    "ripple_stats",
    "percentile_span",
    "amplitude_spectrum",
    "thd",
    "leg_commutations",
    "f_ave_hz",
    "cal_ave",
    "thd_window",
    "fundamental_hz",
    "ripple_summary",
    "sample_time",
    "RunWindows",
    "run_windows",
    "thd_ia",
    "thd_ia_nominal",
    "nominal_fundamental_hz",
    "steady_ripples",
    "SPEED_BAND_FRACTION",
    "SPEED_BAND_FLOOR",
    "TORQUE_REF_SPREAD",
    "SteadyCheck",
    "check_steady",
    "not_computed",
    "WINDOW_GROUPS",
    "metric_flags",
    "fault_counts",
    "thd_all_bins",
    "thd_ia_all_bins",
    "cycle_period",
    "rated_current_a",
    "drive_figures",
    "ANOMALY_PEAK_PER_RATED",
    "ANOMALY_FLUX_SHARE",
    "LOCK_MIN_REPEATS",
    "THD_F_MAX_HZ",
]

# Tolerance, in samples / periods, for mapping times onto the sample grid.
GRID_TOL = 1e-6


def sample_time(k: int, dt_s: float) -> float:
    """Time of sample k for reports (k*dt_s without float noise: 3.8, not 3.8000000000000003)."""
    return round(k * dt_s, 12)


# ---------------------------------------------------------------------------
# windows
# ---------------------------------------------------------------------------
def _change_times(steps: tuple[tuple[float, float], ...], duration_s: float) -> set[float]:
    """Times in (0, duration) where a piecewise-constant reference changes value."""
    out: set[float] = set()
    prev = 0.0  # value before the first step (simulate.scenario_arrays uses 0 as well)
    for t_s, value in sorted(steps, key=lambda s: s[0]):
        if float(value) != prev and 0.0 < float(t_s) < duration_s:
            out.add(float(t_s))
        prev = float(value)
    return out


def reference_changes(model: Model) -> list[float]:
    """Start-up (t = 0) and every instant where the speed reference or the load changes, sorted."""
    sc = model.scenario
    cuts = _change_times(sc.speed_ref_rpm, sc.duration_s) | _change_times(sc.load_nm, sc.duration_s)
    return [0.0, *sorted(cuts)]


def steady_windows(model: Model, window_s: float = 0.2) -> list[tuple[float, float]]:
    """The last ``window_s`` of each constant-reference segment, as (t0, t1) in s.

    Segments are split at every instant where the speed reference or the load
    changes (docs/simulation.md "Metrics": default window is the last 0.2 s
    of each constant-reference segment).  A segment shorter than ``window_s``
    gives its whole length.  For the seed-001 SPMSM scenario (speed step at
    2 s, load steps at 1 s and 3 s, 4 s total):
    [(0.8, 1.0), (1.8, 2.0), (2.8, 3.0), (3.8, 4.0)].
    """
    if window_s <= 0:
        raise ValueError("window_s must be > 0")
    bounds = [*reference_changes(model), float(model.scenario.duration_s)]
    return [(max(a, b - window_s), b) for a, b in zip(bounds[:-1], bounds[1:])]


def window_slice(dt_s: float, t0: float, t1: float, n: int | None = None) -> slice:
    """Samples k with t0 <= k*dt_s < t1 (grid-tolerant), clipped to n samples."""
    k0 = max(0, math.ceil(t0 / dt_s - GRID_TOL))
    k1 = max(k0, math.ceil(t1 / dt_s - GRID_TOL))
    if n is not None:
        k0, k1 = min(k0, n), min(k1, n)
    return slice(k0, k1)


def window_mask(n: int, dt_s: float, windows: list[tuple[float, float]] | tuple[float, float]) -> np.ndarray:
    """Boolean mask of the samples inside one window (t0, t1) or a list of windows."""
    if isinstance(windows, tuple) and len(windows) == 2 and not isinstance(windows[0], tuple):
        windows = [windows]  # type: ignore[list-item]
    mask = np.zeros(n, dtype=bool)
    for t0, t1 in windows:  # type: ignore[misc]
        mask[window_slice(dt_s, t0, t1, n)] = True
    return mask


# ---------------------------------------------------------------------------
# is a window steady?  (docs/simulation.md "Steady windows")
# ---------------------------------------------------------------------------
#: speed band: |n - n*| <= SPEED_BAND_FRACTION * max(|n*|, SPEED_BAND_FLOOR * rated speed) over the window
SPEED_BAND_FRACTION = 0.05
SPEED_BAND_FLOOR = 0.1
#: torque-reference spread: max(T*) - min(T*) <= TORQUE_REF_SPREAD * rated torque over the window
TORQUE_REF_SPREAD = 0.1


@dataclass(frozen=True)
class SteadyCheck:
    """The steady-state check of one window [t0, t1) (:func:`check_steady`)."""

    t0_s: float
    t1_s: float
    reasons: tuple[str, ...]  # empty: steady
    speed_dev_max_rpm: float
    speed_band_rpm: float
    torque_ref_spread_nm: float
    torque_ref_band_nm: float

    @property
    def steady(self) -> bool:
        return not self.reasons

    @property
    def reason(self) -> str:
        """The reasons joined into one line ("" when steady)."""
        return "; ".join(self.reasons)

    def as_json(self) -> dict[str, Any]:
        """``steady``, the measured criteria and, when not steady, ``not_steady_reason``."""
        out: dict[str, Any] = {
            "steady": self.steady,
            "steady_check": {"speed_dev_max_rpm": self.speed_dev_max_rpm, "speed_band_rpm": self.speed_band_rpm,
                             "torque_ref_spread_nm": self.torque_ref_spread_nm,
                             "torque_ref_band_nm": self.torque_ref_band_nm},
        }
        if not self.steady:
            out["not_steady_reason"] = self.reason
        return out


def check_steady(trace: Any, model: Model, t0: float, t1: float) -> SteadyCheck:
    """Is [t0, t1) a steady window?  Steady when all three hold (docs/simulation.md "Steady windows"):

    1. no reference change in [t0, t1): the window neither starts at t = 0
       (start-up) nor at or after a step of the speed reference or the load
       without a settling time before it (a segment not longer than
       ``scenario.window_s`` gives a window that starts at its step);
    2. the speed settled: max |n - n*| <= SPEED_BAND_FRACTION * max(|n*|,
       SPEED_BAND_FLOOR * rated speed) (n* the window's largest |reference|);
    3. the torque reference settled: max(T*) - min(T*) <= TORQUE_REF_SPREAD *
       rated torque.
    """
    sl = window_slice(trace.dt_s, t0, t1, trace.n)
    reasons: list[str] = []
    for c in reference_changes(model):
        if t0 - GRID_TOL * trace.dt_s <= c < t1:
            reasons.append("contains the start-up (t = 0)" if c == 0.0
                           else f"contains the reference step at t = {c:g} s")
    if sl.stop <= sl.start:
        return SteadyCheck(t0, t1, (*reasons, "no samples"), math.nan, math.nan, math.nan, math.nan)
    n_ref = np.asarray(trace.speed_ref_rpm[sl], dtype=np.float64)
    dev = float(np.max(np.abs(np.asarray(trace.speed_rpm[sl], dtype=np.float64) - n_ref)))
    band = SPEED_BAND_FRACTION * max(float(np.max(np.abs(n_ref))), SPEED_BAND_FLOOR * model.motor.rated_speed_rpm)
    if not dev <= band:
        reasons.append(f"speed off its reference by up to {dev:.4g} r/min (band {band:.4g} r/min)")
    spread = float(np.ptp(np.asarray(trace.torque_ref_nm[sl], dtype=np.float64)))
    t_band = TORQUE_REF_SPREAD * model.motor.rated_torque_nm
    if not spread <= t_band:
        reasons.append(f"torque reference spread {spread:.4g} N*m (limit {t_band:.4g} N*m)")
    return SteadyCheck(t0, t1, tuple(reasons), dev, band, spread, t_band)


def not_computed(reason: str, **info: Any) -> tuple[float, dict[str, Any]]:
    """A metric that cannot be computed: NaN (JSON null) and its window entry with the reason."""
    return math.nan, {**info, "description": f"not computed: {reason}", "not_computed_reason": reason}


# ---------------------------------------------------------------------------
# ripple: seed eq. (7)-(8)
# ---------------------------------------------------------------------------
def _error(x: Any, ref: Any, mask: Any) -> np.ndarray:
    e = np.asarray(x, dtype=np.float64) - np.asarray(ref, dtype=np.float64)
    e = np.broadcast_to(e, np.shape(x))
    if mask is not None:
        e = e[np.asarray(mask)]
    return e


def rmse(x: Any, ref: Any, mask: Any = None) -> float:
    """sqrt(mean((x - ref)^2)) over the masked samples (seed 001 eq. (7)-(8)).

    ``ref`` is an array like ``x`` or a scalar (psi* is constant); ``mask`` a
    boolean array or index (None: all samples).  NaN for an empty selection.
    """
    e = _error(x, ref, mask)
    return float(np.sqrt(np.mean(e * e))) if e.size else math.nan


def ripple_stats(x: Any, ref: Any, mask: Any = None) -> dict[str, float]:
    """Ripple of x about ref over the masked samples.

    Returns ``rmse`` (seed eq. (7)-(8)), ``std`` (standard deviation of the
    error x - ref, i.e. the ripple about its mean offset), ``pp``
    (peak-to-peak of the error) and ``mean`` (mean error), all NaN if empty;
    the percentile span is :func:`percentile_span`.
    """
    e = _error(x, ref, mask)
    if not e.size:
        return {"rmse": math.nan, "std": math.nan, "pp": math.nan, "mean": math.nan}
    return {
        "rmse": float(np.sqrt(np.mean(e * e))),
        "std": float(np.std(e)),
        "pp": float(np.ptp(e)),
        "mean": float(np.mean(e)),
    }


def percentile_span(x: Any, ref: Any, mask: Any = None, lo: float = 1.0, hi: float = 99.0) -> float:
    """The ``hi``-th minus the ``lo``-th percentile of the error x - ref over the masked samples (numpy's
    linear interpolation between order statistics): the 1st-99th percentile span by default, a
    peak-to-peak that ignores the most extreme 2 % of the samples.  NaN if empty."""
    e = _error(x, ref, mask)
    if not e.size:
        return math.nan
    p_lo, p_hi = np.percentile(e, [lo, hi])
    return float(p_hi - p_lo)


# ---------------------------------------------------------------------------
# spectrum and THD
# ---------------------------------------------------------------------------
def amplitude_spectrum(
    signal: Any, dt_s: float, t0: float, t1: float, f1_hz: float
) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """Single-sided amplitude spectrum over an integer number of fundamental periods.

    Takes the longest whole number of periods 1/f1_hz that fits in the samples
    of [t0, t1) (starting at t0), M = round(n_periods/(f1*dt)) samples, so the
    fundamental falls on FFT bin n_periods and harmonic h on bin
    h*n_periods (exactly when 1/(f1*dt) is an integer; otherwise the FFT's
    own fundamental n_periods/(M*dt) is used and reported as ``f1_used_hz``).
    Returns (frequencies Hz, peak amplitudes, info).  Raises ValueError when
    not even one period fits.
    """
    x = np.asarray(signal, dtype=np.float64)
    if not (f1_hz > 0 and math.isfinite(f1_hz)):
        raise ValueError(f"fundamental frequency must be positive, got {f1_hz!r}")
    sl = window_slice(dt_s, t0, t1, x.shape[0])
    avail = sl.stop - sl.start
    if not f1_hz < 0.5 / dt_s:
        raise ValueError(f"fundamental {f1_hz:.4g} Hz is not below the Nyquist frequency fs/2 = "
                         f"{0.5 / dt_s:.4g} Hz of the {dt_s:g} s sampling")
    per_period = 1.0 / (f1_hz * dt_s)  # samples per fundamental period
    n_per = int(math.floor(avail / per_period + GRID_TOL))
    if n_per < 1:
        raise ValueError(
            f"window [{t0:.6g}, {t1:.6g}) s holds {avail} samples, less than one fundamental "
            f"period ({per_period:.1f} samples at {f1_hz:.4g} Hz)"
        )
    m = min(avail, int(round(n_per * per_period)))
    seg = x[sl.start : sl.start + m]
    spec = np.fft.rfft(seg)
    amp = np.abs(spec) * (2.0 / m)
    amp[0] *= 0.5  # DC
    if m % 2 == 0:
        amp[-1] *= 0.5  # Nyquist bin
    freqs = np.fft.rfftfreq(m, dt_s)
    info = {
        "t0_s": sample_time(sl.start, dt_s),
        "t1_s": sample_time(sl.start + m, dt_s),
        "n_samples": m,
        "n_periods": n_per,
        "f1_hz": float(f1_hz),
        "f1_used_hz": n_per / (m * dt_s),
        "samples_per_period": per_period,
    }
    return freqs, amp, info


def thd(
    signal: Any, dt_s: float, t0: float, t1: float, f1_hz: float, f_max_hz: float = 10e3
) -> tuple[float, dict[str, Any]]:
    """Total harmonic distortion in percent: 100*sqrt(sum_{h>=2} I_h^2)/I_1.

    FFT over an integer number of fundamental periods inside [t0, t1)
    (:func:`amplitude_spectrum`), harmonics h = 2 .. h_max with h_max*f1 <=
    min(f_max_hz, fs/2) (docs/simulation.md "Metrics").  Only integer
    harmonics enter the sum.  The info dict gives the window actually used,
    the number of periods, f1, the harmonic range and the fundamental's
    amplitude.
    """
    freqs, amp, info = amplitude_spectrum(signal, dt_s, t0, t1, f1_hz)
    n_per = info["n_periods"]
    nbins = amp.shape[0]
    f_lim = min(f_max_hz, 0.5 / dt_s)
    h_max = int(math.floor(f_lim / info["f1_used_hz"] + GRID_TOL))
    h_max = min(h_max, (nbins - 1) // n_per)
    if h_max < 2:
        raise ValueError(f"no harmonic h >= 2 of {info['f1_used_hz']:.4g} Hz lies below "
                         f"min(f_max, fs/2) = {f_lim:.4g} Hz")
    i1 = float(amp[n_per])
    harm = amp[n_per * np.arange(2, h_max + 1)] if h_max >= 2 else np.zeros(0)
    value = 100.0 * float(np.sqrt(np.sum(harm * harm))) / i1 if i1 > 0 else math.nan
    info.update(
        {
            "harmonics": [2, h_max],
            "f_max_hz": h_max * info["f1_used_hz"],
            "f_limit_hz": f_lim,
            "i1_peak": i1,
        }
    )
    return value, info


def thd_all_bins(
    signal: Any, dt_s: float, t0: float, t1: float, f1_hz: float, f_max_hz: float = 10e3
) -> tuple[float, dict[str, Any]]:
    """Distortion over every FFT bin in percent: 100*sqrt(sum_{k != k1} A_k^2)/A_1, k = 1 .. k_max.

    The window and fundamental of :func:`thd` (:func:`amplitude_spectrum`: an
    integer number n of fundamental periods, so the fundamental is bin k1 = n
    and the bins are df = f1/n apart); k_max*df <= min(f_max_hz, fs/2).  Every
    bin but DC and the fundamental enters: integer harmonics (k a multiple of
    n), interharmonics and subharmonics.  The info dict gives the window, the
    bin range and spacing and ``interharmonic_percent``: the same sum over the
    bins that are not integer harmonics (so all^2 = harmonics^2 + inter^2).
    """
    freqs, amp, info = amplitude_spectrum(signal, dt_s, t0, t1, f1_hz)
    n_per = info["n_periods"]
    df = info["f1_used_hz"] / n_per
    f_lim = min(f_max_hz, 0.5 / dt_s)
    k_max = min(int(math.floor(f_lim / df + GRID_TOL)), amp.shape[0] - 1)
    if k_max <= n_per:
        raise ValueError(f"no bin above the fundamental {info['f1_used_hz']:.4g} Hz lies below "
                         f"min(f_max, fs/2) = {f_lim:.4g} Hz")
    k = np.arange(1, k_max + 1)
    a2 = amp[1:k_max + 1] ** 2
    i1 = float(amp[n_per])
    off = k != n_per
    inter = (k % n_per) != 0
    value = 100.0 * float(np.sqrt(np.sum(a2[off]))) / i1 if i1 > 0 else math.nan
    info.update({
        "bins": [1, k_max],
        "bin_hz": df,
        "f_max_hz": k_max * df,
        "f_limit_hz": f_lim,
        "i1_peak": i1,
        "interharmonic_percent": 100.0 * float(np.sqrt(np.sum(a2[inter]))) / i1 if i1 > 0 else math.nan,
        "definition": "100 * sqrt(sum of A_k^2 over every bin 1..k_max but the fundamental's) / A_1: integer "
                      "harmonics, interharmonics and subharmonics",
    })
    return value, info


# ---------------------------------------------------------------------------
# switching frequency and computation: seed eq. (9)-(10)
# ---------------------------------------------------------------------------
def leg_commutations(sw: Any, sw_initial: int = 0) -> int:
    """Total number of leg state changes in a sequence of states Sa*4+Sb*2+Sc.

    The state before the first entry is ``sw_initial`` (000 at start-up).
    """
    s = np.concatenate(([int(sw_initial)], np.asarray(sw, dtype=np.int64).ravel()))
    x = (s[1:] ^ s[:-1]) & 7
    return int(np.sum((x & 1) + ((x >> 1) & 1) + ((x >> 2) & 1)))


def f_ave_hz(sw: Any, duration_s: float, sw_initial: int = 0) -> float:
    """Average switching frequency, seed 001 eq. (9): N_switching / (6 t).

    N_switching counts on/off changes of all six switches; one leg change is
    two switch changes (upper and lower), hence f_ave = leg changes /
    (3 * duration_s): leg commutations per second per leg.
    """
    if not duration_s > 0.0:
        return math.nan  # an empty window has no frequency
    return leg_commutations(sw, sw_initial) / (3.0 * duration_s)


def cal_ave(n_eval: Any) -> float:
    """Average number of evaluated candidates per sample, seed 001 eq. (10): Cal / n."""
    a = np.asarray(n_eval, dtype=np.float64)
    return float(np.mean(a)) if a.size else math.nan


# ---------------------------------------------------------------------------
# pieces of every topology's metric set
# ---------------------------------------------------------------------------
def thd_window(trace: Any, model: Model, window_s: float = 0.2) -> tuple[float, float] | None:
    """The last steady window whose speed reference is nonzero (None if there is none)."""
    for t0, t1 in reversed(steady_windows(model, window_s)):
        sl = window_slice(trace.dt_s, t0, t1, trace.n)
        if sl.stop > sl.start and np.all(trace.speed_ref_rad_s[sl] != 0.0):
            return (t0, t1)
    return None


def fundamental_hz(trace: Any, model: Model, t0: float, t1: float) -> float:
    """Fundamental of the phase currents: mean |omega_e| over the window / (2*pi)."""
    sl = window_slice(trace.dt_s, t0, t1, trace.n)
    w_e = model.motor.pole_pairs * float(np.mean(np.abs(trace.omega_m_rad_s[sl])))
    return w_e / (2.0 * math.pi)


def ripple_summary(trace: Any, psi_ref: Any, run_mask: Any, rip_mask: Any) -> dict[str, float]:
    """Torque and flux ripple entries shared by the two- and three-level metrics.

    RMSE of Te - T* and |psi_s| - psi* over ``run_mask``; std, pp and the
    1st-99th percentile span over ``rip_mask`` (see :func:`ripple_stats`).
    Keys in report order.
    """
    t_stats = ripple_stats(trace.te_nm, trace.torque_ref_nm, rip_mask)
    p_stats = ripple_stats(trace.psi_wb, psi_ref, rip_mask)
    return {
        "T_rip_RMSE_nm": rmse(trace.te_nm, trace.torque_ref_nm, run_mask),
        "psi_rip_RMSE_wb": rmse(trace.psi_wb, psi_ref, run_mask),
        "T_rip_std_nm": t_stats["std"],
        "T_rip_pp_nm": t_stats["pp"],
        "psi_rip_std_wb": p_stats["std"],
        "psi_rip_pp_wb": p_stats["pp"],
        "T_rip_p1_p99_nm": percentile_span(trace.te_nm, trace.torque_ref_nm, rip_mask),
        "psi_rip_p1_p99_wb": percentile_span(trace.psi_wb, psi_ref, rip_mask),
    }


@dataclass(frozen=True)
class RunWindows:
    """Where one run's metrics are taken (see :func:`run_windows`)."""

    windows: list[tuple[float, float]]  # the steady windows
    sl: slice  # the whole run, or stats_window
    run_mask: np.ndarray | None  # None: the whole run
    run_desc: dict[str, Any]
    rip_mask: np.ndarray  # the steady windows, or stats_window
    rip_desc: dict[str, Any]


def run_windows(trace: Any, model: Model, stats_window: tuple[float, float] | None, window_s: float,
                whole_run: str, stats_desc: str = "window given by the caller") -> RunWindows:
    """The windows of a topology's metric set, described for the result's ``window`` entry.

    RMSE-type metrics over the whole run (described as ``whole_run``) or
    over ``stats_window`` (described as ``stats_desc``); std/pp ripples over the steady windows (last
    ``window_s`` of each constant-reference segment) or ``stats_window``.
    """
    dt, n = trace.dt_s, trace.n
    windows = steady_windows(model, window_s)
    if stats_window is None:
        rip_mask = window_mask(n, dt, windows)
        return RunWindows(windows, slice(0, n), None,
                          {"t0_s": 0.0, "t1_s": sample_time(n, dt), "n_samples": n, "description": whole_run},
                          rip_mask, {
                              "windows_s": [[a, b] for a, b in windows],
                              "n_samples": int(np.count_nonzero(rip_mask)),
                              "description": f"steady windows: last {window_s:g} s of each constant-reference segment",
                              **_all_steady(trace, model, windows),
                          })
    sl = window_slice(dt, stats_window[0], stats_window[1], n)
    run_mask = np.zeros(n, dtype=bool)
    run_mask[sl] = True
    run_desc = {"t0_s": sample_time(sl.start, dt), "t1_s": sample_time(sl.stop, dt),
                "n_samples": sl.stop - sl.start, "description": stats_desc}
    return RunWindows(windows, sl, run_mask, run_desc, run_mask,
                      {**run_desc, **_all_steady(trace, model, [stats_window])})


def _all_steady(trace: Any, model: Model, windows: list[tuple[float, float]]) -> dict[str, Any]:
    """``steady`` (every window steady) and, when not, ``not_steady_reason`` naming each failing window."""
    bad = [c for c in (check_steady(trace, model, a, b) for a, b in windows) if not c.steady]
    if not bad:
        return {"steady": True}
    return {"steady": False,
            "not_steady_reason": " | ".join(f"[{c.t0_s:g}, {c.t1_s:g}) s: {c.reason}" for c in bad)}


def _thd_ia_over(trace: Any, model: Model, tw: tuple[float, float] | None, f_max_hz: float,
                 f1_hz: Callable[[float, float], float], describe: Callable[[dict[str, Any], float], str],
                 fundamental: str, measure: Callable[..., tuple[float, dict[str, Any]]] = thd,
                 ) -> tuple[float, dict[str, Any]]:
    """THD of i_a over the THD window ``tw`` with the fundamental ``f1_hz(t0, t1)`` (NaN and the reason
    when there is no window or no THD), described by ``describe(info, f1)``; ``measure``: :func:`thd`
    (integer harmonics) or :func:`thd_all_bins`."""
    if tw is None:
        return not_computed("no steady window with a nonzero speed reference")
    try:
        f1 = f1_hz(*tw)
        value, info = measure(trace.ia_a, trace.dt_s, tw[0], tw[1], f1, f_max_hz)
    except ValueError as exc:
        return not_computed(str(exc), window_s=list(tw))
    info["description"] = describe(info, f1)
    info["fundamental"] = fundamental
    info.update(check_steady(trace, model, *tw).as_json())
    return value, info


def thd_ia(trace: Any, model: Model, tw: tuple[float, float] | None, f_max_hz: float,
           where: str) -> tuple[float, dict[str, Any]]:
    """THD of i_a over the THD window ``tw`` with the measured fundamental (:func:`fundamental_hz`);
    NaN and the reason when there is none.  ``where`` starts the description (e.g. "i_a over")."""
    w = tw or (0.0, 0.0)  # the description is made only for a window
    return _thd_ia_over(
        trace, model, tw, f_max_hz, lambda t0, t1: fundamental_hz(trace, model, t0, t1),
        lambda info, f1: (f"{where} [{w[0]:g}, {w[1]:g}) s, {info['n_periods']} fundamental periods, "
                          f"harmonics {info['harmonics'][0]}..{info['harmonics'][1]}"),
        "measured: mean electrical speed of the plant over the window")


def thd_ia_all_bins(trace: Any, model: Model, tw: tuple[float, float] | None,
                    f_max_hz: float) -> tuple[float, dict[str, Any]]:
    """THD of i_a over every bin (:func:`thd_all_bins`) of the THD window ``tw``, the measured fundamental
    (the window and fundamental of :func:`thd_ia`); NaN and the reason when there is none."""
    return _thd_ia_over(
        trace, model, tw, f_max_hz, lambda t0, t1: fundamental_hz(trace, model, t0, t1),
        lambda info, f1: (f"i_a over [{info['t0_s']:g}, {info['t1_s']:g}) s, {info['n_periods']} fundamental "
                          f"periods, every bin {info['bins'][0]}..{info['bins'][1]} of {info['bin_hz']:.6g} Hz "
                          f"but the fundamental's (<= {info['f_max_hz']:.6g} Hz)"),
        "measured: mean electrical speed of the plant over the window", thd_all_bins)


def nominal_fundamental_hz(trace: Any, pole_pairs: int, t0: float, t1: float) -> float:
    """Nominal fundamental of the phase currents: p * mean |speed reference| over [t0, t1) / (2*pi)."""
    sl = window_slice(trace.dt_s, t0, t1, trace.n)
    w_ref = float(np.mean(np.abs(np.asarray(trace.speed_ref_rad_s[sl], dtype=np.float64))))
    return pole_pairs * w_ref / (2.0 * math.pi)


def thd_ia_nominal(trace: Any, model: Model, tw: tuple[float, float] | None,
                   f_max_hz: float) -> tuple[float, dict[str, Any]]:
    """THD of i_a over ``tw`` with the nominal fundamental (:func:`nominal_fundamental_hz`: from the
    speed reference, not the measured speed), harmonics 2 .. min(f_max_hz, fs/2)/f1; NaN and the
    reason when there is no window."""
    return _thd_ia_over(
        trace, model, tw, f_max_hz, lambda t0, t1: nominal_fundamental_hz(trace, model.motor.pole_pairs, t0, t1),
        lambda info, f1: (f"i_a over [{info['t0_s']:g}, {info['t1_s']:g}) s, {info['n_periods']} periods of the "
                          f"nominal fundamental {f1:.6g} Hz (p * |n*| / 60), harmonics "
                          f"{info['harmonics'][0]}..{info['harmonics'][1]} (<= {info['f_max_hz']:.6g} Hz)"),
        "nominal: pole pairs * speed reference")


def steady_ripples(trace: Any, model: Model, windows: list[tuple[float, float]],
                   psi_ref: Any) -> list[dict[str, Any]]:
    """Torque and flux ripple statistics of each steady window (the result's ``steady`` list), each
    with its steady-state check (:func:`check_steady`)."""
    rows = []
    for a, b in windows:
        m = window_mask(trace.n, trace.dt_s, (a, b))
        ts = ripple_stats(trace.te_nm, trace.torque_ref_nm, m)
        ps = ripple_stats(trace.psi_wb, psi_ref, m)
        rows.append({"t0_s": a, "t1_s": b, "T_rip_RMSE_nm": ts["rmse"], "T_rip_std_nm": ts["std"],
                     "T_rip_pp_nm": ts["pp"], "psi_rip_RMSE_wb": ps["rmse"], "psi_rip_std_wb": ps["std"],
                     "psi_rip_pp_wb": ps["pp"], "T_rip_p1_p99_nm": percentile_span(trace.te_nm, trace.torque_ref_nm, m),
                     "psi_rip_p1_p99_wb": percentile_span(trace.psi_wb, psi_ref, m), **check_steady(trace, model, a, b).as_json()})
    return rows


# ---------------------------------------------------------------------------
# flags and faults of one run's metric set
# ---------------------------------------------------------------------------
#: window entries that cover several metrics (the std/pp ripples over the steady windows)
WINDOW_GROUPS: dict[str, tuple[str, ...]] = {
    "ripple_std_pp": ("T_rip_std_nm", "T_rip_pp_nm", "psi_rip_std_wb", "psi_rip_pp_wb",
                      "T_rip_p1_p99_nm", "psi_rip_p1_p99_wb"),
    "ripple_std_pp_Vo": ("T_rip_std_nm", "T_rip_pp_nm", "psi_rip_std_wb", "psi_rip_pp_wb",
                         "T_rip_p1_p99_nm", "psi_rip_p1_p99_wb", "Vo_std_v", "Vo_pp_v", "Vo_mean_v"),
}


def metric_flags(result: dict[str, Any]) -> dict[str, dict[str, str]]:
    """``not_steady`` and ``not_computed``: metric key -> reason, from the ``window`` entries.

    A metric is not steady when its window entry says ``"steady": false``
    (:func:`check_steady`), not computed when its value is NaN/None; the
    reason of a value that is NaN without one is "no samples".
    """
    not_steady: dict[str, str] = {}
    not_computed_: dict[str, str] = {}
    for entry, info in result.get("window", {}).items():
        for key in WINDOW_GROUPS.get(entry, (entry,)):
            if info.get("steady") is False:
                not_steady[key] = info.get("not_steady_reason", "")
            if "not_computed_reason" in info:
                not_computed_[key] = info["not_computed_reason"]
    for key, value in result.items():
        if isinstance(value, float) and not math.isfinite(value) and key not in not_computed_:
            not_computed_[key] = "no samples in its window"
    for key in not_computed_:
        not_steady.pop(key, None)
    return {"not_steady": not_steady, "not_computed": not_computed_}


def fault_counts(fault: Any, fault_bits: tuple[tuple[str, int, str], ...]) -> dict[str, Any]:
    """``faults`` (periods whose guard tripped: the safe decision) and ``fault_counts`` (periods with
    each fault bit set, by the name of the topology's ``records.FAULT_BITS``)."""
    f = np.asarray(fault, dtype=np.int64)
    return {"faults": int(np.count_nonzero(f)),
            "fault_counts": {name: int(np.count_nonzero(f & bit)) for name, bit, _ in fault_bits}}


# ---------------------------------------------------------------------------
# drive figures: peak current, flux collapse, locked cycle, all-bin THD
# ---------------------------------------------------------------------------
#: a steady window whose peak phase current exceeds this many times the rated current is a current spike
ANOMALY_PEAK_PER_RATED = 2.0
#: a steady window whose smallest |psi_s| is below this share of its mean |psi_s| is a flux collapse
ANOMALY_FLUX_SHARE = 0.6
#: a decision sequence is a locked cycle when it repeats exactly at least this many times over the window
LOCK_MIN_REPEATS = 2
#: upper frequency of the all-bin THD (the topologies' THD default)
THD_F_MAX_HZ = 10e3


def rated_current_a(model: Model) -> float:
    """The rated current the peak current is compared with: T_rated / (1.5 p psi_f) (peak phase current
    of rated torque with i_d = 0, as the operating-point checks estimate it: codegen.operating)."""
    m = model.motor
    return m.rated_torque_nm / (1.5 * m.pole_pairs * m.psi_f_wb)


def cycle_period(decisions: Any, min_repeats: int = LOCK_MIN_REPEATS) -> int | None:
    """The smallest L such that ``decisions[k + L] == decisions[k]`` for every k of the sequence, with
    L <= len / ``min_repeats`` (the cycle seen at least that many times); None when there is none."""
    v = np.asarray(decisions).ravel()
    n = v.shape[0]
    top = n // max(min_repeats, 1)
    if n < 2 or top < 1:
        return None
    for lag in (np.flatnonzero(v[1:top + 1] == v[0]) + 1).tolist():
        if np.array_equal(v[lag:], v[:-lag]):
            return int(lag)
    return None


def drive_figures(trace: Any, model: Model) -> dict[str, Any]:
    """Figures of one run every topology shares, beyond the seed's metrics (docs/tuning.md "Figures"):

    * ``i_peak_a``: the largest |i_a|, |i_b|, |i_c| of the run; ``i_peak_steady_a`` the same over the
      steady windows (the last ``scenario.window_s`` of each constant-reference segment that passes
      :func:`check_steady`), ``i_peak_per_rated`` that over :func:`rated_current_a`;
    * ``psi_min_wb``: the smallest |psi_s| over the steady windows, ``psi_min_share`` that over the mean
      |psi_s| there;
    * ``THD_ia_all_bins_percent`` (and ``THD_ia_interharmonic_percent``): :func:`thd_ia_all_bins` over
      the THD window (:func:`thd_window`);
    * ``locked_cycle``: the controller's decisions (the trace's ``vector``) over the THD window (else the
      last steady window) repeat exactly (:func:`cycle_period`), the period in ``drive_figures``;
    * ``anomalies``: one line per misbehaviour in a steady window: peak current above
      :data:`ANOMALY_PEAK_PER_RATED` x rated (a current spike), smallest |psi_s| below
      :data:`ANOMALY_FLUX_SHARE` x its mean (the flux locus collapses);
    * ``drive_figures``: how each was taken (windows, rated current, THD bins, cycle period).
    """
    window_s = model.scenario.window_s
    dt, n = trace.dt_s, trace.n
    steady = [w for w in steady_windows(model, window_s) if check_steady(trace, model, *w).steady]
    i_abs = np.max(np.abs(np.stack([np.asarray(trace.ia_a, np.float64), np.asarray(trace.ib_a, np.float64),
                                    np.asarray(trace.ic_a, np.float64)])), axis=0) if n else np.zeros(0)
    psi = np.asarray(trace.psi_wb, np.float64)
    mask = window_mask(n, dt, steady) if steady else np.zeros(n, dtype=bool)
    i_rated = rated_current_a(model)
    i_peak = float(np.max(i_abs)) if n else math.nan
    i_steady = float(np.max(i_abs[mask])) if mask.any() else math.nan
    psi_min = float(np.min(psi[mask])) if mask.any() else math.nan
    psi_mean = float(np.mean(psi[mask])) if mask.any() else math.nan
    share = psi_min / psi_mean if psi_mean > 0 else math.nan
    anomalies: list[str] = []
    if i_steady > ANOMALY_PEAK_PER_RATED * i_rated:
        anomalies.append(f"current spike: peak phase current {i_steady:.4g} A in a steady window, "
                         f"{i_steady / i_rated:.2f} x the rated {i_rated:.4g} A (limit {ANOMALY_PEAK_PER_RATED:g} x)")
    if share < ANOMALY_FLUX_SHARE:
        anomalies.append(f"flux collapse: |psi_s| down to {psi_min:.4g} Wb in a steady window, "
                         f"{share:.2f} x its mean {psi_mean:.4g} Wb (limit {ANOMALY_FLUX_SHARE:g} x)")
    tw = thd_window(trace, model, window_s)
    thd_all, thd_info = thd_ia_all_bins(trace, model, tw, THD_F_MAX_HZ)
    lock_w = tw or (steady[-1] if steady else None)
    period = None
    lock_info: dict[str, Any] = {"definition": f"the decisions (vector) over the window repeat exactly, at least "
                                               f"{LOCK_MIN_REPEATS} times"}
    if lock_w is not None:
        sl = window_slice(dt, lock_w[0], lock_w[1], n)
        period = cycle_period(np.asarray(trace.vector)[sl])
        lock_info.update({"window_s": [lock_w[0], lock_w[1]], "n_samples": sl.stop - sl.start,
                          "period_samples": period, "period_s": None if period is None else period * dt})
        if period is not None and tw is not None and thd_info.get("f1_used_hz"):
            lock_info["period_fundamentals"] = period * dt * float(thd_info["f1_used_hz"])
    else:
        lock_info["not_computed_reason"] = "no steady window"
    return {
        "i_peak_a": i_peak,
        "i_peak_steady_a": i_steady,
        "i_peak_per_rated": i_steady / i_rated,
        "psi_min_wb": psi_min,
        "psi_min_share": share,
        "THD_ia_all_bins_percent": thd_all,
        "THD_ia_interharmonic_percent": thd_info.get("interharmonic_percent", math.nan),
        "locked_cycle": period is not None,
        "anomalies": anomalies,
        "drive_figures": {
            "i_rated_a": i_rated,
            "i_rated_definition": "T_rated / (1.5 p psi_f)",
            "steady_windows_s": [[a, b] for a, b in steady],
            "i_peak": "largest |i_a|, |i_b|, |i_c|: i_peak_a over the run, i_peak_steady_a over the steady windows",
            "psi_min": "smallest |psi_s| over the steady windows; psi_min_share = that / mean |psi_s| there",
            "THD_ia_all_bins_percent": thd_info,
            "locked_cycle": lock_info,
            "anomaly_limits": {"i_peak_per_rated": ANOMALY_PEAK_PER_RATED, "psi_min_share": ANOMALY_FLUX_SHARE},
        },
    }


# ---------------------------------------------------------------------------
# the simulator's own verdict on a run
# ---------------------------------------------------------------------------
#: the speed at the end of a constant-reference segment must be within this share of the rated speed plus
#: this share of its reference (docs/simulation.md "Tracking verdict")
SPEED_BAND_SHARE = 0.02
#: the speed PI's output may sit at its limit for at most this share of a steady window
SATURATED_SHARE_MAX = 0.5
#: the samples at the end of a window the final speed is averaged over (the speed ripple is averaged out)
END_SAMPLES = 20


def tracking_verdict(trace: Any, model: Model) -> dict[str, Any]:
    """Whether the drive did what the scenario asked, with the reasons when it did not:

    * speed: at the end of each steady window (the last ``scenario.window_s`` of each constant-reference
      segment) the mean of the last :data:`END_SAMPLES` speeds is within
      ``SPEED_BAND_SHARE * (rated speed + |reference|)`` of the reference (mechanical speed mode only:
      an imposed speed follows its reference by construction);
    * torque: the speed PI's output T* is at +-``speed_loop.limit_nm`` for at most
      :data:`SATURATED_SHARE_MAX` of each steady window (mechanical speed mode only);
    * guard: no period tripped the step's input guard (current, voltage, speed limits).

    Returns ``{"tracking": "ok" | "failed", "tracking_reasons": [one line each]}`` and the run's
    :func:`drive_figures` (peak current, flux minimum, all-bin THD, locked cycle, anomalies), which every
    topology's ``simulate`` reports with the verdict; the anomalies do not change the verdict.
    """
    reasons: list[str] = []
    if model.scenario.speed_mode == "mechanical":
        rated = model.motor.rated_speed_rpm * 2.0 * math.pi / 60.0
        limit = model.speed_loop.limit_nm
        for t0, t1 in steady_windows(model, model.scenario.window_s):
            sl = window_slice(trace.dt_s, t0, t1, trace.n)
            if sl.stop <= sl.start:
                continue
            end = slice(max(sl.start, sl.stop - END_SAMPLES), sl.stop)
            ref = float(np.mean(trace.speed_ref_rad_s[end]))
            got = float(np.mean(trace.omega_m_rad_s[end]))
            band = SPEED_BAND_SHARE * (rated + abs(ref))
            if abs(got - ref) > band:
                reasons.append(f"speed {_rpm(got):.1f} r/min at {t1:g} s against a reference of {_rpm(ref):.1f} "
                               f"r/min (band +-{_rpm(band):.1f} r/min)")
            saturated = float(np.mean(np.abs(trace.torque_ref_nm[sl]) >= limit * (1.0 - 1e-9)))
            if saturated > SATURATED_SHARE_MAX:
                reasons.append(f"torque reference at the speed loop's limit +-{limit:g} N*m for "
                               f"{100.0 * saturated:.0f} % of [{t0:g}, {t1:g}) s")
    tripped = int(np.count_nonzero(np.asarray(trace.fault)))
    if tripped:
        reasons.append(f"the input guard tripped in {tripped} of {trace.n} periods (a current, voltage or speed "
                       "limit was reached)")
    return {"tracking": "failed" if reasons else "ok", "tracking_reasons": reasons, **drive_figures(trace, model)}


def _rpm(w_rad_s: float) -> float:
    return w_rad_s * 60.0 / (2.0 * math.pi)


def tracking_lines(failed: dict[str, list[str]]) -> list[str]:
    """The table's verdict line(s): ``tracking: ok`` or one ``tracking FAILED`` line per failed run."""
    if not failed:
        return ["tracking: ok (speed within its band at the end of every segment, torque not held at the "
                "limit, no guard trip)"]
    return [f"tracking FAILED: {label}: {'; '.join(reasons)}" for label, reasons in failed.items()]
