"""The float32 number format: IEEE-754 binary32, one rounding per operation.

Constants are computed once in float64, rounded once to float32 and emitted
as exact hexadecimal C literals, so the C and the Python reference hold the
same bits.  The reference computes with numpy float32 arrays: every numpy
element-wise operation on float32 operands rounds once, exactly as a C
float operation compiled with ``-ffp-contract=off`` does.  The C side's
spelling of the operations is ``templates/numfmt/float32.j2``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["F", "f32", "c_float_literal", "Float32", "FLOAT32"]

#: numpy scalar type of a float32 value (the reference's working type)
F = np.float32


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


@dataclass(frozen=True)
class Float32:
    """The float32 backend of :class:`codegen.numfmt.NumberFormat`."""

    name: str = "float32"
    real_dtype: np.dtype = np.dtype(np.float32)
    bits_dtype: np.dtype = np.dtype(np.uint32)
    c_type: str = "float"
    macros: str = "numfmt/float32.j2"

    def const(self, x: float) -> np.float32:
        return f32(x)

    def literal(self, x: float | np.generic) -> str:
        return c_float_literal(x)  # type: ignore[arg-type]

    def c_value(self, x: float | np.generic) -> str:
        v = float(x)  # type: ignore[arg-type]
        if v != v:
            return "NAN"
        if v in (float("inf"), float("-inf")):
            return "INFINITY" if v > 0 else "-INFINITY"
        return c_float_literal(v)


FLOAT32 = Float32()
