"""The number-format seam: everything that depends on how a real number is stored.

A :class:`NumberFormat` says, for one format, how a real-valued record field
is stored (numpy dtype, C type, bit pattern for comparison), how a constant
is rounded once and printed as a C literal, and which jinja2 macro library
(``templates/numfmt/<name>.j2``) spells its operations in C.  The Python
reference's operation helpers live in the backend module too.  A new format
is a new backend module registered in :data:`FORMATS`, not a branch in the
stages or the topologies: float32 (``float32.py``) and fixed point
(``fixed.py``, with its Q formats from ``scaling.py``).
"""
from __future__ import annotations

from typing import Any, Protocol

import numpy as np

__all__ = ["Ops", "NumberFormat", "number_format", "FORMATS", "CONFIG_FORMATS", "QUANTISED", "FLOAT_CONTROLLER", "IDEAL"]


class Ops(Protocol):
    """The reference's arithmetic in one format: one helper per C operation.

    Kernels and references compute only through these, so the operation
    sequence (and each rounding) is the format's, never numpy's defaults.
    """

    def const(self, x: float) -> Any: ...
    def array(self, values: Any) -> Any: ...
    def zeros(self, shape: Any) -> Any: ...
    def add(self, a: Any, b: Any) -> Any: ...
    def sub(self, a: Any, b: Any) -> Any: ...
    def mul(self, a: Any, b: Any) -> Any: ...
    def div(self, a: Any, b: Any) -> Any: ...
    def neg(self, a: Any) -> Any: ...
    def abs(self, a: Any) -> Any: ...
    def sqrt(self, a: Any) -> Any: ...
    def lt(self, a: Any, b: Any) -> Any: ...
    def le(self, a: Any, b: Any) -> Any: ...
    def gt(self, a: Any, b: Any) -> Any: ...
    def ge(self, a: Any, b: Any) -> Any: ...
    def eq(self, a: Any, b: Any) -> Any: ...
    def ne(self, a: Any, b: Any) -> Any: ...
    def where(self, cond: Any, a: Any, b: Any) -> Any: ...
    def trunc_int(self, a: Any) -> Any: ...
    def round_away(self, a: Any) -> Any: ...
    def rank_lt(self, a: Any, b: Any) -> Any: ...
    def from_int(self, n: Any) -> Any: ...


class NumberFormat(Protocol):
    """What a stage or a topology may ask of a number format."""

    @property
    def name(self) -> str:
        """Config value of ``controller.number_format``."""
        ...

    @property
    def real_dtype(self) -> np.dtype:
        """numpy scalar type of a real value."""
        ...

    @property
    def bits_dtype(self) -> np.dtype:
        """numpy type of a real value's bit pattern (compared for bit-exactness)."""
        ...

    @property
    def c_type(self) -> str:
        """C type of a real value."""
        ...

    @property
    def macros(self) -> str:
        """jinja2 macro library of the format (relative to templates/)."""
        ...

    @property
    def value_kind(self) -> str:
        """The firmware runtime's kind of a flattened real value (``MPC_VALUE_*``, selftest.h)."""
        ...

    @property
    def value_reader(self) -> str:
        """The firmware runtime's function reading a real value as 32 bits (mpc_runtime.h)."""
        ...

    @property
    def quantised(self) -> bool:
        """True for an integer (fixed-point) format: the quantisation report applies to it."""
        ...

    @property
    def angle_guard_rad(self) -> float:
        """Largest |theta_e| the step accepts (the input guard's ANGLE limit), rad."""
        ...

    @property
    def sincos_form(self) -> Any:
        """The shape of the generated sin/cos (``trigform.SinCosForm``: table size, polynomial terms)."""
        ...

    @property
    def op_costs(self) -> dict[str, dict[str, int]]:
        """Per essential operation of the algorithm (``add``, ``mul``, ``cmp``, ``sqrt``, ``div``, ``load``,
        ``store``), the instructions it takes at least in this format, by instruction class
        (``codegen.numfmt.opcost``): the cycle bound of ``mpcgen bench --emulated``."""
        ...

    @property
    def scaling(self) -> Any:
        """The step's Q formats (``scaling.Scaling``) of a fixed-point format; None for float32."""
        ...

    @property
    def ops(self) -> Ops:
        """The reference's operation helpers in this format."""
        ...

    def const(self, x: float, unit: str = "") -> np.generic:
        """Round a float64 constant of ``unit`` once to the format."""
        ...

    def encode(self, unit: str, x: Any) -> np.ndarray:
        """Stored values of SI values ``x`` (float64) of ``unit`` (host-side inputs: states, HIL)."""
        ...

    def decode(self, unit: str, n: Any) -> np.ndarray:
        """SI values (float64) of stored values ``n`` of ``unit``."""
        ...

    def scaled(self, scaling: Any) -> NumberFormat:
        """This format bound to a step's scaling (``codegen.numfmt.scaling``; float32 needs none)."""
        ...

    def template_values(self) -> dict[str, object]:
        """Values the format's macro library and the step templates read from the template context
        (every format gives ``interleave``: the independent chains worth interleaving in a step, and
        ``ahead_of_guard``: whether its arithmetic is defined for unguarded inputs, so that the step's
        arithmetic needing no guarded value may run ahead of the input guard)."""
        ...

    def guard_bits(self, x: Any) -> str | None:
        """The C literal of the bit pattern of guard limit ``x`` (a value of the format) when the
        generated guard may compare bit patterns instead of values (float32: a positive finite
        limit, where |v| <= x is (bits(v) & 0x7FFFFFFF) <= bits(x) for every v, NaN included), else None."""
        ...

    def for_step(self, signals: list[Any], base: Any, global_q: int | None) -> NumberFormat:
        """This format for a step with these signal ranges and constants (``scaling.Signal``) and
        base ranges (``scaling.BaseRanges``); fixed point chooses its Q formats (RepresentationError
        if one does not fit), float32 returns itself."""
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


from .fixed import FIXED  # noqa: E402  (the registry needs the Protocol above)
from .float32 import FLOAT32  # noqa: E402
from .float64 import FLOAT64  # noqa: E402

#: Every number format, by ``controller.number_format`` value (layouts; ``scaled`` binds a step's scaling),
#: and the analysis-only float64 ideal of ``mpcgen report`` (not a config choice).
FORMATS: dict[str, NumberFormat] = {FLOAT32.name: FLOAT32, FIXED.name: FIXED, FLOAT64.name: FLOAT64}
#: the ``controller.number_format`` values a config may choose (float64 is analysis only)
CONFIG_FORMATS: tuple[str, ...] = (FLOAT32.name, FIXED.name)

#: the formats the quantisation report compares, by role: the quantised controller, the float
#: controller it is measured against, and the float64 ideal
QUANTISED, FLOAT_CONTROLLER, IDEAL = FIXED.name, FLOAT32.name, FLOAT64.name
