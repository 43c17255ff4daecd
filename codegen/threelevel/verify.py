"""Verification of the three-level step: compiled C against the Python
reference, bit for bit (numerics.md "Bit-for-bit"), over random and
adversarial states (``states``), in chunks."""
from __future__ import annotations

import time
from typing import Callable

import numpy as np

from ..compare import describe_mismatch, mismatch_mask
from ..model import Model
from . import reference
from .derive import derive_three_level
from .hostbuild import build_three_level_library
from .states import adversarial_states, random_states

CHUNK = 250_000


def verify_three_level(model: Model, n_states: int, log: Callable[[str], None] | None = None,
                       seed: int = 11) -> dict:
    """Verify ``model.controller.strategy`` over at least ``n_states`` states.

    Returns dict(strategy, states, mismatches, sources, faulted_states,
    mismatches_per_field, first_mismatch, wall_s, states_per_s).
    """
    t0 = time.perf_counter()
    t = derive_three_level(model)
    lib = build_three_level_library(model, t)
    parts = {"adversarial": adversarial_states(model, t, n_target=min(200_000, max(n_states // 5, 1000)))}
    n_random = max(n_states - len(parts["adversarial"]), 0)
    parts["random"] = random_states(model, n_random, seed=seed)
    states = np.concatenate(list(parts.values()))
    total = len(states)
    mismatches = faulted = 0
    per_field: dict[str, int] = {}
    first = ""
    for lo in range(0, total, CHUNK):
        x = states[lo: lo + CHUNK]
        ref = reference.step_batch(t, x)
        got = lib.step_batch(x)
        bad, pf = mismatch_mask(ref, got)
        faulted += int((ref["fault"] != 0).sum())
        for k, v in pf.items():
            per_field[k] = per_field.get(k, 0) + v
        nb = int(bad.sum())
        if nb and not first:
            i = int(np.flatnonzero(bad)[0])
            first = f"state #{lo + i}:\n" + describe_mismatch(x[i], ref[i], got[i])
        mismatches += nb
        if log:
            log(f"  {t.strategy:8s} {min(lo + CHUNK, total):>9d}/{total} states, {mismatches} mismatches")
    wall = time.perf_counter() - t0
    return {
        "strategy": t.strategy,
        "states": total,
        "mismatches": mismatches,
        "sources": {k: len(v) for k, v in parts.items()},
        "faulted_states": faulted,
        "mismatches_per_field": per_field,
        "first_mismatch": first,
        "wall_s": wall,
        "states_per_s": total / wall if wall > 0 else 0.0,
    }
