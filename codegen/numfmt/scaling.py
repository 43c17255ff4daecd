"""Q formats of the fixed-point step: one power-of-two base per base unit, derived from the config.

Every real value of the fixed-point step is an int32 ``n`` standing for
``n * 2^(e(u) - G)`` in SI units, where ``u`` is the value's unit, ``G`` the
step's fractional bits and ``2^e(u)`` the unit's base: the value is stored in
Q(G - e(u)).  ``e`` is additive over the base units V, A, s
(``codegen.numfmt.units``), so the product of a current and a flux is a
torque with no rescaling, and every operation of the step is the same
integer operation whatever its operands' units: a product shifts right by
``G``, a sum adds (the scaled per-unit system of drive firmware, with
power-of-two bases).

Choice (per-signal formats, the default):

* current base from the trip current ``i_trip_a``; time base from the speed
  guard (``1/|omega_e|max``, so a speed fits); voltage base from the largest
  of ``udc_max_v`` and the flux bound over the time base, so a flux
  ``psi_f + L i_trip`` fits too;
* ``G`` = 31 - 1 (margin) - the integer bits of the largest scaled value
  among every signal range and constant of the step, at most 30.

Global Q (IQmath style, ``controller.fixed_q = N``): every base is 1 (values
in SI units in Q``N``); a signal whose range does not fit is a config error.

Either way a constant that would keep fewer than :data:`MIN_CONST_BITS`
significant bits, or a signal whose scaled range needs more than 30 integer
bits, is a config error naming the signal, its range and the format.
"""
from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .units import parse_unit

__all__ = ["Signal", "BaseRanges", "Scaling", "RepresentationError", "MIN_CONST_BITS", "MIN_FRAC_BITS", "choose_scaling"]

#: a nonzero constant must keep at least this many significant bits (relative error <= 2^-(n+1))
MIN_CONST_BITS = 10
#: per-signal formats: at least this many fractional bits of the per-unit values
MIN_FRAC_BITS = 12
#: largest fractional bit count (sqrt shifts an int32 left by G into an int64)
MAX_FRAC_BITS = 30
INT32_MIN, INT32_MAX = -(2**31), 2**31 - 1


class RepresentationError(ValueError):
    """A signal or constant of the step cannot be represented in the fixed-point format.

    ``signal``, ``field``: the offending value's name and the config field it comes from.  What a fix
    must achieve: ``culprit`` is the range signal that has to shrink (the offending range itself; for
    a constant left with too few bits, the largest scaled range, which set the resolution, when
    shrinking it could free the bits; else None) and ``limit_abs`` the largest ``culprit.max_abs``
    (SI) that would fit, everything else equal (an estimate: the bases move with the ranges).
    ``bits_short``: for a constant, the significant bits it lacks; ``max_abs``: the offending value's
    largest magnitude (SI).
    """

    def __init__(self, signal: str, field: str, text: str, culprit: Signal | None = None,
                 limit_abs: float | None = None, bits_short: int = 0, max_abs: float = math.nan) -> None:
        self.signal, self.field = signal, field
        self.culprit, self.limit_abs, self.bits_short, self.max_abs = culprit, limit_abs, bits_short, max_abs
        super().__init__(text)


@dataclass(frozen=True)
class Signal:
    """A value of the step with its unit and largest magnitude (float64, SI), and the config field it
    comes from (named by a representation error).  ``exact``: a constant (checked for significant bits)."""

    name: str
    unit: str
    max_abs: float
    field: str = "controller.number_format"
    exact: bool = False


@dataclass(frozen=True)
class BaseRanges:
    """The ranges (float64, SI) the per-signal bases are chosen from."""

    i_max_a: float
    u_max_v: float
    omega_max_rad_s: float
    flux_max_wb: float


