"""Metrics of closed-loop three-level (T-type) runs.

Definitions (docs/simulation.md "Metrics", mpdtc-three-level.md):

* ``T_rip_RMSE_nm = sqrt(mean((Te - T*)^2))`` (plant Te at the sample instants,
  T* the reference given to the controller).
* ``psi_rip_RMSE_wb = sqrt(mean((|psi_s| - psi*)^2))`` with psi* the
  CONTROLLER's flux reference of the same period (``trace.psi_ref_wb``; the
  three-level psi* follows T* by MTPA, so it is not a constant).
* ``THD_ia_percent``: :func:`codegen.metrics.thd` of i_a (harmonics up to 10 kHz or
  fs/2) over the last steady window with nonzero speed, fundamental measured
  (mean electrical speed); ``THD_ia_nominal_percent``: the same with the
  nominal fundamental (pole pairs * speed reference).
* ``T_rip_p1_p99_nm``, ``psi_rip_p1_p99_wb``: 1st-99th percentile span of the
  ripple error, over the windows of the std/pp ripples.
* ``Vo_std_v``, ``Vo_pp_v``, ``Vo_mean_v``: neutral-point voltage V_o = (u_c1 -
  u_c2)/2 of the plant at the sample instants, over the steady windows.
* ``THD_uab_percent``: THD of the switched line voltage u_ab at sub-period
  resolution.  The piecewise-constant waveform (one value per applied
  segment, zero-length segments skipped) is resampled onto a uniform grid of
  about ``uab_grid_s`` = 1 us by exact box averaging (the mean of the
  waveform over each grid cell, from its cumulative integral), with the grid
  step adjusted so that one fundamental period holds an integer number P of
  cells; the FFT covers the largest integer number of fundamental periods in
  the THD window; harmonics h = 2 .. h_max with h_max*f1 <= ``uab_f_max_hz``
  = 50 kHz (well below the grid's Nyquist frequency of ~500 kHz).
* Line-voltage jumps: every boundary between consecutive applied segments
  (including period boundaries and the boundary from the state before the
  counted range; the inverter starts in OOO, u_ab = 0), |du_ab| / (Udc/2)
  rounded to the nearest integer and clipped to 0..4.  ``jump_hist_udc2[m]``
  counts the boundaries with m units; index 0 counts boundaries where the
  line-voltage level did not change (only V_o drift).
  ``max_line_jump_udc2`` = the largest m >= 1 that occurred (0: none).
* ``f_ave_hz``: one-level leg changes per second per leg: sum over the run
  of the per-period leg-level changes (|S_x(i) - S_x(i-1)| summed over legs
  and consecutive non-empty segments, period boundaries included) / (3 t).
* ``Cal_ave``: evaluated candidates per step (``n_eval``), averaged.

Windows (:func:`codegen.metrics.run_windows`): RMSE, f_ave, Cal_ave
and the jump histogram over the whole run (or ``stats_window``); std/pp of the
ripples and V_o over the steady windows (last ``window_s`` of each
constant-reference segment, ``scenario.window_s``), each checked by
:func:`codegen.metrics.check_steady` (``not_steady`` names the metrics whose
window is not steady, ``not_computed`` those that could not be computed,
each with the reason); ``faults``/``fault_counts`` count the guard trips by
the names of ``records.FAULT_BITS``.
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from codegen.metrics import (
    GRID_TOL,
    check_steady,
    fault_counts,
    fundamental_hz,
    metric_flags,
    not_computed,
    ripple_summary,
    run_windows,
    sample_time,
    steady_ripples,
    thd,
    thd_ia,
    thd_ia_nominal,
    thd_window,
    window_mask,
    window_slice,
)
from codegen.model import Model
from codegen.topologies.ttype.records import FAULT_BITS
from codegen.topologies.ttype.vectors import OOO

if TYPE_CHECKING:  # pragma: no cover
    from codegen.topologies.ttype.sim import Trace

__all__ = [
    "UAB_GRID_S",
    "UAB_F_MAX_HZ",
    "resample_piecewise",
    "uab_thd",
    "line_jump_histogram",
    "leg_level_changes",
    "three_level_metrics",
]

#: Nominal grid of the u_ab resampling (adjusted to P whole cells per fundamental period).
UAB_GRID_S = 1e-6
#: Highest harmonic frequency counted in THD_uab.
UAB_F_MAX_HZ = 50e3


def _levels(states: np.ndarray) -> np.ndarray:
    s = np.asarray(states, dtype=np.int64)
    return np.stack([s // 9 - 1, (s // 3) % 3 - 1, s % 3 - 1], axis=-1)


# ---------------------------------------------------------------------------
# switched waveform
# ---------------------------------------------------------------------------
def resample_piecewise(values: Any, durations: Any, dt_grid: float, n_samples: int) -> np.ndarray:
    """Box-average a piecewise-constant waveform onto a uniform grid.

    ``values[i]`` holds for ``durations[i]`` seconds (consecutive, starting at
    t = 0; zero-length entries contribute nothing).  Sample j is the mean of
    the waveform over [j*dt_grid, (j+1)*dt_grid), computed exactly from the
    piecewise-linear cumulative integral.  The waveform must cover
    n_samples*dt_grid (up to rounding; beyond its end it is held).
    """
    v = np.asarray(values, dtype=np.float64).ravel()
    d = np.asarray(durations, dtype=np.float64).ravel()
    if v.shape != d.shape:
        raise ValueError("values and durations differ in shape")
    if np.any(d < 0) or not np.all(np.isfinite(d)):
        raise ValueError("durations must be finite and >= 0")
    keep = d > 0
    v, d = v[keep], d[keep]
    if v.size == 0:
        raise ValueError("empty waveform")
    ends = np.concatenate(([0.0], np.cumsum(d)))
    area = np.concatenate(([0.0], np.cumsum(v * d)))
    t = np.arange(n_samples + 1, dtype=np.float64) * dt_grid
    if t[-1] > ends[-1] * (1 + 1e-9):
        raise ValueError(f"waveform covers {ends[-1]:.6g} s, grid needs {t[-1]:.6g} s")
    # hold the last value past the end (rounding only)
    big = t[-1] + 1.0
    ends = np.append(ends, big)
    area = np.append(area, area[-1] + v[-1] * (big - ends[-2]))
    f = np.interp(t, ends, area)
    return np.diff(f) / dt_grid


def uab_thd(
    trace: Trace,
    t0: float,
    t1: float,
    f1_hz: float,
    grid_s: float = UAB_GRID_S,
    f_max_hz: float = UAB_F_MAX_HZ,
) -> tuple[float, dict[str, Any]]:
    """THD (percent) of the switched u_ab over whole fundamental periods in [t0, t1).

    See the module docstring.  Returns (THD, info) with the window, number of
    periods, grid step, cells per period and harmonic range.  Raises
    ValueError when not even one fundamental period fits.
    """
    if not (f1_hz > 0 and math.isfinite(f1_hz)):
        raise ValueError(f"fundamental frequency must be positive, got {f1_hz!r}")
    dt = trace.dt_s
    sl = window_slice(dt, t0, t1, trace.n)
    span = (sl.stop - sl.start) * dt
    n_per = int(math.floor(span * f1_hz + GRID_TOL))
    if n_per < 1:
        raise ValueError(f"window [{t0:.6g}, {t1:.6g}) s is shorter than one fundamental period ({1 / f1_hz:.4g} s)")
    cells = max(2, int(round(1.0 / (f1_hz * grid_s))))
    dt_grid = 1.0 / (f1_hz * cells)
    m = n_per * cells
    need = m * dt_grid
    k_end = min(sl.stop, sl.start + int(math.ceil(need / dt - GRID_TOL)) + 1)
    x = resample_piecewise(trace.uab_v[sl.start:k_end], trace.seg_s[sl.start:k_end], dt_grid, m)
    value, info = thd(x, dt_grid, 0.0, m * dt_grid, f1_hz, f_max_hz)
    info.update({
        "t0_s": sample_time(sl.start, dt),
        "t1_s": round(sl.start * dt + m * dt_grid, 12),
        "grid_s": dt_grid,
        "cells_per_period": cells,
        "resampling": "box average of the piecewise-constant segment waveform",
    })
    return value, info


def line_jump_histogram(uab_v: Any, seg_s: Any, udc_v: float, uab_before: float | None = 0.0) -> dict[str, Any]:
    """Histogram of |du_ab| between consecutive applied segments, in units of Udc/2.

    ``uab_v``/``seg_s``: per-segment line voltage and duration (any shape,
    read in order; zero-length segments skipped).  ``uab_before``: u_ab of
    the segment before the first (0.0 = OOO at start-up; None: not counted).
    Returns ``counts`` (index m = 0..4 units, m = round(|du|/(Udc/2)) clipped),
    ``n_boundaries``, ``n_jumps`` (m >= 1) and ``max_udc2``.
    """
    v = np.asarray(uab_v, dtype=np.float64).ravel()
    d = np.asarray(seg_s, dtype=np.float64).ravel()
    v = v[d > 0]
    if uab_before is not None:
        v = np.concatenate(([float(uab_before)], v))
    units = np.clip(np.rint(np.abs(np.diff(v)) / (0.5 * udc_v)), 0, 4).astype(np.int64)
    counts = np.bincount(units, minlength=5)[:5]
    nz = np.nonzero(counts[1:])[0]
    return {
        "counts": [int(c) for c in counts],
        "n_boundaries": int(units.size),
        "n_jumps": int(counts[1:].sum()),
        "max_udc2": int(nz[-1] + 1) if nz.size else 0,
    }


def leg_level_changes(seg_states: Any, seg_s: Any, initial_state: int = OOO) -> np.ndarray:
    """Per-period one-level leg changes from (n, 7) applied states and durations.

    Python cross-check of the C count (``trace.leg_changes``): sum over legs
    of |S_x(i) - S_x(i-1)| over consecutive non-empty segments, the first
    compared with the last non-empty segment of the previous period
    (``initial_state`` before the first period).
    """
    st = np.asarray(seg_states, dtype=np.int64)
    d = np.asarray(seg_s, dtype=np.float64)
    n = st.shape[0]
    flat_st, flat_d = st.ravel(), d.ravel()
    period = np.repeat(np.arange(n), st.shape[1])
    keep = flat_d > 0
    s = np.concatenate(([int(initial_state)], flat_st[keep]))
    lv = _levels(s)
    steps = np.abs(np.diff(lv, axis=0)).sum(axis=1)
    return np.bincount(period[keep], weights=steps, minlength=n).astype(np.int64)


# ---------------------------------------------------------------------------
# all three-level metrics of one run
# ---------------------------------------------------------------------------
def three_level_metrics(
    trace: Trace, model: Model, stats_window: tuple[float, float] | None = None, window_s: float | None = None,
    f_max_hz: float = 10e3,
    uab_grid_s: float = UAB_GRID_S,
    uab_f_max_hz: float = UAB_F_MAX_HZ,
    stats_desc: str = "window given by the caller",
) -> dict[str, Any]:
    """The three-level metric set of one closed-loop run (JSON-ready values; ``window_s`` defaults to
    ``scenario.window_s``; ``stats_desc`` describes ``stats_window`` in the result's ``window``)."""
    window_s = model.scenario.window_s if window_s is None else window_s
    dt = trace.dt_s
    psi_ref = trace.psi_ref_wb.astype(np.float64)
    w = run_windows(trace, model, stats_window, window_s, "whole run", stats_desc)
    sl, run_desc = w.sl, w.run_desc
    uab_before: float | None = 0.0  # OOO before the first period
    if stats_window is not None and sl.start > 0:
        prev_v = trace.uab_v[: sl.start].ravel()[trace.seg_s[: sl.start].ravel() > 0]
        uab_before = float(prev_v[-1]) if prev_v.size else 0.0
    t_run = (sl.stop - sl.start) * dt

    vo = trace.vo_v[np.asarray(w.rip_mask)]
    vo_stats = {
        "std": float(np.std(vo)) if vo.size else math.nan,
        "pp": float(np.ptp(vo)) if vo.size else math.nan,
        "mean": float(np.mean(vo)) if vo.size else math.nan,
    }

    tw = thd_window(trace, model, window_s)
    thd_ia_value, ia_info = thd_ia(trace, model, tw, f_max_hz, "i_a over")
    thd_nom, nom_info = thd_ia_nominal(trace, model, tw, f_max_hz)
    thd_uab, uab_info = not_computed("no steady window with a nonzero speed reference")
    if tw is not None:
        try:
            thd_uab, uab_info = uab_thd(trace, tw[0], tw[1], fundamental_hz(trace, model, *tw), uab_grid_s,
                                        uab_f_max_hz)
            uab_info["description"] = (
                f"switched u_ab over [{uab_info['t0_s']:g}, {uab_info['t1_s']:.6g}) s, "
                f"{uab_info['n_periods']} fundamental periods, box-averaged onto a "
                f"{uab_info['grid_s'] * 1e6:.4g} us grid, harmonics "
                f"{uab_info['harmonics'][0]}..{uab_info['harmonics'][1]} (<= {uab_f_max_hz:g} Hz)"
            )
            uab_info.update(check_steady(trace, model, *tw).as_json())
        except ValueError as exc:
            thd_uab, uab_info = not_computed(str(exc), window_s=list(tw))

    jumps = line_jump_histogram(trace.uab_v[sl], trace.seg_s[sl], trace.udc_v, uab_before)
    legs = int(np.sum(trace.leg_changes[sl], dtype=np.int64))

    steady = steady_ripples(trace, model, w.windows, psi_ref)
    for row in steady:
        v = trace.vo_v[window_mask(trace.n, dt, (row["t0_s"], row["t1_s"]))]
        row["Vo_std_v"] = float(np.std(v)) if v.size else math.nan
        row["Vo_pp_v"] = float(np.ptp(v)) if v.size else math.nan

    out = {
        **ripple_summary(trace, psi_ref, w.run_mask, w.rip_mask),
        "THD_ia_percent": thd_ia_value,
        "THD_uab_percent": thd_uab,
        "Vo_std_v": vo_stats["std"],
        "Vo_pp_v": vo_stats["pp"],
        "Vo_mean_v": vo_stats["mean"],
        "jump_hist_udc2": jumps["counts"],
        "max_line_jump_udc2": jumps["max_udc2"],
        "f_ave_hz": legs / (3.0 * t_run) if t_run > 0 else math.nan,
        "Cal_ave": float(np.mean(trace.n_eval[sl])) if sl.stop > sl.start else math.nan,
        "THD_ia_nominal_percent": thd_nom,
        "window": {
            "T_rip_RMSE_nm": run_desc,
            "psi_rip_RMSE_wb": {**run_desc, "reference": "controller psi_ref_wb of each period"},
            "f_ave_hz": {**run_desc, "definition": "one-level leg changes / (3 legs * t)"},
            "Cal_ave": run_desc,
            "jump_hist_udc2": {
                **run_desc,
                "definition": "boundaries between consecutive applied segments (period boundaries "
                              "included), index m = round(|du_ab|/(Udc/2)); m = 0: no level change",
                "n_boundaries": jumps["n_boundaries"],
                "n_jumps": jumps["n_jumps"],
            },
            "ripple_std_pp_Vo": w.rip_desc,
            "THD_ia_percent": ia_info,
            "THD_ia_nominal_percent": nom_info,
            "THD_uab_percent": uab_info,
        },
        "steady": steady,
        **fault_counts(trace.fault, FAULT_BITS),
    }
    return {**out, **metric_flags(out)}
