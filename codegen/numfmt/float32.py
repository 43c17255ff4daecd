"""The float32 number format: IEEE-754 binary32, one rounding per operation.

Constants are computed once in float64, rounded once to float32 and emitted
as exact hexadecimal C literals, so the C and the Python reference hold the
same bits.  The reference computes with numpy float32 arrays: every numpy
element-wise operation on float32 operands rounds once, exactly as a C
float operation compiled with ``-ffp-contract=off`` does.  The C side's
spelling of the operations is ``templates/numfmt/float32.j2``.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .lanes import LaneOps
from .opcost import FLOAT_OP_COSTS
from .trigform import SinCosForm

__all__ = ["F", "f32", "c_float_literal", "Float32Ops", "Float32", "FLOAT32"]

#: numpy scalar type of a float32 value (test-state builders; the references use ``Float32Ops``)
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


#: independent operation chains a step interleaves statement by statement: pipelined FPU
#: operations overlap (the T-type step's group costs and its three sin/cos)
INTERLEAVE = 4


class Float32Ops(LaneOps):
    """The reference's arithmetic in float32: each helper is one numpy operation.

    Every element-wise numpy operation on float32 operands rounds once, like
    one C float operation under ``-ffp-contract=off``; operand order is kept
    as written (the helpers never reassociate or fuse).  A fixed-point
    backend provides the same helpers with its own rounding and scaling.
    """

    real = np.float32

    def const(self, x: float) -> np.float32:
        """A literal value of the format (rounded once)."""
        return self.real(x)

    def add(self, a: Any, b: Any) -> Any:
        """a + b, one rounding."""
        return a + b

    def sub(self, a: Any, b: Any) -> Any:
        """a - b, one rounding."""
        return a - b

    def mul(self, a: Any, b: Any) -> Any:
        """a * b, one rounding."""
        return a * b

    def div(self, a: Any, b: Any) -> Any:
        """a / b, one rounding (IEEE division)."""
        return a / b

    def neg(self, a: Any) -> Any:
        """-a (exact)."""
        return -a

    def abs(self, a: Any) -> Any:
        """|a| (exact)."""
        return np.abs(a)

    def sqrt(self, a: Any) -> Any:
        """Square root, correctly rounded."""
        return np.sqrt(a)

    def trunc_int(self, a: Any) -> np.ndarray:
        """Conversion to int32 by truncation toward zero (C's ``(int32_t)x``)."""
        return np.trunc(a).astype(np.int32)

    def round_away(self, a: Any) -> np.ndarray:
        """The nearest integral value, halfway cases away from zero, with the sign of ``a`` (C99's
        ``roundf``).  Exact in the format itself: |a| - floor(|a|) is exact in binary floating point,
        so no sum is rounded (|a| + 0.5 would round up for the largest value below 0.5 in the format,
        e.g. 0.49999997f + 0.5f = 1.0f)."""
        a = np.asarray(a, self.real)
        m = np.abs(a)
        f = np.floor(m)
        return np.copysign(f + (m - f >= 0.5), a).astype(self.real)

    def rank_lt(self, a: Any, b: Any) -> np.ndarray:
        """Cost ranking: ``a`` before ``b`` by their bit patterns as unsigned integers (the C's
        ``rank_key``), the float order for the costs' values (>= +0; a NaN would rank last)."""
        bits = np.dtype(f"u{np.dtype(self.real).itemsize}")
        return np.asarray(np.ascontiguousarray(a, self.real).view(bits) < np.ascontiguousarray(b, self.real).view(bits))

    def from_int(self, n: Any) -> np.ndarray:
        """Conversion of an integer to the format (C's ``(float)n``)."""
        return np.asarray(n).astype(self.real)


@dataclass(frozen=True)
class Float32:
    """The float32 backend of :class:`codegen.numfmt.NumberFormat`."""

    name: str = "float32"
    real_dtype: np.dtype = np.dtype(np.float32)
    bits_dtype: np.dtype = np.dtype(np.uint32)
    c_type: str = "float"
    macros: str = "numfmt/float32.j2"
    value_kind: str = "MPC_VALUE_F32"
    value_reader: str = "mpc_f32_bits"
    ops: Float32Ops = field(default_factory=Float32Ops)
    scaling: Any = None
    quantised: bool = False
    #: |theta_e| <= 256 rad: table index |n| <= 10 430 (codegen.kernels.trig: its Cody-Waite split
    #: keeps fn STEP_HI exact to twice that)
    angle_guard_rad: float = 256.0
    #: sin/cos: a 256-entry table and one polynomial term each (|r| <= pi/256)
    sincos_form: SinCosForm = SinCosForm(256, 1, 1)

    @property
    def op_costs(self) -> dict[str, dict[str, int]]:
        """The cycle bound's instructions per essential operation: one each (``opcost``)."""
        return FLOAT_OP_COSTS

    def const(self, x: float, unit: str = "") -> np.float32:
        return self.real_dtype.type(x)  # type: ignore[no-any-return]

    def encode(self, unit: str, x: Any) -> np.ndarray:
        return np.asarray(x, np.float64).astype(self.real_dtype)

    def decode(self, unit: str, n: Any) -> np.ndarray:
        return np.asarray(n, self.real_dtype).astype(np.float64)

    def scaled(self, scaling: Any) -> Float32:
        return self

    def template_values(self) -> dict[str, object]:
        # float arithmetic is defined for every input (NaN and infinities propagate): the step's
        # arithmetic that needs no guarded value runs ahead of the input guard, overlapping it
        return {"interleave": INTERLEAVE, "ahead_of_guard": True}

    def for_step(self, signals: list[Any], base: Any, global_q: int | None) -> Float32:
        return self

    def literal(self, x: float | np.generic) -> str:
        return c_float_literal(x)  # type: ignore[arg-type]

    def guard_bits(self, x: Any) -> str | None:
        v = np.float32(x)
        if not (np.isfinite(v) and v >= np.finfo(np.float32).tiny):
            return None
        return f"0x{int(v.view(np.uint32)):08X}u"

    def c_value(self, x: float | np.generic) -> str:
        v = float(x)  # type: ignore[arg-type]
        if v != v:
            return "NAN"
        if v in (float("inf"), float("-inf")):
            return "INFINITY" if v > 0 else "-INFINITY"
        return c_float_literal(v)


FLOAT32 = Float32()
