"""Shared pieces of the long-horizon tests: the example configs and the states they run on."""
from __future__ import annotations

from typing import Any

import numpy as np

from codegen.config import load_config
from codegen.model import Model
from codegen.topology import topology_of

from conftest import EXAMPLES

#: the long-horizon examples by short name
CONFIGS = {"spmsm": EXAMPLES / "mpcc_spmsm.toml", "tlevel": EXAMPLES / "mpcc_tlevel.toml"}


def mpcc_model(config: str, **controller: object) -> Model:
    """A long-horizon example with ``controller.<key>`` overrides."""
    return load_config(CONFIGS[config], {f"controller.{k}": v for k, v in controller.items()})


def built(model: Model) -> tuple[Any, Any, Any]:
    """(plugin, tables, host library) of ``model``."""
    topo = topology_of(model)
    t = topo.derive(model)
    return topo, t, topo.host_library(model, t)


def states(model: Model, tables: Any, n: int, seed: int = 21) -> np.ndarray:
    """``n`` states: four fifths random over the operating range, a fifth adversarial (ties, limits)."""
    topo = topology_of(model)
    n_adv = n // 5
    return np.concatenate([topo.random_states(model, tables, n - n_adv, seed),
                           topo.adversarial_states(model, tables, n_adv)[:n_adv]])


def penalties(tables: Any, x: np.ndarray) -> np.ndarray | None:
    """The reference's neutral-point penalties P(m) (docs/mpcc.md eq. (14)) of the states of ``x`` that
    pass the guard, (n, 8) float32; None for a topology without a midpoint."""
    from codegen.mpcc.reference import solve

    return solve(tables, x)[1]["pen"]


def sequence_digits(seq: np.ndarray, base: int) -> np.ndarray:
    """(n, 3N) position digits of the output's ``seq`` (phase a most significant in each state)."""
    s = np.asarray(seq, np.int64).reshape(len(seq), -1)
    return np.stack([(s // (base * base)) % base, (s // base) % base, s % base], axis=2).reshape(len(s), -1)


def sequence_index(seq: np.ndarray, base: int) -> np.ndarray:
    """The tie-break index sum d_i base^i of each output's ``seq``."""
    d = sequence_digits(seq, base)
    return d @ (base ** np.arange(d.shape[1], dtype=np.int64))
