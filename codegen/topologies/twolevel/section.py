"""The two-level MPTC's part of the configuration (loaded by :mod:`codegen.config` through the registry).

Its strategies, the config fields only the two-level controller has (their
checks, in the order they are checked, after the common ones), the
consistency checks between them and the operating point, and the artefact a
config names (the trained s2/s3 switch tables, read at load time).  A field
listed here is refused in a config of another topology.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import NoReturn

from codegen.config import INT, PATH, Ref, Spec, choice_spec, closed, closed_open, open_closed, real_spec
from codegen.model import COST_FORMS, PSI_REFS, Model
from codegen.mpcc import spec as mpcc_spec
from codegen.operating import Finding, g4

__all__ = ["strategies", "families", "fields", "narrowed", "check", "operating_findings", "resolve"]

#: the MPTC strategies of seed 001 (torque and flux in the cost, one period)
MPTC = "mptc"
#: long-horizon current control with a sphere decoder (codegen.mpcc, docs/mpcc.md)
MPCC = "mpcc"

#: strategy family -> its strategies, in report order; the first of each is its baseline
families: dict[str, tuple[str, ...]] = {MPTC: ("conventional", "s1", "s2", "s3"), MPCC: ("mpcc",)}

#: every strategy, in report order; the first is the baseline the others are compared to
strategies: tuple[str, ...] = families[MPTC] + families[MPCC]

_mptc_fields: dict[str, Spec] = {
    "controller.predictor": choice_spec(("flux-geometry", "dq-euler"), required=True),
    "controller.tables": choice_spec(("derived", "published"), required=True),
    "controller.tables_file": Spec(PATH),
    "controller.psi_ref_wb": real_spec(open_closed(0, 10), required=True),
    "controller.psi_ref": choice_spec(PSI_REFS),
    "controller.cost": choice_spec(COST_FORMS),
    "controller.lambda_psi": real_spec(closed(0, 1e3)),
    "controller.eps_t_nm": real_spec(closed_open(0, Ref("motor.rated_torque_nm")), required=True),
    "controller.derivation.coverage": real_spec(open_closed(0, 1)),
    "controller.derivation.max_active": Spec(INT, closed(1, 6)),
}

#: the two-level controller's own fields: the MPTC's (mptc-two-level: predictor, tables, flux reference,
#: cost), read only by its strategies, and the long-horizon family's
fields: dict[str, Spec] = {**{k: replace(v, families=(MPTC,)) for k, v in _mptc_fields.items()},
                           **mpcc_spec.fields(MPCC)}


def family(strategy: object) -> str:
    """The family of ``strategy`` (MPTC for anything else: the strategy's own check reports it)."""
    return MPCC if strategy in families[MPCC] else MPTC

#: common fields whose allowed values the two-level narrows (none)
narrowed: dict[str, Spec] = {}


def check(values: Mapping[str, object], fail: Callable[[str, object, str], NoReturn]) -> None:
    """Consistency between the two-level fields (after every field passed its own check)."""
    if family(values["controller.strategy"]) == MPCC:
        mpcc_spec.check(values, fail)
        return
    if values["controller.predictor"] == "flux-geometry" and values["motor.ld_h"] != values["motor.lq_h"]:
        fail("controller.predictor", values["controller.predictor"],
             'flux-geometry predictor needs Ld == Lq (surface PMSM); use predictor = "dq-euler" '
             f"(motor.ld_h = {values['motor.ld_h']:g}, motor.lq_h = {values['motor.lq_h']:g})")
    if values["controller.tables_file"] is not None and values["controller.tables"] != "derived":
        fail("controller.tables_file", values["controller.tables_file"],
             "names the switch tables derived by a training run, which only controller.tables = 'derived' "
             f"uses (controller.tables = '{values['controller.tables']}')")


def operating_findings(model: Model) -> list[Finding]:
    """The flux reference psi* must be reachable at rated speed: omega_e psi* <= 2 Udc/pi (an error).
    A salient motor (Ld != Lq) with the constant flux reference gets a warning: psi* is then the
    MTPA flux of one torque at most and the reluctance torque goes unused (``controller.psi_ref =
    "mtpa"`` follows T*).  A surface motor (Ld == Lq) gets none: it has no reluctance torque."""
    m, c = model.motor, model.controller
    if family(c.strategy) == MPCC:  # no flux reference, no torque term: nothing of the MPTC's applies
        return []
    w_e = m.rated_speed_rpm * 2.0 * math.pi / 60.0 * m.pole_pairs
    v_six_step = 2.0 * model.inverter.udc_v / math.pi
    v_flux = w_e * c.psi_ref_wb
    out: list[Finding] = []
    if v_flux > v_six_step:
        out.append(Finding("controller.psi_ref_wb", c.psi_ref_wb,
                           f"needs omega_e psi* = {g4(v_flux)} V at rated speed, more than the inverter "
                           f"gives (2 Udc/pi = {g4(v_six_step)} V)", True))
    if c.psi_ref == "constant" and m.ld_h != m.lq_h:
        out.append(Finding("controller.psi_ref", c.psi_ref,
                           f"the motor is salient (motor.ld_h = {g4(m.ld_h)} H, motor.lq_h = {g4(m.lq_h)} H) and a "
                           f"constant psi* (controller.psi_ref_wb = {g4(c.psi_ref_wb)} Wb) ignores it: it is the "
                           "maximum-torque-per-ampere flux of one torque at most, elsewhere the same torque takes "
                           'more current; controller.psi_ref = "mtpa" takes psi* from T* at the MTPA point', False))
    out += _current_step_findings(model)
    return out


#: a per-period current step above this share of the margin between rated current and the trip
#: limit gets the load-time warning (the seed and servo examples: 2.5-11 %; a 150 uH spindle: 56 %)
CURRENT_STEP_OF_MARGIN = 0.25


def _current_step_findings(model: Model) -> list[Finding]:
    """One active vector moves the current by up to di = (2/3) Udc Ts / min(Ld, Lq) in a period (at
    standstill, back-EMF aside) and the torque by about 1.5 p psi_f di.  Against the margin between the
    rated current T_N / (1.5 p psi_f) and the trip limit, a large di means a few wrong steps trip the
    drive; in the cost, the torque term (in units of T_N) then outweighs the flux term (in units of
    psi*) so much that the flux drifts.  A warning while ``controller.lambda_psi`` is the papers' 1."""
    m, c, inv = model.motor, model.controller, model.inverter
    di = 2.0 / 3.0 * inv.udc_v * c.dt_s / min(m.ld_h, m.lq_h)
    i_rated = m.rated_torque_nm / (1.5 * m.pole_pairs * m.psi_f_wb)
    margin = inv.i_trip_a - i_rated
    if c.lambda_psi != 1.0 or margin <= 0.0 or di <= CURRENT_STEP_OF_MARGIN * margin:
        return []
    d_t = 1.5 * m.pole_pairs * m.psi_f_wb * di
    return [Finding("controller.lambda_psi", c.lambda_psi, (
        f"one active vector moves the current by up to {g4(di)} A per period ((2/3) inverter.udc_v "
        f"controller.dt_s / min(motor.ld_h, motor.lq_h)), {100 * di / margin:.0f} % of the margin between "
        f"the rated current ({g4(i_rated)} A) and inverter.i_trip_a = {g4(inv.i_trip_a)} A, and the torque "
        f"by about {g4(d_t)} N*m ({100 * d_t / m.rated_torque_nm:.0f} % of motor.rated_torque_nm): the "
        "cost's torque term hides the flux term and the flux drifts; raise controller.lambda_psi "
        "(mpcgen tune CONFIG --weight controller.lambda_psi finds it) or shorten controller.dt_s"), False)]


def resolve(model: Model) -> Model:
    """The model with the trained s2/s3 tables its ``controller.tables_file`` names read in (the file is
    read and checked against the config; no compiler, no run)."""
    if family(model.controller.strategy) == MPCC:
        return model
    from codegen.topologies.twolevel.tables_file import load_into

    return load_into(model)
