"""An analysis-only float64 number format: the ideal the fixed-point report measures against.

Not a config choice (``codegen.numfmt.CONFIG_FORMATS`` does not list it) and
without a C spelling: the topology's Python reference runs in it, one float64
rounding per operation, to give ``mpcgen report`` its float64 ideal.  Its
angle guard is the fixed-point format's, so the ideal trips its guard where
the fixed-point step does.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .fixed import FIXED
from .float32 import Float32, Float32Ops

__all__ = ["Float64Ops", "Float64", "FLOAT64"]


class Float64Ops(Float32Ops):
    """The reference's arithmetic in float64 (analysis only): one float64 rounding per operation."""

    real = np.float64  # type: ignore[assignment]


@dataclass(frozen=True)
class Float64(Float32):
    """An analysis-only float64 backend of :class:`codegen.numfmt.NumberFormat` (no C spelling): the
    float32 backend with float64 storage and operations."""

    name: str = "float64"
    real_dtype: np.dtype = np.dtype(np.float64)
    bits_dtype: np.dtype = np.dtype(np.uint64)
    c_type: str = "double"
    macros: str = ""
    value_kind: str = "MPC_VALUE_F64"
    value_reader: str = ""
    ops: Float64Ops = field(default_factory=Float64Ops)
    #: the fixed-point step's angle guard, so the ideal trips where the fixed step does
    angle_guard_rad: float = FIXED.angle_guard_rad

    def literal(self, x: float | np.generic) -> str:
        return repr(float(x))  # type: ignore[arg-type]

    def guard_bits(self, x: Any) -> str | None:
        return None  # no C spelling

    def c_value(self, x: float | np.generic) -> str:
        return self.literal(x)


FLOAT64 = Float64()
