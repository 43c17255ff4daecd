"""The number-format seam: everything that depends on how a real number is stored.

A :class:`NumberFormat` says, for one format, how a real-valued record field
is stored (numpy dtype, C type, bit pattern for comparison), how a constant
is rounded once and printed as a C literal, and which jinja2 macro library
(``templates/numfmt/<name>.j2``) spells its operations in C.  The Python
reference's operation helpers live in the backend module too.  A new format
(fixed point) is a new backend module registered in :data:`FORMATS`, not a
branch in the stages or the topologies.
"""
from __future__ import annotations

from typing import Protocol

import numpy as np

__all__ = ["NumberFormat", "number_format", "FORMATS"]


class NumberFormat(Protocol):
    """What a stage or a topology may ask of a number format."""

    #: config value of ``controller.number_format``
    name: str
    #: numpy scalar type of a real value, and of its bit pattern
    real_dtype: np.dtype
    bits_dtype: np.dtype
    #: C type of a real value
    c_type: str
    #: jinja2 macro library of the format (relative to templates/)
    macros: str

    def const(self, x: float) -> np.generic:
        """Round a float64 constant once to the format."""
        ...

    def literal(self, x: float | np.generic) -> str:
        """Exact C literal of a value already in the format."""
        ...

    def c_value(self, x: float | np.generic) -> str:
        """C initializer of one stored value (non-finite values included, for test data)."""
        ...


def number_format(name: str) -> NumberFormat:
    """The backend of ``name``; ValueError naming the formats for any other name."""
    try:
        return FORMATS[name]
    except KeyError:
        raise ValueError(f"unknown number format {name!r}; allowed: {', '.join(FORMATS)}") from None


from .float32 import FLOAT32  # noqa: E402  (the registry needs the Protocol above)

#: Every number format, by ``controller.number_format`` value.
FORMATS: dict[str, NumberFormat] = {FLOAT32.name: FLOAT32}
