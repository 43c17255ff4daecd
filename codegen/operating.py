"""Operating-point consistency of a validated config: can this drive run the scenario it describes?

Each field can be inside its own range while the combination cannot work
(a trip limit below the rated current, a DC link whose voltage cannot drive
the back-EMF at rated speed) or works badly (a speed-loop limit whose
current trips the guard).  These checks run at load time: an error where the
run cannot work, a warning where it degrades.  Estimates (stated in each
message) use the magnet torque constant 1.5 p psi_f and neglect Rs:

* rated current  I_rated = T_rated / (1.5 p psi_f)
* rated back-EMF E = omega_e,rated psi_f, with omega_e,rated = 2 pi n_rated / 60 * p
* largest fundamental phase voltage of the inverter: six-step, 2 Udc / pi;
  linear modulation reaches Udc / sqrt(3)
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from codegen.model import SPEED_GUARD_PER_RATED, Model

__all__ = ["Finding", "above_rated_finding", "operating_findings", "plausibility_findings", "g4"]


@dataclass(frozen=True)
class Finding:
    """One inconsistency: the field to blame, its value, the explanation, and whether it is fatal."""

    field: str
    value: object
    text: str
    error: bool


def g4(x: float) -> str:
    """Four significant digits, for messages."""
    return f"{x:.4g}"


def operating_findings(model: Model) -> list[Finding]:
    """Every inconsistency of ``model``'s operating point that every topology shares, errors first (a
    topology adds its own: ``TopologySection.operating_findings``)."""
    m, inv, sl = model.motor, model.inverter, model.speed_loop
    k_t = 1.5 * m.pole_pairs * m.psi_f_wb
    i_rated = m.rated_torque_nm / k_t
    w_e = m.rated_speed_rpm * 2.0 * math.pi / 60.0 * m.pole_pairs
    v_six_step = 2.0 * inv.udc_v / math.pi
    v_linear = inv.udc_v / math.sqrt(3.0)
    out: list[Finding] = []
    if inv.i_trip_a < i_rated:
        out.append(Finding("inverter.i_trip_a", inv.i_trip_a,
                           f"below the rated current {g4(i_rated)} A (T_rated / (1.5 p psi_f)): "
                           "rated torque would trip the current guard", True))
    emf = w_e * m.psi_f_wb
    if emf > v_six_step:
        n_max = v_six_step / (m.psi_f_wb * m.pole_pairs) * 60.0 / (2.0 * math.pi)
        out.append(Finding("inverter.udc_v", inv.udc_v,
                           f"too low for the back-EMF at rated speed: omega_e psi_f = {g4(emf)} V > 2 Udc/pi = "
                           f"{g4(v_six_step)} V; the motor cannot exceed about {g4(n_max)} r/min", True))
    elif emf > v_linear:
        out.append(Finding("inverter.udc_v", inv.udc_v,
                           f"little voltage margin: back-EMF at rated speed {g4(emf)} V > Udc/sqrt(3) = "
                           f"{g4(v_linear)} V; torque control degrades near rated speed", False))
    i_limit = sl.limit_nm / k_t
    if i_limit > inv.i_trip_a:
        out.append(Finding("speed_loop.limit_nm", sl.limit_nm,
                           f"asks for about {g4(i_limit)} A (limit / (1.5 p psi_f)), above inverter.i_trip_a = "
                           f"{g4(inv.i_trip_a)} A: accelerations at the limit will trip the guard", False))
    out += plausibility_findings(model)
    return sorted(out, key=lambda f: not f.error)


#: a mechanical time constant J omega_rated / T_rated above this, s, is more likely a unit slip than a motor
TAU_M_MAX_S = 5.0
#: viscous friction at rated speed above this share of the rated torque is more likely a unit slip
FRICTION_SHARE_MAX = 0.2
#: a back-EMF at rated speed below this share of Udc/sqrt(3) is more likely rad/s entered as r/min
EMF_SHARE_MIN = 0.05
#: an electrical time constant L/Rs below this many control periods leaves the current uncontrollable
TAU_E_MIN_PERIODS = 2.0


def plausibility_findings(model: Model) -> list[Finding]:
    """Warnings for the unit slips engineers make, each checked against another field:

    * mechanical time constant tau_m = J omega_m,rated / T_rated (time to reach rated speed at rated
      torque): above :data:`TAU_M_MAX_S` suggests kg*cm^2 entered as kg*m^2;
    * friction at rated speed B omega_m,rated against T_rated: above :data:`FRICTION_SHARE_MAX`;
    * back-EMF at rated speed against Udc/sqrt(3): below :data:`EMF_SHARE_MIN` suggests rad/s entered as
      r/min (or a motor far too small for the DC link);
    * electrical time constant min(Ld, Lq)/Rs against the control period;
    * the speed reference against the step's speed guard (``SPEED_GUARD_PER_RATED`` x rated), or,
      below the guard, against the rated speed itself when the config's profile is what runs
      (``scenario.set = "config"``; a topology's own run set is checked by its section): the other
      load-time checks hold up to rated speed only.
    """
    m, inv, c = model.motor, model.inverter, model.controller
    w_m = m.rated_speed_rpm * 2.0 * math.pi / 60.0
    out: list[Finding] = []
    tau_m = m.j_kgm2 * w_m / m.rated_torque_nm
    if tau_m > TAU_M_MAX_S:
        out.append(Finding("motor.j_kgm2", m.j_kgm2,
                           f"gives a mechanical time constant J omega_rated/T_rated of {g4(tau_m)} s (more than "
                           f"{g4(TAU_M_MAX_S)} s to reach rated speed at rated torque); kg*cm^2 entered as kg*m^2? "
                           f"({g4(m.j_kgm2)} kg*cm^2 = {g4(m.j_kgm2 * 1e-4)} kg*m^2)", False))
    friction = m.b_nms * w_m / m.rated_torque_nm
    if friction > FRICTION_SHARE_MAX:
        out.append(Finding("motor.b_nms", m.b_nms,
                           f"takes {g4(100 * friction)} % of the rated torque at rated speed (B omega_rated = "
                           f"{g4(m.b_nms * w_m)} N*m); is the unit N*m*s/rad (per rad/s of mechanical speed)?",
                           False))
    emf_share = w_m * m.pole_pairs * m.psi_f_wb / (inv.udc_v / math.sqrt(3.0))
    if emf_share < EMF_SHARE_MIN:
        out.append(Finding("motor.rated_speed_rpm", m.rated_speed_rpm,
                           f"gives a back-EMF at rated speed of only {g4(100 * emf_share)} % of Udc/sqrt(3); rad/s "
                           f"entered as r/min? ({g4(m.rated_speed_rpm)} rad/s = "
                           f"{g4(m.rated_speed_rpm * 60.0 / (2.0 * math.pi))} r/min)", False))
    tau_e = min(m.ld_h, m.lq_h) / m.rs_ohm
    if tau_e < TAU_E_MIN_PERIODS * c.dt_s:
        out.append(Finding("motor.ld_h", m.ld_h,
                           f"gives an electrical time constant min(Ld, Lq)/Rs of {g4(tau_e)} s, less than "
                           f"{g4(TAU_E_MIN_PERIODS)} control periods ({g4(c.dt_s)} s): the current changes more "
                           "within one period than the controller can follow; inductance in H (e.g. 150e-6 for "
                           "150 uH)?", False))
    guard_rpm = SPEED_GUARD_PER_RATED * m.rated_speed_rpm
    top = max(abs(v) for _, v in model.scenario.speed_ref_rpm)
    if top > guard_rpm:
        out.append(Finding("scenario.speed_ref_rpm", top,
                           f"reaches {g4(top)} r/min, above the step's speed guard ({g4(SPEED_GUARD_PER_RATED)} x "
                           f"rated = {g4(guard_rpm)} r/min): the controller trips there", False))
    elif model.scenario.set == "config" and top > m.rated_speed_rpm:
        out.append(above_rated_finding(model, "scenario.speed_ref_rpm", top, top))
    return out


def above_rated_finding(model: Model, field: str, value: object, top_rpm: float) -> Finding:
    """The warning for a scenario that runs the motor at ``top_rpm`` r/min, above
    ``motor.rated_speed_rpm``: the operating-point checks (back-EMF against the DC link, psi*
    reachable) are made at rated speed, so they do not cover that run; the back-EMF at ``top_rpm``
    is stated against Udc/sqrt(3)."""
    m = model.motor
    emf = top_rpm * 2.0 * math.pi / 60.0 * m.pole_pairs * m.psi_f_wb
    v_linear = model.inverter.udc_v / math.sqrt(3.0)
    return Finding(field, value,
                   f"runs the motor at {g4(top_rpm)} r/min, above motor.rated_speed_rpm = {g4(m.rated_speed_rpm)} "
                   f"r/min: the load-time voltage checks are made at rated speed and do not cover it (back-EMF at "
                   f"{g4(top_rpm)} r/min: {g4(emf)} V; Udc/sqrt(3) = {g4(v_linear)} V)", False)
