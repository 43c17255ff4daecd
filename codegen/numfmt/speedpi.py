"""The integer speed PI of a fixed-point step: its constants (derived once) and its Python reference.

A fixed-point build's ``<prefix>_speed_pi.c`` is integer C in the step's Q
formats: the speeds are int32 counts of the step's rad/s format, the torque
reference an int32 count of its N*m format (the step's ``torque_ref_nm``).
The operations are those of the float32 PI and of the simulator's float64 PI
(``codegen/simulator/csrc/speed_pi.c``), with the same anti-windup:

    e = sat(w_ref - w_m)
    u = sat(sat(kp e) + integral)          kp e: floor(KP_K e / 2^KP_S + 1/2)
    T* = u clamped to +-L
    unless (u > L and e > 0) or (u < -L and e < 0):
        integral = clamp(sat(integral + sat(ki dt e)), -L, L)

Each gain is a mantissa K (at most :data:`GAIN_BITS` significant bits) and a
shift S: the gain from the input's counts to the output's counts is
K 2^-S; a product is formed in int64 and rounded half up (the step's rule),
every sum saturates to int32.  :class:`FixedSpeedPI` refuses
(:class:`RepresentationError`, naming the config field) a gain or a limit the
formats cannot hold.
"""
from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from .scaling import INT32_MAX, INT32_MIN, MIN_CONST_BITS, RepresentationError, Scaling

__all__ = ["FixedSpeedPI", "GAIN_BITS", "MAX_SHIFT"]

#: significant bits of a gain's mantissa
GAIN_BITS = 30
#: largest shift of a gain (int64 products: |K e| < 2^61, plus the rounding half)
MAX_SHIFT = 62


def _sat(x: int) -> int:
    return min(max(x, INT32_MIN), INT32_MAX)


def _gain(g: Fraction, field: str, what: str, speed_fmt: str, torque_fmt: str) -> tuple[int, int]:
    """(K, S) with K 2^-S nearest ``g`` (>= 0), K of at most GAIN_BITS bits; RepresentationError if S
    would leave [0, MAX_SHIFT] (a gain that needs a left shift, or one too small to keep its bits)."""
    if g == 0:
        return 0, 0
    if g < 0:
        raise RepresentationError(what, field, f"the speed PI's {what} must not be negative, got {float(g):.6g}")
    s = GAIN_BITS - 1 - math.floor(math.log2(g))  # then corrected: K = g 2^s in [2^(GAIN_BITS-1), 2^GAIN_BITS)
    while g * Fraction(2) ** s >= 2**GAIN_BITS:
        s -= 1
    while g * Fraction(2) ** s < 2 ** (GAIN_BITS - 1):
        s += 1
    s = min(s, MAX_SHIFT)  # a tiny gain keeps fewer bits (checked below)
    k = math.floor(g * Fraction(2) ** s + Fraction(1, 2))
    if k >= 2**GAIN_BITS:
        k, s = k // 2, s - 1
    if s < 0 or k < 2 ** (MIN_CONST_BITS - 1):
        raise RepresentationError(what, field, (
            f"the fixed-point speed PI's {what} = {float(g):.6g} torque counts per speed count "
            + (f"needs a left shift of {-s}" if s < 0 else f"keeps {k} counts (< 2^{MIN_CONST_BITS - 1}) at shift {s}")
            + f" (speed {speed_fmt}, torque {torque_fmt})"))
    return k, s


def _round_shift(p: int, s: int) -> int:
    """floor(p / 2^s + 1/2) (s = 0: p)."""
    return p if s == 0 else (p + (1 << (s - 1))) >> s


@dataclass(frozen=True)
class FixedSpeedPI:
    """The integer PI's constants: gains (K, S), the clamp L (N*m counts), and the Q formats."""

    kp_k: int
    kp_s: int
    ki_k: int
    ki_s: int
    limit: int
    q_speed: int  # fractional bits of rad/s
    q_torque: int  # fractional bits of N*m
    speed_format: str  # "Q9.22"
    torque_format: str

    @classmethod
    def of(cls, kp: float, ki_dt: float, limit_nm: float, scaling: Scaling) -> FixedSpeedPI:
        """The PI of gains ``kp`` (N*m s/rad), ``ki_dt`` (ki dt, N*m/rad) and clamp ``limit_nm`` in the
        Q formats of ``scaling``."""
        qw, qt = scaling.q("rad/s"), scaling.q("N*m")
        conv = Fraction(2) ** (qt - qw)
        fmts = scaling.describe("rad/s"), scaling.describe("N*m")
        kp_k, kp_s = _gain(Fraction(kp) * conv, "speed_loop.kp", "kp", *fmts)
        ki_k, ki_s = _gain(Fraction(ki_dt) * conv, "speed_loop.ki", "ki dt", *fmts)
        lim = scaling.const(limit_nm, "N*m")
        if not 0 < lim <= INT32_MAX // 2:
            raise RepresentationError("speed_loop.limit_nm", "speed_loop.limit_nm", (
                f"the speed PI's clamp {limit_nm:.6g} N*m is {lim} counts of {scaling.describe('N*m')}: "
                f"it must lie in 1 .. {INT32_MAX // 2} (a margin of 2 below the int32 range)"))
        return cls(kp_k, kp_s, ki_k, ki_s, lim, qw, qt, scaling.describe("rad/s"), scaling.describe("N*m"))

    def step(self, integral: int, w_ref: int, w_m: int) -> tuple[int, int]:
        """One period: (torque reference, new integral), every value an int32 count."""
        lim = self.limit
        e = _sat(w_ref - w_m)
        u = _sat(_sat(_round_shift(self.kp_k * e, self.kp_s)) + integral)
        t = lim if u > lim else (-lim if u < -lim else u)
        if not ((u > lim and e > 0) or (u < -lim and e < 0)):
            i_new = _sat(integral + _sat(_round_shift(self.ki_k * e, self.ki_s)))
            integral = lim if i_new > lim else (-lim if i_new < -lim else i_new)
        return t, integral

    def run(self, w_ref: Iterable[int], w_m: Iterable[int], integral: int = 0) -> np.ndarray:
        """The torque references (int32) of a sequence of periods, from ``integral``."""
        out = []
        for r, w in zip(w_ref, w_m):
            t, integral = self.step(integral, int(r), int(w))
            out.append(t)
        return np.asarray(out, np.int32)

    def template_values(self) -> dict[str, object]:
        """What ``templates/common/speed_pi.*.j2`` print for the integer PI (``pi``)."""
        return {"pi": self, "number_format": "fixed", "real": "int32_t"}
