"""``mpcgen simulate`` for a T-type three-level config (mpdtc-three-level.md section 3).

``scenario.set = "config"`` (the default) runs the config's ``[scenario]``
from standstill, one run per strategy.  ``scenario.set = "mpdtc-table5"``
runs the MPDTC paper's Table 5 set: steady state at 300, 1800 and 3000 r/min with the
speed held by the load machine and T* = 1.27 N*m, and the rated-speed load
step 0 -> 1.27 N*m under the speed PI.

Each steady run lasts ``max(scenario.duration_s, TABLE5_SETTLE_S +
scenario.window_s)`` and its Table-5 metrics (key ``<speed>rpm_steady``) are
taken over its last ``scenario.window_s`` only, so the start-up (the first
``TABLE5_SETTLE_S``) is excluded and every window is steady; the printed
table states that window.  The key ``<speed>rpm`` keeps, for continuity of
the recorded results, the metrics of the first ``scenario.duration_s`` of
the same run from start-up (its windows flagged not steady).  Each strategy variant runs its
compiled step inside the compiled closed loop (seven-segment integration).
Output: the seed's Table 5 layout with the reduction of 63- vs 27-MPDTC,
neutral-point ripple, u_ab THD, line-voltage jumps; JSON; plots.
"""
from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from codegen.metrics import fault_counts, tracking_lines, tracking_verdict
from codegen.model import Model
from codegen.results import WINDOW_HEAD, fault_warning, footnotes, versions, window_cells
from codegen.results import clean_json as _clean
from codegen.results import flagged_cell as flagged
from codegen.results import fmt_cell as _fmt
from codegen.simulator.export import trace_writer
from codegen.simulator.memory import check_trace_memory
from codegen.topologies.ttype.metrics import three_level_metrics
from codegen.topologies.ttype.records import FAULT_BITS

STEADY_SPEEDS_RPM = (300.0, 1800.0, 3000.0)
#: start-up excluded from the Table-5 steady metrics (currents, flux and V_o settle well within it)
TABLE5_SETTLE_S = 0.2
KEYS = ("T_rip_RMSE_nm", "psi_rip_RMSE_wb", "THD_ia_percent", "Vo_std_v", "THD_uab_percent", "max_line_jump_udc2",
        "f_ave_hz", "Cal_ave")


def steady_model(model: Model, speed_rpm: float) -> Model:
    """Speed held at ``speed_rpm`` by the load machine, T* = rated torque."""
    sc = dataclasses.replace(model.scenario, speed_mode="imposed", speed_ref_rpm=((0.0, speed_rpm),),
                             load_nm=((0.0, model.motor.rated_torque_nm),))
    return model.replace(scenario=sc)


def steady_run_model(model: Model, speed_rpm: float) -> Model:
    """:func:`steady_model` lengthened to ``max(duration_s, TABLE5_SETTLE_S + window_s)``."""
    m = steady_model(model, speed_rpm)
    d = max(m.scenario.duration_s, TABLE5_SETTLE_S + m.scenario.window_s)
    return m.replace(scenario=dataclasses.replace(m.scenario, duration_s=d))


def steady_window(model: Model) -> tuple[float, float]:
    """The metric window of a steady run of ``model`` (a :func:`steady_run_model`): its last ``window_s``."""
    d = model.scenario.duration_s
    return (round(d - model.scenario.window_s, 12), d)


def prefix(trace: Any, duration_s: float) -> Any:
    """The first ``duration_s`` of a trace (every per-period array cut; the run is causal, so this is
    the trace a run of that duration gives: round(duration_s / dt_s) periods, as
    ``codegen.simulator.driver.n_periods`` counts them)."""
    k = int(round(duration_s / trace.dt_s))
    cut = {f.name: getattr(trace, f.name)[:k] for f in dataclasses.fields(trace)
           if isinstance(getattr(trace, f.name), np.ndarray)}
    return dataclasses.replace(trace, **cut)


def load_step_model(model: Model) -> Model:
    """Rated speed under the speed PI (the run starts at rated speed), load 0 -> rated torque at half the run."""
    d = max(model.scenario.duration_s, 0.2)
    sc = dataclasses.replace(model.scenario, speed_mode="mechanical", duration_s=d,
                             speed_ref_rpm=((0.0, model.motor.rated_speed_rpm),),
                             load_nm=((0.0, 0.0), (d / 2, model.motor.rated_torque_nm)))
    return model.replace(scenario=sc)


def _run(model: Model, log: Callable[[str], None], label: str,
         initial_speed_rpm: float = 0.0) -> tuple[Any, float]:
    from codegen.topologies.ttype import mpcc as mpcc_step
    from codegen.topologies.ttype import section
    from codegen.topologies.ttype.derive import derive_three_level
    from codegen.topologies.ttype.hostbuild import build_three_level_library
    from codegen.topologies.ttype.sim import run_closed_loop

    if section.family(model.controller.strategy) == section.MPCC:
        lib = mpcc_step.host_library(model, mpcc_step.derive(model), with_sim=True)
    else:
        lib = build_three_level_library(model, derive_three_level(model), with_sim=True)
    t0 = time.perf_counter()
    trace = run_closed_loop(lib.ffi, lib.lib, model, progress=lambda f: log(f"  {label} {f:5.0%}"),
                             initial_speed_rpm=initial_speed_rpm)
    return trace, time.perf_counter() - t0


