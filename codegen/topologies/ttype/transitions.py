"""Switching constraint of 63-MPDTC (mpdtc-three-level.md "Switching
constraint"; seed 000 section 2.2, 1), Fig. 5).

A transition from the state applied last to the first state of a candidate is
allowed iff every leg changes by at most one level (|dS_x| <= 1) and every
line voltage changes by at most Udc/2 (|d(S_x - S_y)| <= 1, line voltages in
Udc/2 units).  Consequences: a zero state cannot switch directly to a medium
or large vector; a small state can reach the neighbouring zero, small,
medium and large vectors (the seed's reason for starting every virtual vector
on a small state).

A virtual vector ends in its start state, so what may follow it is what may
follow that state (``may_follow``).  63-MPDTC uses OOO as its zero vector:
PPP and NNN are never candidates (``ZERO_STATE_63``).
"""
from __future__ import annotations

from functools import cache

import numpy as np

from codegen.topologies.ttype import vectors as v
from codegen.topologies.ttype import virtual as vv

#: the only zero state 63-MPDTC applies
ZERO_STATE_63: int = v.OOO


def leg_steps(prev: int, nxt: int) -> tuple[int, int, int]:
    """Change of each leg level (Sa, Sb, Sc), nxt - prev."""
    a, b = v.STATES[prev].levels, v.STATES[nxt].levels
    return (b[0] - a[0], b[1] - a[1], b[2] - a[2])


def line_steps(prev: int, nxt: int) -> tuple[int, int, int]:
    """Change of the line voltages (u_ab, u_bc, u_ca) in units of Udc/2."""
    da, db, dc = leg_steps(prev, nxt)
    return (da - db, db - dc, dc - da)


def state_transition_allowed(prev: int, nxt: int) -> bool:
    """Every leg moves at most one level and every line voltage at most Udc/2."""
    return all(abs(d) <= 1 for d in leg_steps(prev, nxt)) and all(
        abs(d) <= 1 for d in line_steps(prev, nxt))


@cache
def allowed_matrix() -> np.ndarray:
    """27 x 27 bool array, [prev, next] = ``state_transition_allowed``."""
    m = np.zeros((v.N_STATES, v.N_STATES), dtype=bool)
    for p in range(v.N_STATES):
        for n in range(v.N_STATES):
            m[p, n] = state_transition_allowed(p, n)
    m.setflags(write=False)
    return m


def vector_allowed_after_state(prev_state: int, vid: int) -> bool:
    """May vector ``vid`` (0..62) be applied when ``prev_state`` was applied last?"""
    return state_transition_allowed(prev_state, vv.start_state(vid))


def may_follow(prev_vid: int, vid: int) -> bool:
    """May vector ``vid`` follow vector ``prev_vid`` (both in 0..62)?"""
    return vector_allowed_after_state(vv.end_state(prev_vid), vid)


def is_63_candidate(vid: int) -> bool:
    """Member of the 63-MPDTC vector set: not PPP/NNN (OOO is its zero)."""
    if vv.is_virtual(vid):
        return True
    return v.STATES[vid].kind != "zero" or vid == ZERO_STATE_63


def line_jump_max(prev: int, nxt: int) -> int:
    """Largest line-voltage jump in Udc/2 units (27-MPDTC may reach 4 = 2 Udc)."""
    return max(abs(d) for d in line_steps(prev, nxt))
