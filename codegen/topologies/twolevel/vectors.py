"""Two-level inverter vector set (mptc-two-level.md "Conventions").

Switching state of a leg: 1 = upper switch on.  A state is encoded as
``sw = Sa*4 + Sb*2 + Sc``.  V0 = 000 or 111, V1 = 100, V2 = 110, V3 = 010,
V4 = 011, V5 = 001, V6 = 101; Vn points at (n-1)*60 deg with amplitude
2*Udc/3 (amplitude-invariant space vector u = 2/3*Udc*(Sa + a*Sb + a^2*Sc)).
"""
from __future__ import annotations

import numpy as np

#: switching state of V0..V6 (V0 listed as 000; 111 is chosen at run time)
VEC_TO_SW: tuple[int, ...] = (0b000, 0b100, 0b110, 0b010, 0b011, 0b001, 0b101)


def sw_to_vec() -> tuple[int, ...]:
    """Vector index of each of the 8 switching states (000 and 111 -> V0)."""
    table = [0] * 8
    for v, sw in enumerate(VEC_TO_SW):
        table[sw] = v
    table[0b111] = 0
    return tuple(table)


def zero_state_after(prev_sw: int) -> int:
    """Zero-vector realisation that changes fewer legs than ``prev_sw`` (tie: 000)."""
    legs_on = bin(prev_sw).count("1")
    return 0b111 if (3 - legs_on) < legs_on else 0b000


def zero_sw_table() -> tuple[int, ...]:
    """``zero_state_after`` for every previous state 0..7."""
    return tuple(zero_state_after(s) for s in range(8))


def unit_vectors() -> tuple[np.ndarray, np.ndarray]:
    """alpha/beta components of Vn / (2*Udc/3), float64, n = 0..6.

    Computed from the switching states with the space-vector definition, not
    typed in: u = (2/3)(Sa + a Sb + a^2 Sc) with a = exp(j 2 pi / 3), divided by
    2/3 so that an active vector has unit length.
    """
    a = np.exp(2j * np.pi / 3)
    z = []
    for sw in VEC_TO_SW:
        sa, sb, sc = (sw >> 2) & 1, (sw >> 1) & 1, sw & 1
        z.append(sa + a * sb + a * a * sc)
    zz = np.array(z)
    ux, uy = zz.real.copy(), zz.imag.copy()
    # exact zeros where the geometry has them (cancellation leaves ~1e-17)
    ux[np.abs(ux) < 1e-12] = 0.0
    uy[np.abs(uy) < 1e-12] = 0.0
    return ux, uy
