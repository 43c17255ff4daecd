"""Float32 constants: computed once in float64, rounded once, emitted as hex.

numerics.md "Float32 path": gains and reciprocals are computed in Python in
float64, rounded once to float32 and emitted as hexadecimal float literals so
that the C and the Python reference hold the same bits.
"""
from __future__ import annotations

import numpy as np


def f32(x: float) -> np.float32:
    """Round a float64 value once to float32 (round to nearest even)."""
    return np.float32(x)


def c_float_literal(x: float | np.floating) -> str:
    """Exact C99 hexadecimal float literal with the ``f`` suffix, e.g. ``0x1.8p+3f``.

    The value must already be a float32 value; the literal is exact, so the C
    compiler rounds nothing.
    """
    v = float(np.float32(x))
    if v != float(x) and not (np.isnan(v)):
        raise ValueError(f"{x!r} is not a float32 value; round it with f32() first")
    if v == 0.0:
        return "-0x0p+0f" if np.signbit(v) else "0x0p+0f"
    h = v.hex()  # e.g. '0x1.8000000000000p+3'
    mant, exp = h.split("p")
    if "." in mant:
        mant = mant.rstrip("0").rstrip(".")
    return f"{mant}p{exp}f"