def _row(label: str, s: str, m: dict[str, Any]) -> str:
    """One table row: the metrics (``*`` not steady, ``n/a`` not computed), faults, THD window."""
    return (f"{label:>6s} {s:9s} {flagged(m, 'T_rip_RMSE_nm', '9.4f')}{flagged(m, 'psi_rip_RMSE_wb', '10.5f')}"
            f"{flagged(m, 'THD_ia_percent', '8.2f')}{flagged(m, 'Vo_std_v', '8.4f')}"
            f"{flagged(m, 'THD_uab_percent', '9.2f')}{m['max_line_jump_udc2']:4d} {flagged(m, 'Cal_ave', '5.2f')}"
            f"{flagged(m, 'f_ave_hz', '9.2f', 1e-3)}{m['faults']:7d} {window_cells(m['window']['THD_ia_percent'])}")


HEAD = (f"{'run':>6s} {'strategy':9s} {'T_rip/N*m':>9s}  {'psi_rip/Wb':>10s}  {'THD_ia/%':>8s}  {'Vo_std/V':>8s}  "
        f"{'THD_uab/%':>9s}  {'jump':>4s} {'Cal':>5s}  {'f_ave/kHz':>9s}  {'faults':>6s} {WINDOW_HEAD}")


def table5(results: dict[str, Any], strategies: list[str]) -> str:
    """Seed-000 Table 5 layout (+ V_o, u_ab THD, max jump, faults, THD window) and the 63-vs-27
    reduction; the rated-speed load step last."""
    rows = [HEAD]
    notes: dict[str, dict[str, Any]] = {}
    for key, label in [*((f"{v:g}rpm_steady", f"{v:.0f}") for v in STEADY_SPEEDS_RPM), ("load_step", "load")]:
        for s in strategies:
            m = results[s][key]
            rows.append(_row(label, s, m))
            notes[f"{s} {key}"] = m
        if key != "load_step" and "mpdtc27" in strategies and "mpdtc63" in strategies:
            a, b = results["mpdtc27"][key], results["mpdtc63"][key]
            red = [100 * (1 - b[k] / a[k]) if a[k] else float("nan")
                   for k in ("T_rip_RMSE_nm", "psi_rip_RMSE_wb", "THD_ia_percent")]
            rows.append(f"{'':6s} {'reduction':9s} {_fmt(red[0], '8.1f')}% {_fmt(red[1], '9.1f')}% "
                        f"{_fmt(red[2], '7.1f')}%")
    return "\n".join(rows + footnotes(notes, KEYS))


def config_table(results: dict[str, Any], strategies: list[str]) -> str:
    """The config's scenario: one row per strategy (metrics, faults, THD window), footnotes."""
    rows = [HEAD] + [_row("config", s, results[s]["scenario"]) for s in strategies]
    return "\n".join(rows + footnotes({s: results[s]["scenario"] for s in strategies}, KEYS))


def runs_of(variant: Model) -> list[tuple[str, Model, float]]:
    """(key, model, initial speed r/min) of every run: the config's scenario from standstill
    (``scenario.set = "config"``), or the Table 5 set (``"mpdtc-table5"``: the lengthened steady runs
    of :func:`steady_run_model`, then the load step)."""
    if variant.scenario.set != "mpdtc-table5":
        return [("scenario", variant, 0.0)]
    runs = [(f"{v:g}rpm", steady_run_model(variant, v), 0.0) for v in STEADY_SPEEDS_RPM]  # speed imposed anyway
    runs.append(("load_step", load_step_model(variant), variant.motor.rated_speed_rpm))
    return runs


def _metrics(key: str, trace: Any, m: Model, config: Model) -> dict[str, dict[str, Any]]:
    """Result entries of one run: ``key`` alone, or for a steady Table-5 run ``key`` (the first
    ``scenario.duration_s`` from start-up) and ``key_steady`` (the last ``window_s``)."""
    if config.scenario.set != "mpdtc-table5" or key == "load_step":
        return {key: three_level_metrics(trace, m)}
    d0 = config.scenario.duration_s
    first = m.replace(scenario=dataclasses.replace(m.scenario, duration_s=d0))
    t0, t1 = steady_window(m)
    desc = (f"steady window: last {m.scenario.window_s:g} s of the {t1:g} s run, the first {t0:g} s "
            "(start-up) excluded")
    return {key: three_level_metrics(prefix(trace, d0), first),
            f"{key}_steady": three_level_metrics(trace, m, stats_window=(t0, t1), stats_desc=desc)}


