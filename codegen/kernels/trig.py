"""Generated sin/cos of the rotor angle (numerics.md "Float32 path").

The step needs sin and cos of theta_e without libm trigonometry (its one libm function is the exact
``roundf``, one VRINTA on the Cortex-M7).  The generator emits a
fixed sequence of single float32 operations; ``sincos_f32`` below performs
the same sequence in numpy float32, so the C and the reference agree bit for
bit, and the accuracy of the approximation is a separately tested property.

Algorithm (per numerics.md: explicit range reduction, then polynomials):

1. quadrant   y = x * (2/pi);  fn = round(y) (nearest, halfway away from zero), n = (int)fn
2. Cody-Waite r = (x - n*PIO2_HI) - n*PIO2_LO, |r| <= pi/4 (+ rounding);
   PIO2_HI has few enough significant bits that n*PIO2_HI is exact for
   |n| <= 2^(24 - PIO2_HI_BITS).
3. sin r = r + r^3 (S1 + r^2 (S2 + r^2 S3)),
   cos r = 1 + r^2 (C1 + r^2 (C2 + r^2 (C3 + r^2 C4)))   (Horner)
4. quadrant q = n mod 4 selects (sin, cos) = (s, c), (c, -s), (-s, -c), (-c, s).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from codegen.numfmt import Ops
from codegen.numfmt.float32 import FLOAT32, f32

#: essential operations of one generated sin/cos, for the cycle bound (``Topology.essential_ops``):
#: range reduction (8), odd polynomial (7), even polynomial (8), quadrant select (4); its 9 constants
SINCOS_FP, SINCOS_LOADS = 27, 9
#: Largest |theta_e| the step accepts (rad); beyond it the input guard trips.
ANGLE_GUARD_RAD = FLOAT32.angle_guard_rad
_PIO2_HI_BITS = 15  # n <= 2^(24-15) = 512 > 256 * 2/pi + 1


@dataclass(frozen=True)
class SinCosCoeffs:
    """Float32 constants of the generated sin/cos (all exact float32 values)."""

    two_over_pi: np.float32
    pio2_hi: np.float32
    pio2_lo: np.float32
    s: tuple[np.float32, np.float32, np.float32]  # r^3, r^5, r^7
    c: tuple[np.float32, np.float32, np.float32, np.float32]  # r^2 .. r^8


def _split_pio2() -> tuple[float, float]:
    hi = math.pi / 2
    m, e = math.frexp(hi)
    scale = 2.0 ** _PIO2_HI_BITS
    hi_trunc = math.floor(m * scale) / scale * 2.0**e
    return hi_trunc, math.pi / 2 - hi_trunc


def _fit(func, powers: list[int], lead: float) -> np.ndarray:
    """Least-squares fit on Chebyshev nodes of [0, pi/4] (close to minimax).

    Fits func(r) - lead-term by sum(c_k r^k) with the given powers, in float64.
    """
    k = np.arange(4000)
    r = (np.pi / 8) * (1 - np.cos((k + 0.5) * np.pi / len(k)))  # nodes in [0, pi/4]
    r = r[r > 0]
    a = np.stack([r**p for p in powers], axis=1)
    rhs = func(r) - lead * (r if lead and powers[0] % 2 == 1 else 1.0)
    # relative weighting: minimise relative error of the correction
    coef, *_ = np.linalg.lstsq(a, rhs, rcond=None)
    return coef


@lru_cache(maxsize=1)
def sincos_coeffs64() -> tuple[float, ...]:
    """The constants of the generated sin/cos in float64, derived once (the float64 fit), in the order
    2/pi, PIO2_HI, PIO2_LO, S3, S5, S7, C2, C4, C6, C8: every number format rounds them once."""
    hi, lo = _split_pio2()
    s = _fit(np.sin, [3, 5, 7], 1.0)
    c = _fit(lambda r: np.cos(r) - 1.0, [2, 4, 6, 8], 0.0)
    return (2.0 / math.pi, hi, lo, *(float(v) for v in s), *(float(v) for v in c))


@lru_cache(maxsize=1)
def sincos_coeffs() -> SinCosCoeffs:
    """The coefficients rounded once to float32 (the float32 step's; tests and ``sincos_f32``)."""
    v = [f32(x) for x in sincos_coeffs64()]
    return SinCosCoeffs(two_over_pi=v[0], pio2_hi=v[1], pio2_lo=v[2], s=(v[3], v[4], v[5]), c=(v[6], v[7], v[8], v[9]))


def _horner(ops: Any, coeffs: Any, x: Any) -> Any:
    """(((c_n x + c_{n-1}) x + ...) + c_0) x, lowest coefficient first in ``coeffs``: the operation
    order of the C polynomials (one multiply and one add per coefficient)."""
    p = ops.mul(coeffs[-1], x)
    for c in reversed(coeffs[:-1]):
        p = ops.add(p, c)
        p = ops.mul(p, x)
    return p


def coeffs_of(k: Any) -> SinCosCoeffs:
    """The coefficients as a step's constants hold them (``k.TWO_OVER_PI`` ...: in the step's format)."""
    return SinCosCoeffs(k.TWO_OVER_PI, k.PIO2_HI, k.PIO2_LO, (k.SIN_S3, k.SIN_S5, k.SIN_S7),
                        (k.COS_C2, k.COS_C4, k.COS_C6, k.COS_C8))


def sincos(ops: Ops, x: Any, consts: Any) -> tuple[Any, Any]:
    """sin and cos of ``x`` through the format's ``ops``: the exact operation sequence of the C
    (``templates/common/kernels.j2`` ``sincos_fn``).  ``consts``: the step's constants
    (``Constants``; their sin/cos coefficients in the format)."""
    return _sincos(ops, x, coeffs_of(consts))


def _sincos(ops: Ops, x: Any, k: SinCosCoeffs) -> tuple[Any, Any]:
    x = ops.array(x)
    y = ops.mul(x, k.two_over_pi)
    fn = ops.round_away(y)
    n = ops.trunc_int(fn)
    t = ops.mul(fn, k.pio2_hi)
    r = ops.sub(x, t)
    t = ops.mul(fn, k.pio2_lo)
    r = ops.sub(r, t)
    r2 = ops.mul(r, r)
    ps = ops.mul(_horner(ops, k.s, r2), r)  # (S3 + S5 r^2 + S7 r^4) r^2 r
    sr = ops.add(r, ps)
    cr = ops.add(ops.const(1.0), _horner(ops, k.c, r2))  # 1 + (C2 + C4 r^2 + C6 r^4 + C8 r^6) r^2
    q = n & 3
    quadrant = [q == 0, q == 1, q == 2]
    s_out = ops.select(quadrant, [sr, cr, ops.neg(sr)], ops.neg(cr))
    c_out = ops.select(quadrant, [cr, ops.neg(sr), ops.neg(cr)], sr)
    return s_out, c_out


def sincos_f32(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """sin and cos of float32 ``x``, the exact operation sequence of the C."""
    return _sincos(FLOAT32.ops, x, sincos_coeffs())


def sincos_constants() -> list[tuple[str, float, str, str]]:
    """(name, float64 value, unit, meaning) of every constant the generated sin/cos uses (the step's
    number format rounds each once)."""
    names = [
        ("TWO_OVER_PI", "1/rad", "2/pi: quadrant of theta_e"),
        ("PIO2_HI", "rad", "pi/2, high part (Cody-Waite)"),
        ("PIO2_LO", "rad", "pi/2 - PIO2_HI"),
        ("SIN_S3", "", "sin r = r + r^3 (S3 + r^2 (S5 + r^2 S7))"),
        ("SIN_S5", "", "sin coefficient of r^5 (least squares on [0, pi/4])"),
        ("SIN_S7", "", "sin coefficient of r^7"),
        ("COS_C2", "", "cos r = 1 + r^2 (C2 + r^2 (C4 + r^2 (C6 + r^2 C8)))"),
        ("COS_C4", "", "cos coefficient of r^4"),
        ("COS_C6", "", "cos coefficient of r^6"),
        ("COS_C8", "", "cos coefficient of r^8"),
    ]
    return [(n, v, u, d) for (n, u, d), v in zip(names, sincos_coeffs64())]
