"""Verification of the three-level step: compiled C against the Python
reference, bit for bit (numerics.md "Bit-for-bit"), over random and
adversarial states (``states``), in chunks."""
from __future__ import annotations

import dataclasses
import time
from typing import Callable

import numpy as np

from ..model import Model
from ..verify import compare_batches
from . import reference
from .derive import derive_three_level
from .hostbuild import build_three_level_library
from .states import adversarial_states, random_states


def verify_three_level(model: Model, n_states: int, log: Callable[[str], None] | None = None,
                       seed: int = 11, closed_loop: bool = True) -> dict:
    """Verify ``model.controller.strategy`` over at least ``n_states`` states.

    Returns dict(strategy, states, mismatches, sources, faulted_states,
    mismatches_per_field, first_mismatch, wall_s, states_per_s).
    """
    t0 = time.perf_counter()
    t = derive_three_level(model)
    lib = build_three_level_library(model, t, with_sim=closed_loop)
    parts: dict[str, np.ndarray] = {}
    if closed_loop:
        parts["closed_loop"] = closed_loop_states(model, lib)
    parts["adversarial"] = adversarial_states(model, t, n_target=min(200_000, max(n_states // 5, 1000)))
    n_random = max(n_states - sum(len(p) for p in parts.values()), 0)
    parts["random"] = random_states(model, n_random, seed=seed)
    return compare_batches(t.strategy, parts, lambda x: reference.step_batch(t, x), lib.step_batch,
                           log or (lambda _msg: None), t0).as_dict()


def closed_loop_states(model: Model, lib) -> np.ndarray:
    """Controller inputs recorded from the variant's closed loop at each scenario speed."""
    from ..simulate3l import controller_inputs3, run_closed_loop3

    runs = []
    for speed in scenario_speeds_rpm(model):
        m = model.replace(scenario=dataclasses.replace(model.scenario, speed_ref_rpm=((0.0, speed),)))
        runs.append(controller_inputs3(run_closed_loop3(lib.ffi, lib.lib, m), m))
    return np.concatenate(runs)


def scenario_speeds_rpm(model: Model) -> tuple[float, ...]:
    """Steady-state speeds of the seed-000 scenarios (spec: 300, 1800, 3000 r/min)."""
    return (300.0, 1800.0, 3000.0)
