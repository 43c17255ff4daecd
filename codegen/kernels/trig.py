"""Generated sin/cos of the rotor angle (numerics.md "Float32 path").

The step needs sin and cos of theta_e without libm trigonometry (its one libm function is the exact
``roundf``, one VRINTA on the Cortex-M7).  The generator emits a
fixed sequence of single operations; ``sincos`` below performs the same
sequence through the format's operations, so the C and the reference agree bit
for bit, and the accuracy of the approximation is a separately tested property.

Algorithm (per numerics.md: explicit range reduction, then polynomials), with a table of sin and
cos at the N multiples of 2 pi / N (``SinCosForm.table_n``, a number-format property):

1. index      y = x * N/(2 pi);  fn = round(y) (nearest, halfway away from zero), n = (int)fn,
              k = n mod N (two's complement: the low bits of n)
2. Cody-Waite r = (x - fn STEP_HI) - fn STEP_LO, |r| <= pi/N (+ rounding);
   STEP_HI has few enough significant bits that fn STEP_HI is exact for every |n| the guard lets in
3. sin r = r + r^3 (S3 + r^2 (S5 + ...)),  cos r = 1 + r^2 (C2 + r^2 (C4 + ...))  (Horner)
4. angle sum  sin x = sin_k cos r + cos_k sin r,  cos x = cos_k cos r - sin_k sin r

float32: N = 256, so |r| <= pi/256 and one term each suffices (a 2 KB table instead of a
degree-8 polynomial and a quadrant select); fixed point: N = 4, the quadrant (the table's 0 and
+-1 make step 4 exact, and y stays within the per-unit range), with three and four terms.
"""
from __future__ import annotations

import math
from functools import cache
from typing import Any

import numpy as np

from codegen.numfmt import NumberFormat, Ops
from codegen.numfmt.float32 import FLOAT32
from codegen.numfmt.trigform import SinCosForm

#: Largest |theta_e| the float32 step accepts (rad); beyond it the input guard trips.
ANGLE_GUARD_RAD = FLOAT32.angle_guard_rad
#: the split of STEP_HI keeps at most this many significant bits (float32 has 24)
_MAX_HI_BITS = 15


def table_index_bound(nf: NumberFormat, angle_max_rad: float | None = None) -> int:
    """The largest |n| = round(|x| N / (2 pi)) for |x| up to ``angle_max_rad`` (default: the format's
    angle guard)."""
    x = nf.angle_guard_rad if angle_max_rad is None else angle_max_rad
    return math.floor(x * nf.sincos_form.table_n / (2.0 * math.pi) + 0.5)


def _split_step(nf: NumberFormat) -> tuple[float, float]:
    """2 pi / N as HI + LO, HI with 23 - bits(n_max) significant bits (at most ``_MAX_HI_BITS``): fn HI
    is exact in float32 for |n| < 2^(24 - HI bits), twice the guard's n_max and more (the T-type's
    extrapolated angles go a little beyond the guard)."""
    step = 2.0 * math.pi / nf.sincos_form.table_n
    bits = min(_MAX_HI_BITS, 23 - table_index_bound(nf).bit_length())
    m, e = math.frexp(step)
    hi = math.floor(m * 2.0**bits) / 2.0**bits * 2.0**e
    return hi, step - hi


def _fit(func: Any, powers: list[int], r_max: float) -> np.ndarray:
    """Least-squares fit on Chebyshev nodes of [0, r_max] (close to minimax), float64: func(r) as
    sum(c_k r^k) over ``powers`` (the callers pass sin r - r and cos r - 1)."""
    k = np.arange(4000)
    r = (r_max / 2) * (1 - np.cos((k + 0.5) * np.pi / len(k)))
    r = r[r > 0]
    a = np.stack([r**p for p in powers], axis=1)
    coef, *_ = np.linalg.lstsq(a, func(r), rcond=None)
    return coef


@cache
def _coeffs64(table_n: int, sin_terms: int, cos_terms: int) -> tuple[tuple[float, ...], tuple[float, ...]]:
    r_max = math.pi / table_n
    s = _fit(lambda r: np.sin(r) - r, [2 * i + 3 for i in range(sin_terms)], r_max)
    c = _fit(lambda r: np.cos(r) - 1.0, [2 * i + 2 for i in range(cos_terms)], r_max)
    return tuple(float(v) for v in s), tuple(float(v) for v in c)


def sin_names(form: SinCosForm) -> list[str]:
    """Names of the sin coefficients, lowest power first (SIN_S3, SIN_S5, ...)."""
    return [f"SIN_S{2 * i + 3}" for i in range(form.sin_terms)]


def cos_names(form: SinCosForm) -> list[str]:
    """Names of the cos coefficients, lowest power first (COS_C2, COS_C4, ...)."""
    return [f"COS_C{2 * i + 2}" for i in range(form.cos_terms)]


def _nested(names: list[str]) -> str:
    """Horner text of coefficients ``names`` (lowest power first) in r^2: S3 + r^2 (S5 + r^2 S7)."""
    if len(names) == 1:
        return names[0]
    rest = _nested(names[1:])
    return f"{names[0]} + r^2 " + (rest if len(names) == 2 else f"({rest})")


def poly_text(form: SinCosForm) -> tuple[str, str]:
    """The polynomials of ``form`` as comments print them: sin r = r + r^3 (...), cos r = 1 + r^2 (...)."""
    s = _nested([n[4:] for n in sin_names(form)])
    c = _nested([n[4:] for n in cos_names(form)])
    paren = lambda t: t if " " not in t else f"({t})"  # noqa: E731
    return f"sin r = r + r^3 {paren(s)}", f"cos r = 1 + r^2 {paren(c)}"