def run_three_level(model: Model, strategies: list[str], plots: Path | None = None,
                    log: Callable[[str], None] = print, traces: Path | None = None) -> dict[str, Any]:
    """Every strategy over the runs of :func:`runs_of`; JSON-ready dict with ``_table`` and ``_warnings``.

    Every run's trace memory is checked before anything runs
    (:func:`~codegen.simulator.memory.check_trace_memory`); ``traces``:
    write the time series there (:class:`~codegen.simulator.export.TraceWriter`).
    """
    from codegen.topologies.ttype.sim import TRACE

    for _key, m, _speed in runs_of(model):
        check_trace_memory(m, TRACE)
    results: dict[str, dict[str, Any]] = {}
    warnings: list[str] = []
    failed: dict[str, list[str]] = {}
    with trace_writer(traces, TRACE) as writer:
        for s in strategies:
            results[s] = {}
            whole: list[tuple[int, dict[str, Any]]] = []  # (periods, faults) of each whole run
            for key, m, speed in runs_of(model.with_controller(strategy=s)):
                log(f"simulate {model.name} / {s} / {key}: {m.scenario.duration_s:g} s")
                trace, wall = _run(m, log, f"{s} {key}", initial_speed_rpm=speed)
                entries = _metrics(key, trace, m, model)
                for met in entries.values():
                    met["wall_s"] = wall
                    met["periods_per_s"] = trace.n / wall if wall > 0 else 0.0
                met = entries[key]
                met.update(tracking_verdict(trace, m))
                if met["tracking_reasons"]:
                    failed[f"{s}/{key}"] = met["tracking_reasons"]
                if plots is not None:
                    from codegen.topologies.ttype.plots import plot_three_level

                    tag, run = _plot_names(s, key, m)
                    shown = entries.get(f"{key}_steady", met)  # the metrics the table prints for this run
                    met["plots"] = [str(p) for p in plot_three_level(trace, m, tag, run, plots, shown)]
                if writer is not None:
                    writer.add(s, key, trace)
                whole.append((trace.n, fault_counts(trace.fault, FAULT_BITS)))
                results[s].update(entries)
            warning = _fault_warning(s, whole)
            if warning:
                warnings.append(warning)
    sc = model.scenario
    if sc.set == "mpdtc-table5":
        m0 = steady_run_model(model, STEADY_SPEEDS_RPM[0])
        t0, t1 = steady_window(m0)
        ls = load_step_model(model).scenario.duration_s
        text = (f"{model.name}: steady state at 300/1800/3000 r/min, T* = {model.motor.rated_torque_nm:g} N*m, "
                f"runs of {t1:g} s from start-up, every steady metric (RMSE, std, f_ave, Cal, THD) over the "
                f"window [{t0:g}, {t1:g}) s (start-up excluded, steady state checked); the rated load step, "
                f"{ls:g} s, over the whole run (MPDTC paper Table 5 layout; jump = largest line-voltage jump in "
                "Udc/2)\n" + table5(results, strategies))
    else:
        text = (f"{model.name}: {sc.duration_s:g} s scenario ({sc.speed_mode} speed), dt "
                f"{model.controller.dt_s * 1e6:g} us (RMSE, f_ave, Cal over the whole run; THD over the last "
                f"{sc.window_s:g} s window with nonzero speed, its steady state checked; jump = largest "
                "line-voltage jump in Udc/2)\n" + config_table(results, strategies))
    text += "\n" + "\n".join(tracking_lines(failed))
    warnings += [line.replace("tracking FAILED: ", "tracking failed: ", 1) for line in tracking_lines(failed)
                 if failed]
    return _clean({"config": model.name, "config_hash": model.config_hash(), "versions": versions(),
                   "scenario_set": sc.set, "strategies": results, "tracking_failed": sorted(failed),
                   "_table": text, "_warnings": warnings})


def _plot_names(strategy: str, key: str, m: Model) -> tuple[str, str]:
    """(file tag, title) of one run's plots: the config's scenario by its profiles, a Table-5 steady run
    by its imposed speed and torque, the load step by its speed and load."""
    from codegen.simulator.figures import scenario_label

    if key == "scenario":
        return strategy, f"{strategy}, config scenario ({scenario_label(m)})"
    if key == "load_step":
        return f"{strategy}_loadstep", f"{strategy}, rated-load step ({scenario_label(m)})"
    return f"{strategy}_{key}", f"{strategy}, steady run, speed imposed ({scenario_label(m)})"


def _fault_warning(strategy: str, runs: list[tuple[int, dict[str, Any]]]) -> str | None:
    """One stderr line for a strategy whose guard tripped in any of its whole runs (counts summed)."""
    counts: dict[str, int] = {}
    for _n, f in runs:
        for k, n in f["fault_counts"].items():
            counts[k] = counts.get(k, 0) + n
    total = {"faults": sum(f["faults"] for _n, f in runs), "fault_counts": counts}
    return fault_warning(strategy, sum(n for n, _f in runs), total)