@dataclass(frozen=True)
class Scaling:
    """Fractional bits ``frac_bits`` (G) and base exponents (V, A, s) of a fixed-point step."""

    frac_bits: int
    exps: tuple[int, int, int]
    mode: str  # "per-signal" | "global"

    def exp(self, unit: str) -> int:
        """Base exponent e(unit): the unit's base is 2^e."""
        d = parse_unit(unit)
        return sum(a * b for a, b in zip(d, self.exps))

    def q(self, unit: str) -> int:
        """Fractional bits of a value of ``unit`` in SI units: G - e(unit)."""
        return self.frac_bits - self.exp(unit)

    def resolution(self, unit: str) -> float:
        """One count, in SI units."""
        return math.ldexp(1.0, -self.q(unit))

    def largest(self, unit: str) -> float:
        """Largest representable magnitude, in SI units."""
        return INT32_MAX * self.resolution(unit)

    def describe(self, unit: str) -> str:
        """``Qm.n`` of a value of ``unit``: m integer bits (sign excluded), n fractional bits."""
        n = self.q(unit)
        return f"Q{31 - n}.{n}" if n >= 0 else f"Q{31 - n}.{n} (counts of 2^{-n})"

    def encode(self, unit: str, x: object) -> np.ndarray:
        """int32 counts of SI values ``x``: round half up, saturated; NaN -> 0 (a fixed-point input
        cannot be NaN).  C: ``mpc_q_from_double`` of the format's headers."""
        v = np.asarray(x, np.float64) * math.ldexp(1.0, self.q(unit))
        v = np.floor(np.where(np.isnan(v), 0.0, v) + 0.5)
        return np.clip(v, INT32_MIN, INT32_MAX).astype(np.int32)

    def decode(self, unit: str, n: object) -> np.ndarray:
        """SI values (float64) of int32 counts ``n`` (exact)."""
        return np.asarray(n, np.float64) * self.resolution(unit)

    def const(self, x: float, unit: str) -> int:
        """The count nearest ``x`` (round half up), saturated to int32."""
        return int(self.encode(unit, float(x)))


def _int_bits(pu: float) -> int:
    """Integer bits (sign excluded) a scaled magnitude ``pu`` needs: ceil(log2(pu)), >= 0."""
    return max(0, math.ceil(math.log2(pu))) if pu > 0 else 0


def _check(s: Signal, sc: Scaling, widest: Signal | None = None) -> None:
    """RepresentationError if ``s`` does not fit ``sc`` (margin 2) or, as a constant, keeps too few bits
    (``widest``: the largest scaled range signal, the one that set the fractional bits)."""
    fmt = sc.describe(s.unit)
    unit = f" {s.unit}" if s.unit else ""
    if s.max_abs * 2.0 > sc.largest(s.unit):
        raise RepresentationError(s.name, s.field, (
            f"signal {s.name} (|x| up to {s.max_abs:.6g}{unit}, with margin 2: {2 * s.max_abs:.6g}) does not fit "
            f"{fmt} (|x| < {sc.largest(s.unit):.6g}{unit})"), None if s.exact else s, sc.largest(s.unit) / 2.0,
            max_abs=s.max_abs)
    if s.exact and s.max_abs > 0.0:
        counts = s.max_abs / sc.resolution(s.unit)
        if counts < 2.0 ** (MIN_CONST_BITS - 1):
            short = (MIN_CONST_BITS - 1) - math.floor(math.log2(max(counts, 2.0 ** -60)))
            # per-signal formats: a smaller widest range leaves more fractional bits, up to MAX_FRAC_BITS
            freeable = sc.mode == "per-signal" and widest is not None and sc.frac_bits + short <= MAX_FRAC_BITS
            raise RepresentationError(s.name, s.field, (
                f"constant {s.name} = {s.max_abs:.6g}{unit} keeps {max(counts, 0):.3g} counts "
                f"(< 2^{MIN_CONST_BITS - 1}) in {fmt} (resolution {sc.resolution(s.unit):.3g}{unit})"),
                widest if freeable else None, math.ldexp(widest.max_abs, -short) if freeable and widest else None,
                short, s.max_abs)