def horner_order(coeffs: Any) -> tuple[Any, list[Any]]:
    """(leading coefficient, the others in the order Horner adds them) of ``coeffs`` (lowest power
    first): the C's and the reference's polynomial order."""
    return coeffs[-1], list(reversed(coeffs[:-1]))


def sincos_constants(nf: NumberFormat) -> list[tuple[str, float, str, str]]:
    """(name, float64 value, unit, meaning) of every constant the generated sin/cos of format ``nf``
    uses (the format rounds each once)."""
    f = nf.sincos_form
    hi, lo = _split_step(nf)
    s, c = _coeffs64(f.table_n, f.sin_terms, f.cos_terms)
    out = [
        ("SINCOS_PER_RAD", f.table_n / (2.0 * math.pi), "1/rad", f"N/(2 pi), N = {f.table_n}: table index of theta_e"),
        ("SINCOS_STEP_HI", hi, "rad", "2 pi/N, high part (Cody-Waite: fn STEP_HI exact)"),
        ("SINCOS_STEP_LO", lo, "rad", "2 pi/N - SINCOS_STEP_HI"),
    ]
    sin_t, cos_t = poly_text(f)
    out += [(n, v, "", f"{sin_t}: r^{n[5:]} (least squares on [0, pi/N])") for n, v in zip(sin_names(f), s)]
    out += [(n, v, "", f"{cos_t}: r^{n[5:]} (least squares on [0, pi/N])") for n, v in zip(cos_names(f), c)]
    return out


def sincos_table(nf: NumberFormat) -> tuple[Any, ...]:
    """sin and cos of 2 pi k / N for k = 0 .. N-1, interleaved (sin_0, cos_0, sin_1, ...), each rounded
    once to the format ``nf`` (a scaled format for fixed point)."""
    n = nf.sincos_form.table_n
    return tuple(nf.const(f(2.0 * math.pi * k / n), "") for k in range(n) for f in (math.sin, math.cos))


#: essential operations of one generated sin/cos besides its polynomials, for the cycle bound
#: (``Topology.essential_ops``): products y, the Cody-Waite pair (2), r^2, the angle sum's four; sums and
#: other writes round, convert, the Cody-Waite pair (2), 1 + ..., r + ..., the angle sum's two; loads: 3
#: constants besides the coefficients, and the two table values
_SINCOS_MUL_BASE, _SINCOS_ADD_BASE, _SINCOS_CONST_LOADS, SINCOS_TABLE_LOADS = 8, 8, 3, 2


def sincos_ops(nf: NumberFormat) -> tuple[dict[str, int], int]:
    """(``{"add": sums and other writes, "mul": products}``, constant loads) of one generated sin/cos in
    format ``nf`` (the cycle bound); each angle adds ``SINCOS_TABLE_LOADS`` table loads, while angles of
    one step share the constants."""
    f = nf.sincos_form
    # Horner: n products and n - 1 sums a polynomial of n terms; and x r for sin
    mul = _SINCOS_MUL_BASE + f.sin_terms + f.cos_terms + 1
    add = _SINCOS_ADD_BASE + f.sin_terms + f.cos_terms - 2
    return {"add": add, "mul": mul}, _SINCOS_CONST_LOADS + f.sin_terms + f.cos_terms


def _horner(ops: Ops, coeffs: Any, x: Any) -> Any:
    """(((c_n x + c_{n-1}) x + ...) + c_0) x, lowest coefficient first in ``coeffs``: the operation
    order of the C polynomials (``horner_order``: n multiplies and n - 1 adds)."""
    lead, rest = horner_order(coeffs)
    p = ops.mul(lead, x)
    for c in rest:
        p = ops.add(p, c)
        p = ops.mul(p, x)
    return p


def sincos(ops: Ops, x: Any, consts: Any, table: Any, form: SinCosForm) -> tuple[Any, Any]:
    """sin and cos of ``x`` through the format's ``ops``: the exact operation sequence of the C
    (``templates/common/kernels.j2`` ``sincos_fn``).  ``consts``: the step's constants
    (``Constants``, in the format), ``table``: ``sincos_table`` of the format, ``form``: its
    ``SinCosForm``."""
    k = consts
    tab = np.asarray(table)
    x = ops.array(x)
    y = ops.mul(x, k.SINCOS_PER_RAD)
    fn = ops.round_away(y)
    n = ops.trunc_int(fn)
    i = (np.asarray(n, np.int64) & (form.table_n - 1)) * 2
    t = ops.mul(fn, k.SINCOS_STEP_HI)
    r = ops.sub(x, t)
    t = ops.mul(fn, k.SINCOS_STEP_LO)
    r = ops.sub(r, t)
    rr = ops.mul(r, r)
    ps = ops.mul(_horner(ops, [k[name] for name in sin_names(form)], rr), r)
    sr = ops.add(r, ps)
    cr = ops.add(ops.const(1.0), _horner(ops, [k[name] for name in cos_names(form)], rr))
    sk, ck = tab[i], tab[i + 1]
    s_out = ops.add(ops.mul(sk, cr), ops.mul(ck, sr))
    c_out = ops.sub(ops.mul(ck, cr), ops.mul(sk, sr))
    return s_out, c_out


@cache
def _f32_parts() -> tuple[Any, tuple[Any, ...]]:
    from codegen.kernels.consts import Const, Constants, in_format

    return Constants(in_format(FLOAT32, (Const(*c) for c in sincos_constants(FLOAT32)))), sincos_table(FLOAT32)


def sincos_f32(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """sin and cos of float32 ``x``, the exact operation sequence of the float32 C (constants and
    table rounded once, on the first call)."""
    k, table = _f32_parts()
    return sincos(FLOAT32.ops, x, k, table, FLOAT32.sincos_form)
