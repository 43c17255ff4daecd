"""The seed-001 metric set of one closed-loop two-level run (definitions: codegen.metrics)."""
from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from codegen.metrics import (
    cal_ave,
    f_ave_hz,
    fundamental_hz,
    ripple_stats,
    ripple_summary,
    sample_time,
    steady_windows,
    thd,
    thd_window,
    window_mask,
    window_slice,
)
from codegen.model import Model

if TYPE_CHECKING:  # pragma: no cover
    from codegen.topologies.twolevel.sim import Trace


def two_level_metrics(
    trace: Trace,
    model: Model,
    stats_window: tuple[float, float] | None = None,
    window_s: float = 0.2,
    f_max_hz: float = 10e3,
) -> dict[str, Any]:
    """The seed-001 metric set of one closed-loop run (JSON-ready values).

    Windows (stated in the result under ``window``):

    * ``T_rip_RMSE``, ``psi_rip_RMSE`` (eq. (7)-(8)), ``f_ave_hz`` (eq. (9))
      and ``Cal_ave`` (eq. (10)): over the whole run, as the seed's Tables 2
      and 9 do (n = all samples, t = the simulated time), or over
      ``stats_window`` = (t0, t1) when given.
    * ``T_rip_std``, ``T_rip_pp``, ``psi_rip_std``, ``psi_rip_pp``: ripple of
      the error about its mean, over the steady windows (the last
      ``window_s`` of each constant-reference segment, :func:`steady_windows`),
      so that start-up and reversal transients do not dominate them; or over
      ``stats_window`` when given.
    * ``THD_ia`` (percent): over the last steady window with a nonzero speed
      reference (:func:`thd_window`), f1 from the mean electrical speed there,
      harmonics up to ``f_max_hz``; NaN (with the reason) if there is none.

    ``steady`` lists the ripple statistics of each steady window.
    """
    dt, n = trace.dt_s, trace.n
    psi_ref = float(model.controller.psi_ref_wb)
    windows = steady_windows(model, window_s)

    if stats_window is None:
        run_mask = None
        run_desc = {
            "t0_s": 0.0,
            "t1_s": sample_time(n, dt),
            "n_samples": n,
            "description": "whole run, as seed 001 eq. (7)-(10) (n = all samples, t = simulated time)",
        }
        rip_mask = window_mask(n, dt, windows)
        rip_desc = {
            "windows_s": [[a, b] for a, b in windows],
            "n_samples": int(np.count_nonzero(rip_mask)),
            "description": f"steady windows: last {window_s:g} s of each constant-reference segment",
        }
        sw_run, n_eval_run, t_run, sw0 = trace.applied_sw, trace.n_eval, n * dt, 0
    else:
        sl = window_slice(dt, stats_window[0], stats_window[1], n)
        run_mask = np.zeros(n, dtype=bool)
        run_mask[sl] = True
        run_desc = {
            "t0_s": sample_time(sl.start, dt),
            "t1_s": sample_time(sl.stop, dt),
            "n_samples": sl.stop - sl.start,
            "description": "window given by the caller",
        }
        rip_mask = run_mask
        rip_desc = dict(run_desc)
        sw_run, n_eval_run, t_run = trace.applied_sw[sl], trace.n_eval[sl], (sl.stop - sl.start) * dt
        sw0 = int(trace.applied_sw[sl.start - 1]) if sl.start > 0 else 0


    thd_value = math.nan
    thd_info: dict[str, Any]
    tw = thd_window(trace, model, window_s)
    if tw is None:
        thd_info = {"description": "no steady window with a nonzero speed reference"}
    else:
        try:
            thd_value, thd_info = thd(trace.ia_a, dt, tw[0], tw[1], fundamental_hz(trace, model, *tw), f_max_hz)
            thd_info["description"] = (
                f"i_a over the last steady window with nonzero speed [{tw[0]:g}, {tw[1]:g}) s, "
                f"{thd_info['n_periods']} fundamental periods, harmonics "
                f"{thd_info['harmonics'][0]}..{thd_info['harmonics'][1]}"
            )
        except ValueError as exc:
            thd_info = {"description": f"THD not computed: {exc}", "window_s": list(tw)}

    steady = []
    for a, b in windows:
        m = window_mask(n, dt, (a, b))
        ts = ripple_stats(trace.te_nm, trace.torque_ref_nm, m)
        ps = ripple_stats(trace.psi_wb, psi_ref, m)
        steady.append(
            {
                "t0_s": a,
                "t1_s": b,
                "T_rip_RMSE": ts["rmse"],
                "T_rip_std": ts["std"],
                "T_rip_pp": ts["pp"],
                "psi_rip_RMSE": ps["rmse"],
                "psi_rip_std": ps["std"],
                "psi_rip_pp": ps["pp"],
            }
        )

    return {
        **ripple_summary(trace, psi_ref, run_mask, rip_mask),
        "THD_ia": thd_value,
        "f_ave_hz": f_ave_hz(sw_run, t_run, sw0),
        "Cal_ave": cal_ave(n_eval_run),
        "window": {
            "T_rip_RMSE": run_desc,
            "psi_rip_RMSE": run_desc,
            "f_ave_hz": {**run_desc, "definition": "leg state changes / (3 legs * t), = N_switching/(6 t) of seed eq. (9)"},
            "Cal_ave": run_desc,
            "ripple_std_pp": rip_desc,
            "THD_ia": thd_info,
        },
        "steady": steady,
    }
