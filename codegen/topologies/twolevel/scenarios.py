"""``mpcgen simulate``: the papers' scenarios for every strategy, metrics, plots.

Each strategy variant is built once (the compiled C step inside the compiled
closed loop, proven equal to the reference by ``verify``) and run over the
config's scenario.  Output: the seed-001 Table 9 layout, JSON with the
metrics, the config hash and versions, PNG plots.  ``run_threshold_sweep``
reproduces the Table 1/2 experiment (strategy s1 at several eps_T).
"""
from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from codegen.metrics import tracking_lines, tracking_verdict
from codegen.model import Model
from codegen.results import WINDOW_HEAD, fault_warning, footnotes, versions, window_cells
from codegen.results import clean_json as _clean
from codegen.results import flagged_cell as flagged
from codegen.results import fmt_cell as _fmt
from codegen.simulator.export import trace_writer
from codegen.simulator.memory import check_trace_memory
from codegen.topologies.twolevel.hostbuild import build_host_library
from codegen.topologies.twolevel.metrics import two_level_metrics
from codegen.topologies.twolevel.switch_tables import tables_for


def run_variant(model: Model, log: Callable[[str], None]) -> tuple[Any, float]:
    """Build and run one strategy variant; returns (trace, wall_s)."""
    from codegen.topologies.twolevel import mpcc as mpcc_step
    from codegen.topologies.twolevel import section
    from codegen.topologies.twolevel.sim import run_closed_loop

    if section.family(model.controller.strategy) == section.MPCC:
        lib = mpcc_step.host_library(model, mpcc_step.derive(model), with_sim=True)
    else:
        lib = build_host_library(model, tables_for(model), with_sim=True)
    s = model.controller.strategy
    t0 = time.perf_counter()
    trace = run_closed_loop(lib.ffi, lib.lib, model, progress=lambda f: log(f"  {s:12s} {f:5.0%}"))
    return trace, time.perf_counter() - t0


#: the metrics table9 prints
SHOWN = ("T_rip_RMSE_nm", "psi_rip_RMSE_wb", "THD_ia_percent", "Cal_ave", "f_ave_hz")


def table9(results: dict[str, dict[str, Any]]) -> str:
    """Seed-001 Table 9 layout: T_rip, psi_rip, THD, Cal_ave, f_ave per strategy, the guard faults and
    the THD window (t0, t1), its fundamental and number of periods; ``*``/``n/a`` footnoted."""
    rows = [f"{'strategy':12s} {'T_rip/N*m':>10s} {'psi_rip/Wb':>11s} {'THD/%':>8s} {'Cal_ave':>8s} {'f_ave/kHz':>10s} "
            f"{'faults':>7s} {'wall/s':>7s} {WINDOW_HEAD}"]
    for s, m in results.items():
        rows.append(f"{s:12s} {flagged(m, 'T_rip_RMSE_nm', '10.4f')}{flagged(m, 'psi_rip_RMSE_wb', '11.4f')}"
                    f"{flagged(m, 'THD_ia_percent', '8.2f')}{flagged(m, 'Cal_ave', '8.2f')}"
                    f"{flagged(m, 'f_ave_hz', '10.2f', 1e-3)}{m['faults']:7d} {m['wall_s']:7.2f} "
                    f"{window_cells(m['window']['THD_ia_percent'])}")
    return "\n".join(rows + footnotes(results, SHOWN))


def run_scenarios(model: Model, strategies: list[str], plots: Path | None = None,
                  log: Callable[[str], None] = print, traces: Path | None = None) -> dict[str, Any]:
    """Every strategy over the config's scenario; JSON-ready dict plus ``_table`` and ``_warnings``
    (one line per strategy whose guard tripped).  ``traces``: write the time series there
    (:class:`~codegen.simulator.export.TraceWriter`).  A run whose trace would not fit in memory
    is refused before anything runs (:func:`~codegen.simulator.memory.check_trace_memory`)."""
    from codegen.topologies.twolevel.sim import TRACE

    check_trace_memory(model, TRACE)
    results: dict[str, dict[str, Any]] = {}
    warnings: list[str] = []
    failed: dict[str, list[str]] = {}
    with trace_writer(traces, TRACE) as writer:
        for s in strategies:
            variant = model.with_controller(strategy=s)
            log(f"simulate {model.name} / {s}: {model.scenario.duration_s:g} s scenario")
            trace, wall = run_variant(variant, log)
            m = two_level_metrics(trace, variant)
            m["wall_s"] = wall
            m["periods"] = int(len(trace.t_s))
            m["periods_per_s"] = len(trace.t_s) / wall if wall > 0 else 0.0
            if plots is not None:
                from codegen.topologies.twolevel.plots import plot_two_level

                m["plots"] = [str(p) for p in plot_two_level(trace, variant, s, plots, m)]
            if writer is not None:
                writer.add(s, "scenario", trace)
            warning = fault_warning(s, m["periods"], m)
            if warning:
                warnings.append(warning)
            m.update(tracking_verdict(trace, variant))
            if m["tracking_reasons"]:
                failed[s] = m["tracking_reasons"]
            results[s] = m
    text = (f"{model.name}: {model.scenario.duration_s:g} s scenario, dt {model.controller.dt_s * 1e6:g} us "
            f"(MPTC paper Table 9 layout; RMSE, f_ave, Cal_ave over the whole run, THD over the last "
            f"{model.scenario.window_s:g} s window with nonzero speed, its steady state checked)\n"
            + table9(results) + "\n" + "\n".join(tracking_lines(failed)))
    warnings += [line.replace("tracking FAILED: ", "tracking failed: ", 1) for line in tracking_lines(failed)
                 if failed]
    return _clean({
        "config": model.name, "config_hash": model.config_hash(), "versions": versions(),
        "scenario": {"duration_s": model.scenario.duration_s, "speed_ref_rpm": model.scenario.speed_ref_rpm,
                     "load_nm": model.scenario.load_nm, "window_s": model.scenario.window_s},
        "strategies": results, "tracking_failed": sorted(failed), "_table": text, "_warnings": warnings,
    })


