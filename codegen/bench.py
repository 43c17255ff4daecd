"""``mpcgen bench``: execution cost per step, every strategy side by side.

Host: every strategy's compiled step runs over the same recorded trajectory
(the conventional controller's closed-loop run of the config's scenario,
80 000 samples for the SPMSM, as seed-001 section 7 does), in one process,
interleaved, best of ``repeats``; reported as ns per step and the ratio to
the first strategy (conventional / mpdtc27).  Absolute nanoseconds on a
shared machine are noise; the ratios are the figure to compare with the
seed's Table 11.  Also: closed-loop simulation throughput in periods/s.

Emulated (``--emulated``): instructions per step on the emulated Cortex-M7
(codegen.emulate), reported as instructions -- not cycles.
"""
from __future__ import annotations

import time
from pathlib import Path
from typing import Callable

import numpy as np

from . import __version__
from .hostbuild import build_host_library
from .model import Model
from .twolevel.switch_tables import tables_for


def recorded_trajectory(model: Model, log: Callable[[str], None]) -> tuple[np.ndarray, float, int]:
    """Controller inputs of the baseline's closed-loop run, its wall time and period count."""
    if model.inverter.topology == "t-type":
        return _recorded_trajectory3(model, log)
    from .simulate import controller_inputs, run_closed_loop

    base = model.with_controller(strategy="conventional")
    lib = build_host_library(base, tables_for(base), with_sim=True)
    t0 = time.perf_counter()
    trace = run_closed_loop(lib.ffi, lib.lib, base, progress=lambda f: log(f"  recording trajectory {f:5.0%}"))
    wall = time.perf_counter() - t0
    return controller_inputs(trace, base), wall, len(trace.t_s)


def _recorded_trajectory3(model: Model, log: Callable[[str], None]) -> tuple[np.ndarray, float, int]:
    """Three-level: the 27-MPDTC (baseline) run at rated speed and torque."""
    from .runs3l import steady_model
    from .simulate3l import controller_inputs3, run_closed_loop3

    base = steady_model(model.with_controller(strategy="mpdtc27"), model.motor.rated_speed_rpm)
    lib = _library(base, with_sim=True)
    t0 = time.perf_counter()
    trace = run_closed_loop3(lib.ffi, lib.lib, base, progress=lambda f: log(f"  recording trajectory {f:5.0%}"))
    wall = time.perf_counter() - t0
    return controller_inputs3(trace, base), wall, trace.n


def _library(model: Model, with_sim: bool = False):
    """Host build of either topology's step."""
    if model.inverter.topology == "t-type":
        from .threelevel.derive import derive_three_level
        from .threelevel.hostbuild import build_three_level_library

        return build_three_level_library(model, derive_three_level(model), with_sim=with_sim)
    return build_host_library(model, tables_for(model), with_sim=with_sim)


def _tables(model: Model):
    """Derived tables of either topology (what the firmware project embeds)."""
    if model.inverter.topology == "t-type":
        from .threelevel.derive import derive_three_level

        return derive_three_level(model)
    return tables_for(model)


def host_ns_per_step(libs: dict, states: np.ndarray, repeats: int) -> dict[str, float]:
    """Best-of-``repeats`` ns per step, strategies interleaved in each round."""
    best = {s: float("inf") for s in libs}
    for _ in range(max(1, repeats)):
        for s, lib in libs.items():
            t0 = time.perf_counter_ns()
            lib.step_batch(states)
            dt = time.perf_counter_ns() - t0
            best[s] = min(best[s], dt / len(states))
    return best


def emulated_instructions(model: Model, strategies: list[str], log: Callable[[str], None]) -> dict[str, dict]:
    """Instructions per step on the emulated Cortex-M7 (QEMU -icount) for each strategy.

    Each strategy's qemu-m7 image replays the same 2 000 states of the
    baseline's recorded trajectory (two-level: the conventional closed-loop
    run; three-level: the 27-MPDTC run at rated speed) and also runs the
    bit-exact self-test;
    a mismatch or a digest disagreement is an error, never a number.
    """
    import tempfile

    from .emulate import EmulationError, run_and_check

    out = {}
    with tempfile.TemporaryDirectory(prefix="mpcgen-m7-") as tmp:
        for s in strategies:
            variant = model.with_controller(strategy=s)
            log(f"emulated Cortex-M7: building and running {s} in QEMU")
            r = run_and_check(variant, _tables(variant), Path(tmp) / s, n_selftest=1000)
            if r.mismatches or not r.digests_match:
                raise EmulationError(f"{s}: emulated results differ from the reference ({r.mismatches} mismatches)")
            out[s] = {"min": r.instr_min, "median": r.instr_median, "max": r.instr_max, "mean": r.instr_mean}
    return out


def bench(model: Model, strategies: list[str], emulated: bool = False, repeats: int = 5,
          log: Callable[[str], None] = print) -> dict:
    """Run the benchmark; returns the JSON-able result with a printable ``_table``."""
    states, sim_wall, n_periods = recorded_trajectory(model, log)
    libs = {}
    for s in strategies:
        variant = model.with_controller(strategy=s)
        libs[s] = _library(variant)
    log(f"timing {len(strategies)} strategies over {len(states)} recorded states, best of {repeats}")
    ns = host_ns_per_step(libs, states, repeats)
    base = strategies[0]
    result: dict = {
        "config": model.name, "config_hash": model.config_hash(), "version": __version__,
        "trajectory_states": int(len(states)),
        "sim_periods_per_s": n_periods / sim_wall if sim_wall > 0 else 0.0,
        "baseline": base,
        "strategies": {},
    }
    rows = [f"{'strategy':12s} {'host ns/step':>13s} {'ratio':>7s}" + ("  M7 instr/step (min/median/max)   ratio" if emulated else "")]
    m7 = {}
    if emulated:
        m7 = emulated_instructions(model, strategies, log=log)
    for s in strategies:
        host_ratio = ns[s] / ns[base]
        # with --emulated, ratio_to_conventional is the M7 instruction ratio (the figure)
        entry = {"host_ns_per_step": ns[s], "host_ns_ratio": host_ratio, "ratio_to_conventional": host_ratio}
        line = f"{s:12s} {ns[s]:13.1f} {host_ratio:7.3f}"
        if emulated:
            st = m7[s]
            m7_ratio = st["median"] / m7[base]["median"]
            entry.update({
                "m7_instructions_per_step": st["median"], "m7_instructions_min": st["min"],
                "m7_instructions_max": st["max"], "m7_ratio_to_conventional": m7_ratio,
                "ratio_to_conventional": m7_ratio,
            })
            line += f"  {st['min']:6.0f} / {st['median']:6.0f} / {st['max']:6.0f}   {m7_ratio:6.3f}"
        result["strategies"][s] = entry
        rows.append(line)
    rows.append(f"closed-loop simulation ({model.name}, {base}): {result['sim_periods_per_s']:,.0f} periods/s")
    if emulated:
        rows.append("M7 figures are instruction counts on the emulated Cortex-M7 (QEMU -icount), not cycles.")
    result["_table"] = "\n".join(rows)
    return result
