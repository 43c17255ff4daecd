"""The plant's integrators side by side: closed-loop periods/s and current error (``mpcgen bench``).

``plant.integrator`` chooses how the simulator's C integrates the plant (docs/simulation.md
"Integration"): ``"rk4"``, RK4 sub-steps of at most 1 us, or ``"exact"``, the Taylor series of each
constant-voltage piece summed to double rounding (``csrc/sim_exact.h``).  :func:`compare` runs the
config's scenario through the compiled closed loop with each, in interleaved rounds (best of
``rounds``), and measures each run's phase currents against the tight reference
(:mod:`codegen.simulator.tightref`: scipy's DOP853 at rtol 1e-10, replaying the run's own inverter
open loop) over the first ``error_periods`` periods.
"""
from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from codegen.config import family_strategies
from codegen.model import Model, Plant
from codegen.simulator import tightref

#: periods of each run replayed through the tight reference (a short window: DOP853 in Python)
ERROR_PERIODS = 1000


def with_integrator(model: Model, integrator: str) -> Model:
    """``model`` with ``plant.integrator`` replaced (one of ``Plant.INTEGRATORS``)."""
    if integrator not in Plant.INTEGRATORS:
        raise ValueError(f"plant.integrator = {integrator!r}: must be one of {', '.join(Plant.INTEGRATORS)}")
    value: Any = integrator  # checked above: one of the field's literals
    return model.replace(plant=dataclasses.replace(model.plant, integrator=value))


def same_decisions(a: Any, b: Any, decision_field: str) -> bool:
    """Whether two runs' traces hold the same decisions: the decision field and every period the plant
    applied (its segments' durations and leg levels: e.g. a T-type decision's T_N), bit for bit."""
    if not np.array_equal(np.asarray(getattr(a, decision_field)), np.asarray(getattr(b, decision_field))):
        return False
    return all(a.applied_period(k) == b.applied_period(k) for k in range(min(int(a.n), int(b.n))))


def compare(topo: Any, model: Model, rounds: int = 5, error_periods: int = ERROR_PERIODS,
            log: Callable[[str], None] = print) -> dict[str, Any]:
    """Every integrator on the config's scenario (the baseline strategy of the config strategy's family, ``topo``: its plugin):
    ``periods``, per integrator ``periods_per_s`` (best of ``rounds`` interleaved runs) and
    ``max_current_error_a`` (against DOP853 over the first ``error_periods``), and whether each run's
    decisions equal the first integrator's (``decisions_identical``, :func:`same_decisions`, over the
    whole scenario)."""
    base = model.with_controller(strategy=family_strategies(model.inverter.topology, model.controller.strategy)[0])
    lib = topo.host_library(base, topo.derive(base), with_sim=True)
    variants = {name: with_integrator(base, name) for name in Plant.INTEGRATORS}
    best = {name: 0.0 for name in variants}
    traces: dict[str, Any] = {}
    log(f"simulator: {len(variants)} integrators over the scenario of {model.name}, best of {rounds} interleaved rounds")
    for _ in range(max(1, rounds)):
        for name, variant in variants.items():
            t0 = time.perf_counter()
            traces[name] = topo.closed_loop_trace(variant, lib)
            wall = time.perf_counter() - t0
            best[name] = max(best[name], traces[name].n / wall if wall > 0 else 0.0)
    first = next(iter(variants))
    n = int(traces[first].n)
    window = min(error_periods, n - 1)
    out: dict[str, Any] = {"periods": n, "strategy": base.controller.strategy, "rounds": max(1, rounds),
                           "error_periods": window, "reference": f"scipy DOP853, rtol {tightref.RTOL:g}, "
                           f"atol {tightref.ATOL:g}, the run's inverter replayed open loop", "integrators": {}}
    for name, variant in variants.items():
        log(f"  {name}: max current error against DOP853 over the first {window} periods")
        err = tightref.current_error(variant, traces[name], window)
        same = same_decisions(traces[name], traces[first], topo.decision_field)
        out["integrators"][name] = {"periods_per_s": best[name], "max_current_error_a": err,
                                    "decisions_identical": same}
    return out


def summary(data: dict[str, Any], config: str) -> list[str]:
    """The table's lines of a :func:`compare` result."""
    ints = data["integrators"]
    first = next(iter(ints))
    cells = ", ".join(f"{name} {e['periods_per_s']:,.0f}" for name, e in ints.items())
    errs = ", ".join(f"{name} {e['max_current_error_a']:.1e} A" for name, e in ints.items())
    same = ", ".join(f"{name} {'identical' if e['decisions_identical'] else 'DIFFERENT'}"
                     for name, e in ints.items() if name != first)
    return [f"simulator periods/s ({config}, {data['strategy']}, {data['periods']} periods, best of "
            f"{data['rounds']} interleaved rounds): {cells}",
            f"  max current error against the tight reference ({data['reference']}, first "
            f"{data['error_periods']} periods): {errs}; decisions against {first}: {same}"]
