"""The states a replay sends: recorded closed-loop, random and adversarial, per source."""
from __future__ import annotations

from typing import Any

import numpy as np

from codegen.model import Model
from codegen.stages.fwdata import trajectory_states
from codegen.topology import topology_of

__all__ = ["SOURCES", "replay_states"]

#: state sources, in replay order
SOURCES = ("closed_loop", "random", "adversarial")


def replay_states(model: Model, tables: Any, n: int, seed: int = 1,
                  sources: tuple[str, ...] = SOURCES) -> dict[str, np.ndarray]:
    """About ``n`` states of each source: the topology's recorded closed-loop run (evenly sampled),
    random states over the operating range, adversarial states (borders, ties, guard limits)."""
    topo = topology_of(model)
    out: dict[str, np.ndarray] = {}
    for src in sources:
        if src == "closed_loop":
            out[src] = trajectory_states(model, n)
        elif src == "random":
            out[src] = topo.random_states(model, n, seed)
        elif src == "adversarial":
            out[src] = topo.adversarial_states(model, tables, n)[:n]
        else:
            raise ValueError(f"unknown state source {src!r}; allowed: {', '.join(SOURCES)}")
    return out
