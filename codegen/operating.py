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

from codegen.model import Model

__all__ = ["Finding", "operating_findings", "g4"]


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
    return sorted(out, key=lambda f: not f.error)