def zero_vector_utilisation(trace: Any, bands: list[float]) -> list[dict[str, Any]]:
    """Seed Table 1: zero-vector use among samples with |dT| <= band (dT from the controller's estimate)."""
    d_t = np.abs(trace.torque_ref_nm - trace.te_est_nm.astype(np.float64))
    zero = trace.vector == 0
    rows: list[dict[str, object]] = []
    for b in bands:
        sel = d_t <= b
        n, nz = int(sel.sum()), int((sel & zero).sum())
        rows.append({"band_nm": b, "N": n, "N_V0": nz, "eta_V0_percent": 100.0 * nz / n if n else None})
    n, nz = len(d_t), int(zero.sum())
    rows.append({"band_nm": "all", "N": n, "N_V0": nz, "eta_V0_percent": 100.0 * nz / n})
    return rows


def run_threshold_sweep(model: Model, eps_list: list[float], log: Callable[[str], None] = print) -> dict[str, Any]:
    """Seed Tables 1 and 2: the conventional run's zero-vector use per band, and s1 at every eps_T."""
    from codegen.topologies.twolevel.sim import TRACE

    check_trace_memory(model, TRACE)
    conv = model.with_controller(strategy="conventional")
    log(f"sweep {model.name}: conventional baseline")
    trace, wall = run_variant(conv, log)
    base = two_level_metrics(trace, conv)
    table1 = zero_vector_utilisation(trace, eps_list)
    sweep = []
    for eps in eps_list:
        variant = model.with_controller(strategy="s1", eps_t_nm=eps)
        log(f"sweep {model.name}: s1 eps_T = {eps:g} N*m")
        tr, w = run_variant(variant, log)
        m = two_level_metrics(tr, variant)
        sweep.append({"eps_t_nm": eps, "T_rip_RMSE_nm": m["T_rip_RMSE_nm"], "psi_rip_RMSE_wb": m["psi_rip_RMSE_wb"],
                      "Cal_ave": m["Cal_ave"], "f_ave_hz": m["f_ave_hz"], "faults": m["faults"],
                      "fault_counts": m["fault_counts"], "wall_s": w})
    lines = ["Table 1 layout: zero-vector utilisation of the conventional run vs torque-error band",
             f"{'band/N*m':>10s} {'N':>7s} {'N_V0':>7s} {'eta_V0/%':>9s}"]
    for r in table1:
        band = f"<= {r['band_nm']:g}" if r["band_nm"] != "all" else "all"
        lines.append(f"{band:>10s} {r['N']:7d} {r['N_V0']:7d} {_fmt(r['eta_V0_percent'], '9.2f')}")
    lines += ["", "Table 2 layout: strategy s1 at each threshold eps_T (whole run)",
              f"{'eps_T/N*m':>10s} {'T_rip/N*m':>10s} {'psi_rip/Wb':>11s} {'Cal_ave':>8s} {'f_ave/kHz':>10s} {'faults':>7s}"]
    for r in sweep:
        lines.append(f"{r['eps_t_nm']:10.2f} {r['T_rip_RMSE_nm']:10.4f} {r['psi_rip_RMSE_wb']:11.4f} {r['Cal_ave']:8.2f} {r['f_ave_hz'] / 1e3:10.2f} {r['faults']:7d}")
    lines.append(f"{'conv.':>10s} {base['T_rip_RMSE_nm']:10.4f} {base['psi_rip_RMSE_wb']:11.4f} {base['Cal_ave']:8.2f} {base['f_ave_hz'] / 1e3:10.2f} {base['faults']:7d}")
    warnings = [w for w in [fault_warning("conventional", trace.n, base),
                            *[fault_warning(f"s1 eps_T {r['eps_t_nm']:g}", trace.n, r) for r in sweep]] if w]
    return _clean({
        "config": model.name, "config_hash": model.config_hash(), "versions": versions(),
        "table1": table1, "table2": sweep,
        "conventional": {k: base[k] for k in ("T_rip_RMSE_nm", "psi_rip_RMSE_wb", "Cal_ave", "f_ave_hz", "faults",
                                              "fault_counts")},
        "_table": "\n".join(lines), "_warnings": warnings,
    })
