"""The states a replay sends: recorded closed-loop, random and adversarial, per source."""
from __future__ import annotations

from typing import Any

import numpy as np

from codegen.model import Model
from codegen.stages.fwdata import in_step_format, trajectory_states
from codegen.topology import topology_of

__all__ = ["SOURCES", "replay_states"]

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
