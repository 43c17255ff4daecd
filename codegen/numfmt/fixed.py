"""The fixed-point number format: int32 storage, int64 intermediates, scaled per-unit Q formats.

A real value is an int32 count in the Q format of its unit
(``codegen.numfmt.scaling``): every value of the step shares the fractional
bit count ``G`` of its per-unit value, so one integer operation per C
operation serves every unit.  Each operation has one defined rounding and
saturates to int32 (numerics.md "Fixed-point path"):

=========  ==============================================================
add, sub   ``sat(a +- b)``
neg, abs   ``sat(-a)``, ``sat(|a|)`` (``-INT32_MIN`` saturates)
mul        ``sat(floor((a*b + 2^(G-1)) / 2^G))``: round half up
div        ``sat(floor((a*2^G)/b + 1/2))``, sign of ``b`` folded into the
           numerator; ``b == 0`` gives 0 (the step never divides by 0)
sqrt       ``floor(sqrt(a * 2^G))`` exactly (``a <= 0`` gives 0), by the C's CLZ-seeded
           Newton steps (:func:`isqrt_q`)
trunc_int  ``a / 2^G`` truncated toward zero (C's integer division)
from_int   ``sat(n * 2^G)``
=========  ==============================================================

``FixedOps`` models each with numpy int64, exactly; the C spelling is
``templates/numfmt/fixed.j2``: small helper functions on 32-bit operations
(a sum with an overflow test, a product as one 32x32->64 multiply and a
shift of its two words, a quotient and a square root by 32-bit divisions:
no 64-bit run-time routine on a 32-bit core), with no undefined or
implementation-defined behaviour (no signed overflow, no shift of a
negative value, no out-of-range conversion to a signed type).  The square
root is the one operation whose C steps the reference repeats
(:func:`isqrt_q`); the others are defined by their results, which the C
reaches by other means (tests/numfmt/test_fixed_fast.py checks them bit for
bit).

:func:`count_saturations` records, while it is active, which lanes each
saturating operation saturated, per call site of the reference (the
quantisation report and ``verify`` count the states that saturate each one).
"""
from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .lanes import LaneOps
from .opcost import FIXED_OP_COSTS
from .scaling import INT32_MAX, INT32_MIN, BaseRanges, Scaling, Signal, choose_scaling
from .trigform import SinCosForm

__all__ = ["FixedOps", "Fixed", "FIXED", "isqrt64", "isqrt32_newton", "isqrt_q", "clz32", "SaturationCount",
           "count_saturations"]


class SaturationCount:
    """Which states saturated each saturating operation of a reference run over ``n`` states.

    ``sites``: per call site (``"q_div at ttype/reference.py:236"``: the C helper's name and the
    reference line that calls the operation, outside the format's own modules), a boolean array over
    the states: True where some lane of that state saturated (its exact int64 result lay outside
    int32).  Lanes are the reference's: a batch's leading axis is the state, further axes (the
    candidates) are reduced; an operation on a value with no state axis (constants) marks every state.
    """

    def __init__(self, n: int) -> None:
        self.n = n
        self.sites: dict[str, np.ndarray] = {}

    def note(self, op: str, exact: np.ndarray) -> None:
        """Record the lanes of ``exact`` (the operation's int64 result before saturation) outside int32."""
        over = (exact < INT32_MIN) | (exact > INT32_MAX)
        if not over.any():
            return
        per_state: np.ndarray
        if over.ndim >= 1 and over.shape[0] == self.n:
            per_state = np.asarray(over.reshape(self.n, -1).any(axis=1))
        else:
            per_state = np.ones(self.n, bool)
        key = f"q_{op} at {_call_site()}"
        seen = self.sites.get(key)
        self.sites[key] = per_state if seen is None else np.asarray(seen | per_state)

    def counts(self, among: np.ndarray | None = None) -> dict[str, int]:
        """States per site that saturated, among the states ``among`` (a boolean mask; every state for
        None), sites in name order, sites with no such state left out."""
        out = {}
        for key in sorted(self.sites):
            k = int((self.sites[key] & among).sum()) if among is not None else int(self.sites[key].sum())
            if k:
                out[key] = k
        return out


#: the active recorder of :func:`count_saturations` (None: operations are not watched)
_RECORDER: list[SaturationCount] = []
#: the format's own modules: a call site is the first frame outside them
_OWN = (os.path.dirname(os.path.abspath(__file__)),)


def _call_site() -> str:
    """``dir/file.py:line`` of the innermost caller outside codegen/numfmt (the reference's line)."""
    f = sys._getframe(2)
    while f is not None and os.path.dirname(os.path.abspath(f.f_code.co_filename)) in _OWN:
        f = f.f_back  # type: ignore[assignment]
    if f is None:
        return "?"
    path = os.path.abspath(f.f_code.co_filename)
    return f"{os.path.basename(os.path.dirname(path))}/{os.path.basename(path)}:{f.f_lineno}"


