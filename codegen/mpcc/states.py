"""Adversarial states of the long-horizon step (numerics.md "Test states"), from a topology's random
states: guard limits exactly / one ulp beyond / non-finite, ties (zero current, speed, torque
reference and angle: symmetric lattice points whose sequences tie), the angle-reduction borders, and
every applied switching state with invalid ones beyond.  Deterministic for a seed; vectorised.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from codegen import teststates as common
from codegen.numfmt.float32 import F

__all__ = ["adversarial"]


def adversarial(base: np.ndarray, limits: Sequence[common.Limit], prev_field: str, n_states: int,
                angle_guard: float, table_n: int, seed: int = 7) -> np.ndarray:
    """``base`` (float32 SI input records, modified) turned into adversarial states, a fifth each:
    guard-limit cases, ties, angle borders, every applied state 0..n_states-1 (one in 64 beyond it),
    and zero speed with the torque reference at zero or its extremes."""
    rng = np.random.default_rng(seed)
    x = base.copy()
    n = len(x)
    part = np.arange(n) % 5
    lim = part == 0
    sub = x[lim]
    common.apply_limit_cases(sub, limits, rng)
    x[lim] = sub
    tie = part == 1
    for name in ("ia_a", "ib_a", "omega_e_rad_s", "torque_ref_nm", "theta_e_rad"):
        pick = tie & (rng.random(n) < 0.6)
        x[name][pick] = np.where(rng.random(int(pick.sum())) < 0.5, F(0.0), F(-0.0))
    ang = part == 2
    x["theta_e_rad"][ang] = common.angle_reduction_borders(int(ang.sum()), angle_guard, table_n, rng)
    st = part == 3
    k = int(st.sum())
    x[prev_field][st] = np.where(np.arange(k) % 64 == 63, n_states + rng.integers(0, 4, k), np.arange(k) % n_states)
    slow = part == 4
    x["omega_e_rad_s"][slow] = F(0.0)
    x["torque_ref_nm"][slow] = np.where(rng.random(int(slow.sum())) < 0.5, F(0.0), x["torque_ref_nm"][slow])
    return x
