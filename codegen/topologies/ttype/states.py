"""Test states of the three-level step (numerics.md "Test states").

(b) random states over the operating range (and a little beyond, so the
    guard trips in about 3 % of them), V_o spread up to its limits;
(c) adversarial states: u* on the 30-deg sector borders (currents solved so
    that the deadbeat reference lands on a border, and one ulp off it via
    theta), ties (zero current, zero speed, T* = 0, balanced capacitors: the
    redundant members and groups tie), angle-reduction borders, every guard
    limit exactly / one ulp beyond / NaN / inf, every prev_vector 0..62 with
    t_n_prev_s at 0, T_N_min and Ts/3, invalid prev_vector and t_n_prev_s.
Deterministic for a given seed; vectorised.  The topology-independent pieces
are :mod:`codegen.teststates`.
"""
from __future__ import annotations

import math

import numpy as np

from codegen import teststates as common
from codegen.model import Model
from codegen.numfmt.float32 import F
from codegen.topologies.ttype.derive import ThreeLevelTables, guard_limits, t_n_min
from codegen.topologies.ttype.records import INPUT, INPUT_DTYPE
from codegen.topologies.ttype.vectors import OOO


def random_states(model: Model, n: int, seed: int = 1) -> np.ndarray:
    """``n`` random states over the operating range."""
    rng = np.random.default_rng(seed)
    g = guard_limits(model)
    ts = model.controller.dt_s
    x = np.zeros(n, INPUT_DTYPE)
    common.random_currents_and_motion(x, g, rng)
    udc = model.inverter.udc_v
    lo, hi = g["UC_MIN_V"], g["UC_MAX_V"]
    # V_o from 0 up to its limits (one capacitor at its guard limit), total Udc near nominal
    half = rng.uniform(0.9, 1.1, n) * udc / 2
    vo = np.where(rng.random(n) < 0.7, rng.normal(0, 2.0, n), rng.uniform(-1, 1, n) * (half - lo))
    x["uc1_v"] = np.clip(half + vo, lo - 0.01 * (hi - lo), hi + 0.01 * (hi - lo))
    x["uc2_v"] = np.clip(half - vo, lo - 0.01 * (hi - lo), hi + 0.01 * (hi - lo))
    x["torque_ref_nm"] = common.random_torque_ref(n, g, rng)
    x["prev_vector"] = np.where(rng.random(n) < 0.002, rng.integers(63, 65536, n), rng.integers(0, 63, n))
    x["t_n_prev_s"] = np.where(rng.random(n) < 0.002, rng.uniform(-ts, ts, n),
                               rng.uniform(t_n_min(model), ts / 3, n))
    return x


def limits(model: Model) -> tuple[common.Limit, ...]:
    """Every guard limit of the T-type input record (t_n_prev_s: for a virtual previous vector)."""
    g = guard_limits(model)
    lo, hi = g["UC_MIN_V"], g["UC_MAX_V"]
    return (common.Limit("ia_a", g["I_TRIP_A"]), common.Limit("ib_a", g["I_TRIP_A"]),
            common.Limit("uc1_v", lo, "lower"), common.Limit("uc1_v", hi, "upper"),
            common.Limit("uc2_v", lo, "lower"), common.Limit("uc2_v", hi, "upper"),
            common.Limit("theta_e_rad", g["ANGLE_GUARD_RAD"]), common.Limit("omega_e_rad_s", g["OMEGA_GUARD_RAD_S"]),
            common.Limit("torque_ref_nm", g["TORQUE_REF_GUARD_NM"]),
            common.Limit("t_n_prev_s", model.controller.dt_s / 3, "upper"), common.Limit("t_n_prev_s", 0.0, "lower"))


def _nominal(model: Model, n: int, rng: np.random.Generator) -> np.ndarray:
    """Random states with balanced nominal capacitor voltages, theta in one turn, a valid previous vector."""
    x = random_states(model, n, seed=int(rng.integers(1 << 30)))
    x["theta_e_rad"] = rng.uniform(0, 2 * math.pi, n)
    udc = model.inverter.udc_v
    x["uc1_v"] = udc / 2
    x["uc2_v"] = udc / 2
    x["prev_vector"] = rng.integers(0, 63, n)
    x["t_n_prev_s"] = F(model.controller.dt_s / 6)
    return x