@contextlib.contextmanager
def count_saturations(n: int) -> Iterator[SaturationCount]:
    """While active, every saturating operation of :class:`FixedOps` on a batch of ``n`` states is
    recorded (:class:`SaturationCount`); not reentrant."""
    rec = SaturationCount(n)
    _RECORDER.append(rec)
    try:
        yield rec
    finally:
        _RECORDER.remove(rec)


def _sat(x: Any, op: str = "") -> np.ndarray:
    x = np.asarray(x, np.int64)
    if _RECORDER and op:
        _RECORDER[-1].note(op, x)
    return np.clip(x, INT32_MIN, INT32_MAX).astype(np.int32)


def _i64(x: Any) -> np.ndarray:
    return np.asarray(x, np.int64)


def isqrt64(x: Any) -> np.ndarray:
    """floor(sqrt(x)) of non-negative int64 values below 2^62, exactly (float estimate, then corrected)."""
    x = _i64(x)
    r = np.floor(np.sqrt(x.astype(np.float64))).astype(np.int64)
    for _ in range(2):  # the float estimate is off by at most one
        r = np.where(r * r > x, r - 1, r)
        r = np.where((r + 1) * (r + 1) <= x, r + 1, r)
    return r


def clz32(x: Any) -> np.ndarray:
    """Leading zero bits of uint32 values 1 <= x < 2^32 (C ``__builtin_clz``), exactly: the binary
    exponent of x as a float64 (exact below 2^53)."""
    _, e = np.frexp(np.asarray(x, np.int64).astype(np.float64))
    return (32 - e).astype(np.int64)


