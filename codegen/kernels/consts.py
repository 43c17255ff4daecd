"""Named constants of a generated step: computed once, printed by the templates, read by the reference."""
from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from codegen.kernels.trig import sincos_constants
from codegen.model import SPEED_GUARD_PER_RATED, Model
from codegen.numfmt import NumberFormat, number_format
from codegen.units import GUARD_UNITS

__all__ = ["Const", "Constants", "guard_limits", "in_format", "leading_constants", "sector_constants",
           "fault_action_constants"]


@dataclass(frozen=True)
class Const:
    """One constant of the step, in the step's number format, with its unit and meaning."""

    name: str
    value: Any
    unit: str
    doc: str


class Constants:
    """Attribute and item access to a step's constants by name (``k.LD_H``, ``k["LD_H"]``)."""

    def __init__(self, consts: Iterable[Const]) -> None:
        for c in consts:
            setattr(self, c.name, c.value)

    def __getitem__(self, name: str) -> Any:
        return getattr(self, name)

    def __getattr__(self, name: str) -> Any:
        """Typing aid (constants are set per step); an unknown name is an AttributeError naming it."""
        raise AttributeError(f"no constant {name!r} in this step")


def guard_limits(model: Model, dc_min: str, dc_max: str, dc_scale: float) -> dict[str, float]:
    """Input-guard limits (numerics.md "Input guard and safe decision"), float64, in guard order.

    The DC-link limits are ``inverter.udc_min_v`` / ``udc_max_v`` times
    ``dc_scale`` under the names ``dc_min`` / ``dc_max`` (a split DC link
    guards each capacitor at half the limits).
    """
    m, inv, sl = model.motor, model.inverter, model.speed_loop
    rated_omega_e = m.rated_speed_rpm * 2 * math.pi / 60 * m.pole_pairs
    return {
        "I_TRIP_A": inv.i_trip_a,
        dc_min: inv.udc_min_v * dc_scale,
        dc_max: inv.udc_max_v * dc_scale,
        "ANGLE_GUARD_RAD": number_format(model.controller.number_format).angle_guard_rad,
        "OMEGA_GUARD_RAD_S": SPEED_GUARD_PER_RATED * rated_omega_e,
        "TORQUE_REF_GUARD_NM": 4.0 * max(sl.limit_nm, m.rated_torque_nm),
    }


def in_format(nf: NumberFormat, consts: Iterable[Const]) -> tuple[Const, ...]:
    """The constants (float64 values) rounded once to the step's format ``nf``, by their units."""
    return tuple(Const(c.name, nf.const(float(c.value), c.unit), c.unit, c.doc) for c in consts)


def leading_constants(limits: dict[str, float], nf: NumberFormat) -> list[Const]:
    """Constants every step starts with (float64 values; ``in_format`` rounds them): the sin/cos
    constants of the step's format ``nf``, guard limits, the Clarke gain."""
    out = [Const(*c) for c in sincos_constants(nf)]
    out += [Const(name, float(v), GUARD_UNITS.get(name, ""), "input guard limit") for name, v in limits.items()]
    out.append(Const("INV_SQRT3", 1 / math.sqrt(3), "", "Clarke: i_beta = (i_a + 2 i_b)/sqrt(3)"))
    return out


def sector_constants() -> list[Const]:
    """The sector-border gains of ``sector.sector12`` (eq. (12)), float64."""
    return [
        Const("TAN30", math.tan(math.pi / 6), "", "sector borders at 30 deg multiples"),
        Const("TAN60", math.tan(math.pi / 3), "", "tan(60 deg): sector borders"),
    ]


def fault_action_constants(model: Model) -> list[Const]:
    """The constant of ``controller.fault_action`` (none for "gates-off"): for "active-short-circuit"
    the electrical-speed threshold p * asc_min_speed_rpm * 2 pi / 60 of the short circuit (float64)."""
    c = model.controller
    if c.fault_action != "active-short-circuit":
        return []
    w = model.motor.pole_pairs * c.asc_min_speed_rpm * 2.0 * math.pi / 60.0
    return [Const("ASC_OMEGA_MIN_RAD_S", w, "rad/s",
                  "fault: active short circuit at |omega_e| >= this (p * asc_min_speed_rpm), else gates off")]


class HasConsts:
    """Mixin of derived tables that carry their constants as ``consts``, their number format's
    name ``number_format`` and its ``scaling`` (fixed point; None for float32)."""

    consts: tuple[Const, ...]
    number_format: str
    scaling: Any

    @property
    def nf(self) -> NumberFormat:
        """The step's number format, bound to its scaling."""
        return number_format(self.number_format).scaled(self.scaling)

    def const(self, name: str) -> Any:
        """Value of the constant ``name``."""
        for c in self.consts:
            if c.name == name:
                return c.value
        raise KeyError(name)
