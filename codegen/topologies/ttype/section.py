"""The T-type MPDTC's part of the configuration (loaded by :mod:`codegen.config` through the registry).

Its strategies, the config fields only the T-type has (DC-link capacitors,
the cost weights of eq. (7), the T_N clamp), the common fields whose allowed
values it narrows (the MPDTC step always compensates the one-period delay;
the paper's Table 5 run set), and its consistency checks.  A field listed
here is refused in a config of another topology.
"""
from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import NoReturn

from codegen.config import BOOL, Ref, Spec, choice_spec, closed, open_closed, real_spec
from codegen.model import Model
from codegen.mpcc import spec as mpcc_spec
from codegen.operating import Finding, above_rated_finding

__all__ = ["strategies", "families", "fields", "narrowed", "check", "operating_findings", "resolve"]

#: the MPDTC strategies of seed 000 (torque, flux and neutral point in the cost, virtual vectors)
MPDTC = "mpdtc"
#: long-horizon current control with a sphere decoder (codegen.mpcc, docs/mpcc.md)
MPCC = "mpcc"

#: strategy family -> its strategies, in report order; the first of each is its baseline
families: dict[str, tuple[str, ...]] = {MPDTC: ("mpdtc27", "mpdtc63"), MPCC: ("mpcc",)}

#: every strategy, in report order; the first is the baseline the others are compared to
strategies: tuple[str, ...] = families[MPDTC] + families[MPCC]


def family(strategy: object) -> str:
    """The family of ``strategy`` (MPDTC for anything else: the strategy's own check reports it)."""
    return MPCC if strategy in families[MPCC] else MPDTC


#: the T-type's own fields (eq. (7) weights and eq. (10)-(11) T_N clamp, read by the MPDTC strategies only;
#: the neutral-point capacitors), and the long-horizon family's
fields: dict[str, Spec] = {
    "inverter.c_f": real_spec(open_closed(0, 1), hint_low="capacitance <= 0"),
    "controller.lambda_psi_nm_per_wb": replace(real_spec(closed(0, 1e6)), families=(MPDTC,)),
    "controller.lambda_vo_nm_per_v": replace(real_spec(closed(0, 1e3)), families=(MPDTC,)),
    "controller.t_n_min_s": replace(real_spec(closed(0, Ref("controller.dt_s", 1 / 3, "Ts/3")),
                                              hint_high="T_N clamp minimum above Ts/3"), families=(MPDTC,)),
    "plant.c_f": real_spec(open_closed(0, 1), hint_low="capacitance <= 0"),
    **mpcc_spec.fields(MPCC),
    **mpcc_spec.neutral_point_fields(MPCC),
}

#: common fields whose allowed values the T-type narrows or widens
narrowed: dict[str, Spec] = {
    "controller.delay_compensation": Spec(
        BOOL, choices=(True,), hint="the T-type steps always predict k+1 under the applied vector and evaluate from k+2 "
                      "(the one-period delay is compensated; to simulate another actuation delay set "
                      "plant.actuation_delay_periods)"),
    "scenario.set": choice_spec(("config", "mpdtc-table5")),
}


def check(values: Mapping[str, object], fail: Callable[[str, object, str], NoReturn]) -> None:
    """The MPDTC's model is a surface PMSM: Ld == Lq (the long-horizon family: its own checks)."""
    if family(values["controller.strategy"]) == MPCC:
        mpcc_spec.check(values, fail)
        return
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