def isqrt32_newton(an: Any) -> np.ndarray:
    """floor(sqrt(an)) of 2^30 <= an < 2^32 by the C's ``q_isqrt32``: the tangent of sqrt at 2^31 as the
    seed, two Newton steps, the result capped at 2^16 - 1 and corrected once (exact: checked
    over the whole range, tests/numfmt/test_fixed_fast.py)."""
    an = _i64(an)
    y = (((an >> 16) * 46341) >> 16) + 23171
    y = (y + an // y) >> 1
    y = (y + an // y) >> 1
    y = np.minimum(y, 0xFFFF)
    return np.where(y * y > an, y - 1, y)


def isqrt_q(a: Any, g: int) -> np.ndarray:
    """floor(sqrt(a * 2^g)) of int32 counts ``a`` (0 for a <= 0), 8 <= g <= 30, by the C's ``q_sqrt``:
    a 2^g scaled by an even power of two 2^k to an * 2^30 with 2^30 <= an < 2^32 (k from the CLZ of
    a), s = floor(sqrt(an)), one Newton step on an * 2^30 from s * 2^15, shifted back by k/2 and
    corrected once.  Exact floor(sqrt) for every int32 (the Newton step from below the root lands on
    the floor or one above it)."""
    a = _i64(a)
    pos = a > 0
    a1 = np.where(pos, a, 1)
    m = clz32(a1)
    m = m - ((m ^ g) & 1)
    an = a1 << m
    s = isqrt32_newton(an)
    t = (s << 15) + (((an - s * s) << 14) // s)
    t = t >> ((m + 30 - g) >> 1)
    t = np.where(t * t > (a1 << g), t - 1, t)
    return np.where(pos, t, 0)


class FixedOps(LaneOps):
    """The reference's arithmetic in the fixed-point format: numpy int64, saturated to int32."""

    real = np.int32

    def __init__(self, scaling: Scaling) -> None:
        self.g = scaling.frac_bits
        self.scaling = scaling
        self.one = np.int64(1) << self.g
        self.half = np.int64(1) << (self.g - 1)

    def const(self, x: float) -> np.int32:
        """A dimensionless literal (round half up)."""
        return np.int32(self.scaling.const(x, ""))

    def add(self, a: Any, b: Any) -> np.ndarray:
        return _sat(_i64(a) + _i64(b), "add")

    def sub(self, a: Any, b: Any) -> np.ndarray:
        return _sat(_i64(a) - _i64(b), "sub")

    def mul(self, a: Any, b: Any) -> np.ndarray:
        # numpy's >> on int64 is an arithmetic shift: floor division by 2^G
        return _sat((_i64(a) * _i64(b) + self.half) >> self.g, "mul")

    def div(self, a: Any, b: Any) -> np.ndarray:
        a, b = np.broadcast_arrays(_i64(a), _i64(b))
        n = np.where(b < 0, -a, a) * self.one
        d = np.abs(b)
        safe = np.where(d == 0, 1, d)
        q = np.floor_divide(2 * n + safe, 2 * safe)
        return _sat(np.where(d == 0, 0, q), "div")

    def neg(self, a: Any) -> np.ndarray:
        return _sat(-_i64(a), "neg")

    def abs(self, a: Any) -> np.ndarray:
        return _sat(np.abs(_i64(a)), "abs")

    def sqrt(self, a: Any) -> np.ndarray:
        return _sat(isqrt_q(a, self.g), "sqrt")

    def trunc_int(self, a: Any) -> np.ndarray:
        a = _i64(a)
        m = np.abs(a) >> self.g
        return np.where(a < 0, -m, m).astype(np.int32)

    def from_int(self, n: Any) -> np.ndarray:
        return _sat(_i64(n) << self.g, "from_int")

    def rank_lt(self, a: Any, b: Any) -> np.ndarray:
        """Cost ranking: the counts' order."""
        return self.lt(a, b)

    def round_away(self, a: Any) -> np.ndarray:
        """The nearest integer (in the format), halfway cases away from zero: a +- 1/2 truncated."""
        half = self.const(0.5)
        return self.from_int(self.trunc_int(self.add(a, self.where(self.ge(a, 0), half, self.neg(half)))))


@dataclass(frozen=True)
class Fixed:
    """The fixed-point backend of :class:`codegen.numfmt.NumberFormat`.

    Without a scaling it gives the layouts only (dtypes, C types, value kinds:
    the records, the wire schema); :meth:`scaled` binds the step's
    :class:`Scaling`, which the constants, the encodings and the ops need.
    """

    scaling: Scaling | None = None
    name: str = "fixed"
    real_dtype: np.dtype = np.dtype(np.int32)
    bits_dtype: np.dtype = np.dtype(np.uint32)
    c_type: str = "int32_t"
    macros: str = "numfmt/fixed.j2"
    value_kind: str = "MPC_VALUE_I32"
    value_reader: str = "mpc_i32_value"
    quantised: bool = True
    #: |theta_e| <= 8 rad (a wrapped angle, and its extrapolation by two periods): the angle is a
    #: dimensionless per-unit value, so a wide guard would cost every dimensionless signal its bits
    angle_guard_rad: float = 8.0
    #: sin/cos: the quadrant (table of 4: y = theta 2/pi stays small) and a degree-7/8 polynomial
    sincos_form: SinCosForm = SinCosForm(4, 3, 4)
    _ops: list[Any] = field(default_factory=list, compare=False, repr=False)

    @property
    def op_costs(self) -> dict[str, dict[str, int]]:
        """The cycle bound's integer instructions per essential operation: each helper's shortest
        sequence (``opcost``)."""
        return FIXED_OP_COSTS

    def for_step(self, signals: list[Signal], base: BaseRanges, global_q: int | None) -> Fixed:
        return Fixed(choose_scaling(signals, base, global_q))

    def scaled(self, scaling: Scaling | None) -> Fixed:
        if scaling is None:
            raise ValueError("the fixed-point format needs the step's scaling (derived with its tables)")
        return Fixed(scaling)

    def _sc(self) -> Scaling:
        if self.scaling is None:
            raise ValueError("fixed-point values need the step's scaling; use the derived tables' format")
        return self.scaling

    @property
    def ops(self) -> FixedOps:
        if not self._ops:
            self._ops.append(FixedOps(self._sc()))
        return self._ops[0]

    def const(self, x: float, unit: str = "") -> np.int32:
        if x == 0.0:
            return np.int32(0)
        return np.int32(self._sc().const(x, unit))

    def literal(self, x: float | np.generic) -> str:
        return f"INT32_C({int(x)})" if int(x) != INT32_MIN else "(-INT32_C(2147483647) - 1)"  # type: ignore[arg-type]

    def c_value(self, x: float | np.generic) -> str:
        return self.literal(x)

    def guard_bits(self, x: Any) -> str | None:
        return None  # the counts are integers already: the guard compares them

    def encode(self, unit: str, x: Any) -> np.ndarray:
        return self._sc().encode(unit, x)

    def decode(self, unit: str, n: Any) -> np.ndarray:
        return self._sc().decode(unit, n)

    def template_values(self) -> dict[str, object]:
        sc = self._sc()
        return {"interleave": 1,  # the int64 helpers gain nothing from interleaved chains (more spills)
                "ahead_of_guard": False,  # integer arithmetic on unguarded inputs could overflow
                "q_frac_bits": sc.frac_bits,
                "q_lits": {"0.5": self.literal(sc.const(0.5, "")),
                           "1": self.literal(sc.const(1.0, ""))}}


FIXED = Fixed()