def _on_sector_border(model: Model, x: np.ndarray, rng: np.random.Generator) -> None:
    """Place u* on a 30-deg border (exactly in float64, or 1e-7 / 1e-6 rad next to it).

    With speed zero and the previous vector OOO (zero voltage), the step is linear in i(k):
    the delay step gives i1 = (1 - Ts Rs/Ls) i, the MTPA reference in dq is (psi_f, Ls i_q*),
    and u* = ((psi_f, Ls i_q*) - (Ls i1 + psi_f))/Ts + Rs i1 (dq, rotated by theta).  Solve it
    for i(k) given u* = U e^(j ang); the float32 rounding of the currents then puts u* within
    a few 1e-7 rad of the border (``tests/topologies/ttype/test_ttype_states.py`` measures it)."""
    m, ts = model.motor, model.controller.dt_s
    n = len(x)
    x["omega_e_rad_s"] = 0.0
    x["prev_vector"] = OOO
    th = x["theta_e_rad"].astype(np.float64)
    iqr = x["torque_ref_nm"].astype(np.float64) / (1.5 * m.pole_pairs * m.psi_f_wb)
    ang = rng.integers(0, 12, n) * (math.pi / 6) + rng.choice([0.0, 1e-7, -1e-7, 1e-6, -1e-6], n)
    u_dq = rng.uniform(1, 150, n) * np.exp(1j * (ang - th))
    ls, rs = m.ld_h, m.rs_ohm
    i1 = (u_dq - 1j * ls * iqr / ts) / (rs - ls / ts)
    i = i1 / (1.0 - ts * rs / ls)
    x["ia_a"], x["ib_a"] = common.phase_currents(i.real, i.imag, th)


def adversarial_states(model: Model, t: ThreeLevelTables, n_target: int = 200_000, seed: int = 2) -> np.ndarray:
    """Adversarial states (see module doc); about ``n_target`` of them."""
    rng = np.random.default_rng(seed)
    g = guard_limits(model)
    ts = model.controller.dt_s
    parts: list[np.ndarray] = []

    # u* on sector borders (speed zero, previous vector OOO: the step is linear in the currents)
    n = n_target // 5
    x = _nominal(model, n, rng)
    _on_sector_border(model, x, rng)
    parts.append(x)

    # sin/cos angle-reduction borders: multiples of pi/N, +-0, one ulp either side
    x = _nominal(model, n_target // 10, rng)
    x["theta_e_rad"] = common.angle_reduction_borders(len(x), g["ANGLE_GUARD_RAD"], t.nf.sincos_form.table_n, rng)
    parts.append(x)

    # ties: zero currents (all i_o = 0: redundant members tie), zero speed,
    # T* = 0, theta = 0, balanced capacitors
    n = n_target // 5
    x = _nominal(model, n, rng)
    zero_i = rng.random(n) < 0.5
    x["ia_a"] = np.where(zero_i, 0.0, x["ia_a"])
    x["ib_a"] = np.where(zero_i | (rng.random(n) < 0.3), 0.0, x["ib_a"])
    x["omega_e_rad_s"] = np.where(rng.random(n) < 0.5, 0.0, x["omega_e_rad_s"])
    x["torque_ref_nm"] = np.where(rng.random(n) < 0.5, 0.0, np.round(x["torque_ref_nm"]))
    x["theta_e_rad"] = np.where(rng.random(n) < 0.5, 0.0, x["theta_e_rad"])
    parts.append(x)

    # V_o at its limits: one capacitor exactly at its guard limit, the other nominal
    n = n_target // 10
    x = _nominal(model, n, rng)
    udc = model.inverter.udc_v
    lim = np.where(rng.random(n) < 0.5, g["UC_MIN_V"], g["UC_MAX_V"])
    up = rng.random(n) < 0.5
    x["uc1_v"] = np.where(up, lim, udc / 2)
    x["uc2_v"] = np.where(up, udc / 2, lim)
    parts.append(x)

    # guard limits: exactly at the limit (passes), one ulp beyond (trips), one inside, NaN, inf
    x = _nominal(model, n_target // 5, rng)
    lims = limits(model)
    which = common.apply_limit_cases(x, lims, rng)
    tn = np.isin(which, [i for i, lim in enumerate(lims) if lim.field == "t_n_prev_s"])
    x["prev_vector"][tn] = rng.integers(27, 63, int(tn.sum()))  # only checked for a virtual previous vector
    parts.append(x)

    # every prev_vector 0..62 (and invalid ids), t_n_prev_s at 0, T_N_min, Ts/3,
    # speed zero and at its guard
    n = max(n_target - sum(len(p) for p in parts), 66)
    x = _nominal(model, n, rng)
    ids = np.arange(n) % 66
    x["prev_vector"] = np.where(ids < 63, ids, np.array([63, 64, 65535])[np.clip(ids - 63, 0, 2)])
    x["t_n_prev_s"] = np.array([0.0, t_n_min(model), ts / 3], np.float32)[rng.integers(0, 3, n)]
    x["omega_e_rad_s"] = np.where(rng.random(n) < 0.5, 0.0, F(g["OMEGA_GUARD_RAD_S"]))
    parts.append(x)
    return common.in_format(np.concatenate(parts), INPUT.bind(t.nf))
