"""The seed-001 metric set of one closed-loop two-level run (definitions: codegen.metrics)."""
from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from codegen.metrics import (
    cal_ave,
    fault_counts,
    metric_flags,
    ripple_summary,
    run_windows,
    steady_ripples,
    thd_ia,
    thd_ia_nominal,
    thd_window,
)
from codegen.model import Model
from codegen.topologies.twolevel.mtpa import mtpa_flux
from codegen.topologies.twolevel.records import FAULT_BITS

if TYPE_CHECKING:  # pragma: no cover
    from codegen.topologies.twolevel.sim import Trace



def flux_reference_of(trace: Any, model: Model) -> Any:
    """psi* the flux ripple is measured about: ``controller.psi_ref_wb`` (constant), or for
    ``controller.psi_ref = "mtpa"`` the float64 MTPA flux of each sample's T* (the step interpolates
    the same curve from a table, within 5e-5 Wb: docs/algorithms.md "Flux reference"); the long-horizon
    family (no flux reference): the flux of its current reference, sqrt(psi_f^2 + (L i_q*)^2)."""
    from codegen.topologies.twolevel import section

    if section.family(model.controller.strategy) == section.MPCC:  # the flux of the current reference
        m = model.motor
        iq = np.asarray(trace.torque_ref_nm, np.float64) / (1.5 * m.pole_pairs * m.psi_f_wb)
        return np.sqrt(m.psi_f_wb ** 2 + (m.ld_h * iq) ** 2)
    if model.controller.psi_ref == "mtpa":
        return mtpa_flux(model.motor, np.asarray(trace.torque_ref_nm, np.float64))
    return float(model.controller.psi_ref_wb)

def switching_f_ave_hz(applied_sw: Any, inverter_open: Any, dt_s: float, sw_initial: int = 0,
                       open_initial: int = 0) -> tuple[float, int]:
    """Average switching frequency f_ave (seed 001 eq. (9), ``codegen.metrics.f_ave_hz``) of the periods
    in which the inverter switched: ``(f_ave_hz, open_periods)``.

    Periods with the inverter open (``inverter_open`` 1: gates off after a guard trip, every switch
    off) are left out of both the count and the time: a leg change into or out of an open period is
    not a commutation of the controller's decisions (the safe state 000 the step returns there would
    otherwise count as three), and t is the time the inverter switched, ``dt_s`` times the periods
    not open.  ``applied_sw[k]`` is the state held during period k; ``sw_initial`` /
    ``open_initial`` those of the period before the first (000, closed at start-up).  Without open
    periods this is ``f_ave_hz(applied_sw, len(applied_sw) * dt_s, sw_initial)`` exactly; NaN when
    no period switched."""
    sw = np.concatenate(([int(sw_initial)], np.asarray(applied_sw, dtype=np.int64).ravel()))
    is_open = np.concatenate(([bool(open_initial)], np.asarray(inverter_open).ravel() != 0))
    closed = ~is_open[1:]
    counted = closed & ~is_open[:-1]  # a change between two periods that both switched
    x = (sw[1:] ^ sw[:-1]) & 7
    changes = int(np.sum(((x & 1) + ((x >> 1) & 1) + ((x >> 2) & 1))[counted]))
    t = int(np.count_nonzero(closed)) * dt_s
    n_open = int(np.count_nonzero(is_open[1:]))
    return (changes / (3.0 * t) if t > 0.0 else math.nan), n_open


