"""``mpcgen simulate`` for a T-type three-level config (mpdtc-three-level.md section 3).

Scenarios of the spec: steady state at 300, 1800 and 3000 r/min with the
speed held by the load machine and T* = 1.27 N*m, and the rated-speed load
step 0 -> 1.27 N*m under the speed PI.  Each strategy variant runs its
compiled step inside the compiled closed loop (seven-segment integration).
Output: the seed's Table 5 layout with the reduction of 63- vs 27-MPDTC,
neutral-point ripple, u_ab THD, line-voltage jumps; JSON; plots.
"""
from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from pathlib import Path

from codegen.model import Model
from codegen.results import clean_json as _clean
from codegen.results import fmt_cell as _fmt
from codegen.results import versions
from codegen.topologies.ttype.metrics import three_level_metrics

STEADY_SPEEDS_RPM = (300.0, 1800.0, 3000.0)
KEYS = ("T_rip_RMSE", "psi_rip_RMSE", "THD_ia", "Vo_std", "THD_uab", "max_line_jump_udc2", "f_ave_hz", "Cal_ave")


def steady_model(model: Model, speed_rpm: float) -> Model:
    """Speed held at ``speed_rpm`` by the load machine, T* = rated torque."""
    sc = dataclasses.replace(model.scenario, speed_mode="imposed", speed_ref_rpm=((0.0, speed_rpm),),
                             load_nm=((0.0, model.motor.rated_torque_nm),))
    return model.replace(scenario=sc)


def load_step_model(model: Model) -> Model:
    """Rated speed under the speed PI (the run starts at rated speed), load 0 -> rated torque at half the run."""
    d = max(model.scenario.duration_s, 0.2)
    sc = dataclasses.replace(model.scenario, speed_mode="mechanical", duration_s=d,
                             speed_ref_rpm=((0.0, model.motor.rated_speed_rpm),),
                             load_nm=((0.0, 0.0), (d / 2, model.motor.rated_torque_nm)))
    return model.replace(scenario=sc)


def _run(model: Model, log: Callable[[str], None], label: str, initial_speed_rpm: float = 0.0):
    from codegen.topologies.ttype.derive import derive_three_level
    from codegen.topologies.ttype.hostbuild import build_three_level_library
    from codegen.topologies.ttype.sim import run_closed_loop

    lib = build_three_level_library(model, derive_three_level(model), with_sim=True)
    t0 = time.perf_counter()
    trace = run_closed_loop(lib.ffi, lib.lib, model, progress=lambda f: log(f"  {label} {f:5.0%}"),
                             initial_speed_rpm=initial_speed_rpm)
    return trace, time.perf_counter() - t0


def table5(results: dict, strategies: list[str]) -> str:
    """Seed-000 Table 5 layout (+ V_o, u_ab THD, max jump) and the 63-vs-27 reduction."""
    head = f"{'speed':>6s} {'strategy':9s} {'T_rip/N*m':>9s} {'psi_rip/Wb':>10s} {'THD_ia/%':>8s} {'Vo_std/V':>8s} {'THD_uab/%':>9s} {'jump':>4s} {'Cal':>5s} {'f_ave/kHz':>9s}"
    rows = [head]
    for speed in STEADY_SPEEDS_RPM:
        key = f"{speed:g}rpm"
        for s in strategies:
            m = results[s][key]
            rows.append(f"{speed:6.0f} {s:9s} {_fmt(m['T_rip_RMSE'], '9.4f')} {_fmt(m['psi_rip_RMSE'], '10.5f')} "
                        f"{_fmt(m['THD_ia'], '8.2f')} {_fmt(m['Vo_std'], '8.4f')} {_fmt(m['THD_uab'], '9.2f')} "
                        f"{m['max_line_jump_udc2']:4d} {_fmt(m['Cal_ave'], '5.2f')} {_fmt(m['f_ave_hz'] / 1e3, '9.2f')}")
        if "mpdtc27" in strategies and "mpdtc63" in strategies:
            a, b = results["mpdtc27"][key], results["mpdtc63"][key]
            red = [100 * (1 - b[k] / a[k]) if a[k] else float("nan") for k in ("T_rip_RMSE", "psi_rip_RMSE", "THD_ia")]
            rows.append(f"{'':6s} {'reduction':9s} {red[0]:8.1f}% {red[1]:9.1f}% {red[2]:7.1f}%")
    return "\n".join(rows)


def run_three_level(model: Model, strategies: list[str], plots: Path | None = None,
                    log: Callable[[str], None] = print) -> dict:
    """Every strategy at every steady speed, plus the load step; JSON-ready dict with ``_table``."""
    results: dict[str, dict] = {}
    for s in strategies:
        variant = model.with_controller(strategy=s)
        results[s] = {}
        runs = [(f"{v:g}rpm", steady_model(variant, v), v) for v in STEADY_SPEEDS_RPM]
        runs.append(("load_step", load_step_model(variant), variant.motor.rated_speed_rpm))
        for key, m, speed in runs:
            log(f"simulate {model.name} / {s} / {key}: {m.scenario.duration_s:g} s")
            start = speed if key == "load_step" else 0.0  # steady runs: speed imposed anyway
            trace, wall = _run(m, log, f"{s} {key}", initial_speed_rpm=start)
            met = three_level_metrics(trace, m)
            met["wall_s"] = wall
            met["periods_per_s"] = trace.n / wall if wall > 0 else 0.0
            if plots is not None:
                from codegen.topologies.ttype.plots import plot_three_level

                met["plots"] = [str(p) for p in plot_three_level(trace, m, s if key != "load_step" else f"{s}_loadstep", speed, plots)]
            results[s][key] = met
    text = (f"{model.name}: steady state at 300/1800/3000 r/min, T* = {model.motor.rated_torque_nm:g} N*m, "
            f"{model.scenario.duration_s:g} s each (seed 000 Table 5 layout; jump = largest line-voltage jump in Udc/2)\n"
            + table5(results, strategies))
    return _clean({"config": model.name, "config_hash": model.config_hash(), "versions": versions(),
                   "strategies": results, "_table": text})
