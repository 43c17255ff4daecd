"""What the user of a fixed-point step needs to fill and read its records: each real field's Q format.

The header (``templates/common/mpc.h.j2``) states per real field of a
fixed-point step its Q format, the value of one count (LSB) in SI units and
the representable range, and ``#define``s the field's fractional bits
(:class:`FieldFormat`); ``mpc_binding.h`` adds integer conversions that
need no double (``templates/common/binding.h.j2``), modelled exactly here:

* :func:`q_from_f32`: a float32 SI value as counts of Q(q): floor(x 2^q +
  1/2) (round half up, the rule of ``Scaling.encode`` and of the step's
  products), saturated to int32, NaN -> 0, from the float's bits alone
  (integer operations only: no FPU, no libm);
* :func:`q_scale`: round-half-up of x k / 2^s for int32 x and k, saturated
  (the ADC conversion: ``<prefix>_<field>_from_adc``, gain k 2^-s SI units
  per ADC count);
* :func:`adc_gain`: the gain's (k, s) for an SI-per-count value, k with 30
  significant bits.

Float formats have no Q formats: :func:`field_formats` gives them nothing, so
the float32 header is unchanged.
"""
from __future__ import annotations

import math
import struct
from collections.abc import Iterable
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

from .scaling import INT32_MAX, INT32_MIN, Scaling

__all__ = ["FieldFormat", "field_formats", "q_from_f32", "q_scale", "adc_gain", "ADC_UNITS", "GAIN_BITS"]

#: units of the input fields a converter samples (currents, voltages): they get an ADC helper
ADC_UNITS = ("A", "V")
#: significant bits of an ADC gain's mantissa k (:func:`adc_gain`)
GAIN_BITS = 30


def _pow2(n: int) -> str:
    return f"2^{n}"


@dataclass(frozen=True)
class FieldFormat:
    """One real field's Q format, as the header prints it (formatted here, once)."""

    name: str
    unit: str  # SI unit ("" dimensionless)
    q: int  # fractional bits: count = SI value x 2^q
    qformat: str  # "Q17.14"
    lsb: str  # "2^-14 A": one count in SI units
    range: str  # "[-131072, 131072) A"
    macro: str  # the field's name in macros: "IA_A"
    adc: bool  # an input a converter samples (unit A or V): the binding has its ADC helper

    @property
    def text(self) -> str:
        """The struct member's comment suffix."""
        return f"int32 count of {self.qformat}: 1 LSB = {self.lsb}, range {self.range}"


def field_formats(scaling: Scaling | None, fields: Iterable[Any], inputs: Iterable[str] = ()) -> dict[str, FieldFormat]:
    """Field name -> :class:`FieldFormat` of every field (``.name``, ``.unit``) under ``scaling``; empty
    without a scaling (a float format).  ``inputs``: the input fields' names (an A or V input gets an
    ADC helper)."""
    if scaling is None:
        return {}
    ins = set(inputs)
    out = {}
    for f in fields:
        q = scaling.q(f.unit)
        unit = f" {f.unit}" if f.unit else ""
        top = 31 - q
        out[f.name] = FieldFormat(f.name, f.unit, q, scaling.describe(f.unit), f"{_pow2(-q)}{unit}",
                                  f"[-{_pow2(top)}, {_pow2(top)}){unit}" if not 0 <= top <= 20
                                  else f"[-{2 ** top}, {2 ** top}){unit}",
                                  f.name.upper(), f.name in ins and f.unit in ADC_UNITS)
    return out


def _sat(n: int) -> tuple[int, bool]:
    if n > INT32_MAX:
        return INT32_MAX, True
    if n < INT32_MIN:
        return INT32_MIN, True
    return n, False


def q_from_f32(x: float, q: int) -> int:
    """floor(x 2^q + 1/2) of the float32 value ``x`` (given as a Python float already in float32),
    saturated to int32; NaN -> 0 (``<prefix>_q_from_f32``)."""
    if math.isnan(x):
        return 0
    if math.isinf(x):
        return INT32_MAX if x > 0 else INT32_MIN
    v = Fraction(x) * Fraction(2) ** q
    return _sat(math.floor(v + Fraction(1, 2)))[0]


def f32_from_bits(bits: int) -> float:
    """The float32 value of a bit pattern, as a Python float."""
    return float(struct.unpack("<f", struct.pack("<I", bits & 0xFFFFFFFF))[0])


def q_scale(x: int, k: int, shift: int) -> tuple[int, bool]:
    """(result, saturated) of floor(x k / 2^shift + 1/2) (shift <= 0: x k 2^-shift exactly), saturated to
    int32 (``<prefix>_q_scale``)."""
    v = Fraction(x * k) / Fraction(2) ** shift
    return _sat(math.floor(v + Fraction(1, 2)))


def adc_gain(si_per_count: float, bits: int = GAIN_BITS) -> tuple[int, int]:
    """(k, s) with k 2^-s the nearest to ``si_per_count`` (> 0) and k of ``bits`` significant bits:
    the gain argument of ``<prefix>_<field>_from_adc``."""
    if not si_per_count > 0 or not math.isfinite(si_per_count):
        raise ValueError(f"an ADC gain must be a positive finite number, got {si_per_count!r}")
    s = bits - math.frexp(si_per_count)[1]
    k = math.floor(Fraction(si_per_count) * Fraction(2) ** s + Fraction(1, 2))
    if k >= 2 ** bits:
        k, s = k // 2, s - 1
    return k, s