def two_level_metrics(
    trace: Trace, model: Model, stats_window: tuple[float, float] | None = None, window_s: float | None = None,
    f_max_hz: float = 10e3,
) -> dict[str, Any]:
    """The seed-001 metric set of one closed-loop run (JSON-ready values).

    Windows (stated in the result under ``window``):

    * ``T_rip_RMSE_nm``, ``psi_rip_RMSE_wb`` (eq. (7)-(8)), ``f_ave_hz`` (eq. (9))
      and ``Cal_ave`` (eq. (10)): over the whole run, as the seed's Tables 2
      and 9 do (n = all samples, t = the simulated time), or over
      ``stats_window`` = (t0, t1) when given.  ``f_ave_hz`` leaves out the periods with the
      inverter open (gates off after a guard trip, :func:`switching_f_ave_hz`): neither the leg
      changes into or out of them nor their time count (the ``faults`` periods, with gates off).
    * ``T_rip_std_nm``, ``T_rip_pp_nm``, ``psi_rip_std_wb``, ``psi_rip_pp_wb``: ripple of
      the error about its mean, over the steady windows (the last
      ``window_s`` (default ``scenario.window_s``) of each constant-reference segment),
      so that start-up and reversal transients do not dominate them; or over
      ``stats_window`` when given.
    * ``THD_ia_percent``: over the last steady window with a nonzero speed
      reference (:func:`thd_window`), f1 from the mean electrical speed there,
      harmonics up to ``f_max_hz``; NaN (with the reason) if there is none.
      ``THD_ia_nominal_percent``: the same window with the nominal fundamental
      (pole pairs * speed reference).
    * ``T_rip_p1_p99_nm``, ``psi_rip_p1_p99_wb``: 1st-99th percentile span of the
      error, over the windows of the std/pp ripples.
    * ``zero_vector_percent``: samples whose decision is V0, in % (seed 001's
      "zero-vector usage" of section 6); ``shortcut_percent``: samples decided
      without evaluating a candidate (n_eval = 0, the eps_T zero-vector
      shortcut); both over the RMSE window.

    ``steady`` lists the ripple statistics of each steady window.  Every
    window is checked (:func:`codegen.metrics.check_steady`): its entry says
    ``"steady"`` and, when false, ``not_steady_reason``; ``not_steady`` and
    ``not_computed`` map metric keys to reasons (:func:`codegen.metrics.metric_flags`).
    """
    window_s = model.scenario.window_s if window_s is None else window_s
    psi_ref = flux_reference_of(trace, model)
    w = run_windows(trace, model, stats_window, window_s,
                    "whole run, as seed 001 eq. (7)-(10) (n = all samples, t = simulated time)")
    sl, run_desc = w.sl, w.run_desc
    sw0 = int(trace.applied_sw[sl.start - 1]) if sl.start > 0 else 0
    open0 = int(trace.inverter_open[sl.start - 1]) if sl.start > 0 else 0
    f_ave, _n_open = switching_f_ave_hz(trace.applied_sw[sl], trace.inverter_open[sl], trace.dt_s, sw0, open0)
    tw = thd_window(trace, model, window_s)
    thd_value, thd_info = thd_ia(trace, model, tw, f_max_hz, "i_a over the last steady window with nonzero speed")
    thd_nom, thd_nom_info = thd_ia_nominal(trace, model, tw, f_max_hz)
    n_run = sl.stop - sl.start
    vec, n_eval = np.asarray(trace.vector[sl]), np.asarray(trace.n_eval[sl])

    out = {
        **ripple_summary(trace, psi_ref, w.run_mask, w.rip_mask),
        "THD_ia_percent": thd_value,
        "f_ave_hz": f_ave,
        "Cal_ave": cal_ave(trace.n_eval[sl]),
        "THD_ia_nominal_percent": thd_nom,
        "zero_vector_percent": 100.0 * float(np.count_nonzero(vec == 0)) / n_run if n_run else math.nan,
        "shortcut_percent": 100.0 * float(np.count_nonzero(n_eval == 0)) / n_run if n_run else math.nan,
        "window": {
            "T_rip_RMSE_nm": run_desc,
            "psi_rip_RMSE_wb": run_desc,
            "f_ave_hz": {**run_desc, "definition": "leg state changes / (3 legs * t), = N_switching/(6 t) of seed eq. (9)"},
            "Cal_ave": run_desc,
            "ripple_std_pp": w.rip_desc,
            "THD_ia_percent": thd_info,
            "THD_ia_nominal_percent": thd_nom_info,
            "zero_vector_percent": run_desc,
            "shortcut_percent": run_desc,
        },
        "steady": steady_ripples(trace, model, w.windows, psi_ref),
        **fault_counts(trace.fault, FAULT_BITS),
    }
    return {**out, **metric_flags(out)}