#: how far the search moves each base exponent from its natural choice
_SEARCH = 8


def _natural_bases(base: BaseRanges) -> tuple[int, int, int]:
    """(e_V, e_A, e_s) with the trip current, the DC link and the speed guard each within their base."""
    e_a = _int_bits(base.i_max_a)
    e_s = -_int_bits(base.omega_max_rad_s)
    e_v = max(_int_bits(base.u_max_v), _int_bits(base.flux_max_wb) - e_s)
    return e_v, e_a, e_s


def _best_bases(sigs: list[Signal], base: BaseRanges) -> tuple[tuple[int, int, int], int, Signal]:
    """The base exponents (e_V, e_A, e_s) within +-_SEARCH of the natural ones that need the fewest
    integer bits for the largest scaled signal; ties: the most significant bits for the smallest
    nonzero constant, then the natural choice.  Returns (exponents, integer bits, the largest signal)."""
    dims = np.array([parse_unit(s.unit) for s in sigs], np.int64)
    logs = np.array([math.log2(s.max_abs) if s.max_abs > 0 else -np.inf for s in sigs])
    exact = np.array([s.exact and s.max_abs > 0 for s in sigs])
    nat = np.array(_natural_bases(base))
    best: tuple[Any, ...] | None = None
    rng = range(-_SEARCH, _SEARCH + 1)
    for dv in rng:
        for da in rng:
            for ds in rng:
                e = nat + np.array([dv, da, ds])
                scaled = logs - dims @ e
                # integer bits such that every scaled magnitude is below 2^need: a magnitude of exactly
                # 2^n needs n + 1 (the largest count is 2^31 - 1, not 2^31)
                need = max(0, math.floor(float(np.max(scaled))) + 1)
                small = float(np.min(scaled[exact])) if exact.any() else 0.0
                key = (need, -small, abs(dv) + abs(da) + abs(ds))
                if best is None or key < best[0]:
                    best = (key, tuple(int(v) for v in e), need, int(np.argmax(scaled)))
    assert best is not None
    return best[1], best[2], sigs[best[3]]


def choose_scaling(signals: Iterable[Signal], base: BaseRanges, global_q: int | None = None) -> Scaling:
    """The step's scaling from its signals (every range and constant) and the ranges that fix the
    bases; ``global_q``: IQmath-style global Q (all bases 1).  RepresentationError if a signal does not fit."""
    sigs = list(signals)
    if global_q is not None:
        sc = Scaling(global_q, (0, 0, 0), "global")
    else:
        exps, need, worst = _best_bases(sigs, base)
        g = min(MAX_FRAC_BITS, 31 - 1 - need)
        sc = Scaling(g, exps, "per-signal")
        if g < MIN_FRAC_BITS:
            raise RepresentationError(worst.name, worst.field, (
                f"signal {worst.name} (|x| up to {worst.max_abs:.6g}{' ' + worst.unit if worst.unit else ''}) "
                f"needs {need} integer bits "
                f"of the per-unit format: {g} fractional bits left, fewer than {MIN_FRAC_BITS}"),
                None if worst.exact else worst, math.ldexp(worst.max_abs, g - MIN_FRAC_BITS), max_abs=worst.max_abs)
    ranges = [s for s in sigs if not s.exact and s.max_abs > 0]
    widest = max(ranges, key=lambda s: s.max_abs / sc.largest(s.unit)) if ranges else None
    # the worst offender first: ranges beyond the format by how far, then constants by fewest counts
    for s in sorted(sigs, key=lambda s: (-(s.max_abs / sc.largest(s.unit)),
                                         s.max_abs / sc.resolution(s.unit) if s.exact and s.max_abs > 0 else 1e300)):
        _check(s, sc, widest)
    return sc


