"""The T-type MPDTC's part of the configuration (loaded by :mod:`codegen.config` through the registry).

Its strategies, the config fields only the T-type has (DC-link capacitors,
the cost weights of eq. (7), the T_N clamp), the common fields whose allowed
values it narrows (the MPDTC step always compensates the one-period delay;
the paper's Table 5 run set), and its consistency checks.  A field listed
here is refused in a config of another topology.
"""
from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import NoReturn

from codegen.config import BOOL, Ref, Spec, choice_spec, closed, open_closed, real_spec
from codegen.model import Model
from codegen.operating import Finding, above_rated_finding

__all__ = ["strategies", "fields", "narrowed", "check", "operating_findings", "resolve"]

#: every strategy, in report order; the first is the baseline the others are compared to
strategies: tuple[str, ...] = ("mpdtc27", "mpdtc63")

#: the T-type's own fields (eq. (7) weights, eq. (10)-(11) T_N clamp, the neutral-point capacitors)
fields: dict[str, Spec] = {
    "inverter.c_f": real_spec(open_closed(0, 1), hint_low="capacitance <= 0"),
    "controller.lambda_psi_nm_per_wb": real_spec(closed(0, 1e6)),
    "controller.lambda_vo_nm_per_v": real_spec(closed(0, 1e3)),
    "controller.t_n_min_s": real_spec(closed(0, Ref("controller.dt_s", 1 / 3, "Ts/3")),
                                      hint_high="T_N clamp minimum above Ts/3"),
    "plant.c_f": real_spec(open_closed(0, 1), hint_low="capacitance <= 0"),
}

#: common fields whose allowed values the T-type narrows or widens
narrowed: dict[str, Spec] = {
    "controller.delay_compensation": Spec(
        BOOL, choices=(True,), hint="the MPDTC step always predicts k+1 under the applied vector and evaluates k+2 "
                      "(the one-period delay is compensated; to simulate another actuation delay set "
                      "plant.actuation_delay_periods)"),
    "scenario.set": choice_spec(("config", "mpdtc-table5")),
}


def check(values: Mapping[str, object], fail: Callable[[str, object, str], NoReturn]) -> None:
    """The MPDTC's model is a surface PMSM: Ld == Lq."""
    if values["motor.ld_h"] != values["motor.lq_h"]:
        fail("controller.strategy", values["controller.strategy"],
             f"t-type MPDTC needs Ld == Lq (surface PMSM model); motor.ld_h = {values['motor.ld_h']:g}, "
             f"motor.lq_h = {values['motor.lq_h']:g}")


def operating_findings(model: Model) -> list[Finding]:
    """Beyond the common checks (psi* comes from MTPA): ``scenario.set = "mpdtc-table5"`` runs the
    MPDTC paper's steady speeds whatever the motor; a speed above ``motor.rated_speed_rpm`` is
    warned about, naming ``scenario.set``."""
    if model.scenario.set != "mpdtc-table5":
        return []
    from codegen.topologies.ttype.scenarios import STEADY_SPEEDS_RPM

    top = max(STEADY_SPEEDS_RPM)
    if top <= model.motor.rated_speed_rpm:
        return []
    *low, high = (f"{v:g}" for v in STEADY_SPEEDS_RPM)
    speeds = f"{', '.join(low)} and {high}" if low else high
    f = above_rated_finding(model, "scenario.set", model.scenario.set, top)
    return [Finding(f.field, f.value, f"the MPDTC paper's Table 5 set (steady runs at {speeds} r/min) {f.text}",
                    f.error)]


def resolve(model: Model) -> Model:
    """The model as it is (a T-type config names no artefact)."""
    return model
