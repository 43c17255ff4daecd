"""Named constants of a generated step: computed once, printed by the templates, read by the reference."""
from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from codegen.kernels.trig import ANGLE_GUARD_RAD, sincos_constants
from codegen.model import Model
from codegen.numfmt import NumberFormat
from codegen.units import GUARD_UNITS

__all__ = ["Const", "Constants", "guard_limits", "leading_constants", "sector_constants", "fault_action_constants"]


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
    """Input-guard limits (numerics.md "Inputs are guarded"), float64, in guard order.

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
        "ANGLE_GUARD_RAD": ANGLE_GUARD_RAD,
        "OMEGA_GUARD_RAD_S": 5.0 * rated_omega_e,
        "TORQUE_REF_GUARD_NM": 4.0 * max(sl.limit_nm, m.rated_torque_nm),
    }


def leading_constants(nf: NumberFormat, limits: dict[str, float]) -> list[Const]:
    """Constants every step starts with: sin/cos coefficients, guard limits, the Clarke gain."""
    out = [Const(*c) for c in sincos_constants()]
    out += [Const(name, nf.const(v), GUARD_UNITS.get(name, ""), "input guard limit") for name, v in limits.items()]
    out.append(Const("INV_SQRT3", nf.const(1 / math.sqrt(3)), "", "Clarke: i_beta = (i_a + 2 i_b)/sqrt(3)"))
    return out


def sector_constants(nf: NumberFormat) -> list[Const]:
    """The sector-border gains of ``sector.sector12`` (eq. (12))."""
    return [
        Const("TAN30", nf.const(math.tan(math.pi / 6)), "", "sector borders at 30 deg multiples"),
        Const("TAN60", nf.const(math.tan(math.pi / 3)), "", "tan(60 deg): sector borders"),
    ]


def fault_action_constants(model: Model, nf: NumberFormat) -> list[Const]:
    """The constant of ``controller.fault_action`` (none for "gates-off"): for "active-short-circuit"
    the electrical-speed threshold p * asc_min_speed_rpm * 2 pi / 60 of the short circuit,
    computed in float64 and rounded once."""
    c = model.controller
    if c.fault_action != "active-short-circuit":
        return []
    w = model.motor.pole_pairs * c.asc_min_speed_rpm * 2.0 * math.pi / 60.0
    return [Const("ASC_OMEGA_MIN_RAD_S", nf.const(w), "rad/s",
                  "fault: active short circuit at |omega_e| >= this (p * asc_min_speed_rpm), else gates off")]


class HasConsts:
    """Mixin of derived tables that carry their constants as ``consts``."""

    consts: tuple[Const, ...]

    def const(self, name: str) -> Any:
        """Value of the constant ``name``."""
        for c in self.consts:
            if c.name == name:
                return c.value
        raise KeyError(name)
