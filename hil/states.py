"""The states a replay sends: recorded closed-loop, random and adversarial, per source."""
from __future__ import annotations

from typing import Any

import numpy as np

from codegen.model import Model
from codegen.stages.fwdata import in_step_format, trajectory_states
from codegen.topology import topology_of

__all__ = ["SOURCES", "replay_states", "index_ranges", "mask_of_ranges"]

#: state sources, in replay order
SOURCES = ("closed_loop", "random", "adversarial")


def replay_states(model: Model, tables: Any, n: int, seed: int = 1,
                  sources: tuple[str, ...] = SOURCES) -> dict[str, np.ndarray]:
    """``n`` states in all, shared between the sources: the topology's recorded closed-loop run
    (evenly sampled), random states over the operating range, adversarial states (borders, ties,
    guard limits).  A source that yields fewer than its share leaves the rest to the random states."""
    topo = topology_of(model)
    out: dict[str, np.ndarray] = {}
    share = {src: n // len(sources) + (1 if i < n % len(sources) else 0) for i, src in enumerate(sources)}
    for src in sorted(sources, key=lambda s: s == "random"):  # random last: it takes what is left
        n = share[src] + (0 if src != "random" else sum(share[s] - len(out[s]) for s in out))
        if src == "closed_loop":
            out[src] = in_step_format(model, tables, trajectory_states(model, n))
        elif src == "random":
            out[src] = topo.random_states(model, tables, n, seed)
        elif src == "adversarial":
            out[src] = topo.adversarial_states(model, tables, max(n, 1000))[:n]
        else:
            raise ValueError(f"unknown state source {src!r}; allowed: {', '.join(SOURCES)}")
    return out


def index_ranges(mask: np.ndarray) -> list[list[int]]:
    """The runs of True in a bool array as inclusive ``[first, last]`` index pairs."""
    idx = np.flatnonzero(np.asarray(mask, bool))
    if len(idx) == 0:
        return []
    breaks = np.flatnonzero(np.diff(idx) != 1)
    firsts = np.concatenate([idx[:1], idx[breaks + 1]])
    lasts = np.concatenate([idx[breaks], idx[-1:]])
    return [[int(a), int(b)] for a, b in zip(firsts, lasts)]


def mask_of_ranges(ranges: list[list[int]], n: int) -> np.ndarray:
    """The bool array of length ``n`` True on the inclusive ``[first, last]`` pairs; ValueError if one
    is not a pair of indices in range, in order."""
    mask = np.zeros(n, bool)
    for r in ranges:
        if (not isinstance(r, list) or len(r) != 2 or not all(isinstance(v, int) for v in r)
                or not 0 <= r[0] <= r[1] < n):
            raise ValueError(f"range {r!r} is not [first, last] within 0..{n - 1}")
        mask[r[0]:r[1] + 1] = True
    return mask
