"""The shape of a number format's generated sin/cos (``codegen.kernels.trig``)."""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["SinCosForm"]


@dataclass(frozen=True)
class SinCosForm:
    """A table of sin and cos at ``table_n`` (a power of two) multiples of 2 pi / ``table_n``, and
    the polynomial terms of sin r and cos r on |r| <= pi / ``table_n`` beyond r and 1."""

    table_n: int
    sin_terms: int
    cos_terms: int
