"""Test states of the three-level step (numerics.md "Test states").

(b) random states over the operating range (and a little beyond, so the
    guard trips in about 3 % of them), V_o spread up to its limits;
(c) adversarial states: u* on the 30-deg sector borders (currents solved so
    that the deadbeat reference lands on a border, and one ulp off it via
    theta), ties (zero current, zero speed, T* = 0, balanced capacitors: the
    redundant members and groups tie), angle-reduction borders, every guard
    limit exactly / one ulp beyond / NaN / inf, every prev_vector 0..62 with
    t_n_prev_s at 0, T_N_min and Ts/3, invalid prev_vector and t_n_prev_s.
Deterministic for a given seed; vectorised.
"""
from __future__ import annotations

import math

import numpy as np

from codegen.model import Model
from codegen.topologies.ttype.derive import ThreeLevelTables, guard_limits, t_n_min
from codegen.topologies.ttype.records import INPUT_DTYPE

F = np.float32


def random_states(model: Model, n: int, seed: int = 1) -> np.ndarray:
    """``n`` random states over the operating range."""
    rng = np.random.default_rng(seed)
    g = guard_limits(model)
    ts = model.controller.dt_s
    x = np.zeros(n, INPUT_DTYPE)
    i_max = 1.03 * g["I_TRIP_A"] / 2
    x["ia_a"] = rng.uniform(-i_max, i_max, n)
    x["ib_a"] = rng.uniform(-i_max, i_max, n)
    wide = rng.random(n) < 0.05
    x["theta_e_rad"] = np.where(wide, rng.uniform(-260, 260, n), rng.uniform(0, 2 * math.pi, n))
    w = 1.01 * g["OMEGA_GUARD_RAD_S"]
    x["omega_e_rad_s"] = np.where(rng.random(n) < 0.9, rng.uniform(-w / 5, w / 5, n), rng.uniform(-w, w, n))
    udc = model.inverter.udc_v
    lo, hi = g["UC_MIN_V"], g["UC_MAX_V"]
    # V_o from 0 up to its limits (one capacitor at its guard limit), total Udc near nominal
    half = rng.uniform(0.9, 1.1, n) * udc / 2
    vo = np.where(rng.random(n) < 0.7, rng.normal(0, 2.0, n), rng.uniform(-1, 1, n) * (half - lo))
    x["uc1_v"] = np.clip(half + vo, lo - 0.01 * (hi - lo), hi + 0.01 * (hi - lo))
    x["uc2_v"] = np.clip(half - vo, lo - 0.01 * (hi - lo), hi + 0.01 * (hi - lo))
    t = 1.01 * g["TORQUE_REF_GUARD_NM"]
    x["torque_ref_nm"] = np.where(rng.random(n) < 0.9, rng.uniform(-t / 4, t / 4, n), rng.uniform(-t, t, n))
    x["prev_vector"] = np.where(rng.random(n) < 0.002, rng.integers(63, 65536, n), rng.integers(0, 63, n))
    x["t_n_prev_s"] = np.where(rng.random(n) < 0.002, rng.uniform(-ts, ts, n),
                               rng.uniform(t_n_min(model), ts / 3, n))
    return x


def _nominal(model: Model, n: int, rng: np.random.Generator) -> np.ndarray:
    x = random_states(model, n, seed=int(rng.integers(1 << 30)))
    x["theta_e_rad"] = rng.uniform(0, 2 * math.pi, n)
    udc = model.inverter.udc_v
    x["uc1_v"] = udc / 2
    x["uc2_v"] = udc / 2
    x["prev_vector"] = rng.integers(0, 63, n)
    x["t_n_prev_s"] = F(model.controller.dt_s / 6)
    return x


def _on_sector_border(model: Model, x: np.ndarray, rng: np.random.Generator) -> None:
    """Place u* (float64 model of the step, no delay term) on a 30-deg border.

    Solve for the stator flux at k+1 that makes u* point at the border angle
    with a random magnitude, then back to currents at k (ignoring the delay
    step's voltage, which is why only some states land exactly: enough to
    exercise both sides of every border)."""
    m, ts = model.motor, model.controller.dt_s
    n = len(x)
    th = x["theta_e_rad"].astype(np.float64)
    w = x["omega_e_rad_s"].astype(np.float64)
    th2 = th + 2 * w * ts
    iqr = x["torque_ref_nm"].astype(np.float64) / (1.5 * m.pole_pairs * m.psi_f_wb)
    pr = (m.psi_f_wb + 1j * m.ld_h * iqr) * np.exp(1j * th2)
    ang = rng.integers(0, 12, n) * (math.pi / 6)
    u = rng.uniform(1, 150, n) * np.exp(1j * ang)
    psi1 = pr - u * ts  # Rs term neglected
    psi_dq = psi1 * np.exp(-1j * th)
    i_d = (psi_dq.real - m.psi_f_wb) / m.ld_h
    i_q = psi_dq.imag / m.ld_h
    i_ab = (i_d + 1j * i_q) * np.exp(1j * th)
    x["ia_a"] = i_ab.real
    x["ib_a"] = (-i_ab.real + math.sqrt(3) * i_ab.imag) / 2
    x["omega_e_rad_s"] = np.where(rng.random(n) < 0.5, 0.0, x["omega_e_rad_s"])


def adversarial_states(model: Model, t: ThreeLevelTables, n_target: int = 200_000, seed: int = 2) -> np.ndarray:
    """Adversarial states (see module doc); about ``n_target`` of them."""
    rng = np.random.default_rng(seed)
    g = guard_limits(model)
    ts = model.controller.dt_s
    parts: list[np.ndarray] = []

    # u* on sector borders, with zero speed for half of them (exact geometry)
    n = n_target // 5
    x = _nominal(model, n, rng)
    _on_sector_border(model, x, rng)
    parts.append(x)

    # angle-reduction borders: multiples of pi/4, +-0, one ulp either side
    k = rng.integers(-320, 321, n_target // 10)
    th = (k * (math.pi / 4)).astype(np.float32)
    th = np.where(rng.random(len(k)) < 0.5, np.nextafter(th, F(np.inf)), th)
    th = np.where(rng.random(len(k)) < 0.3, np.nextafter(th, F(-np.inf)), th)
    x = _nominal(model, len(k), rng)
    x["theta_e_rad"] = np.clip(th, -g["ANGLE_GUARD_RAD"], g["ANGLE_GUARD_RAD"])
    x["theta_e_rad"][:4] = [0.0, -0.0, g["ANGLE_GUARD_RAD"], -g["ANGLE_GUARD_RAD"]]
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

    # guard limits: exactly at the limit (passes), one ulp beyond (trips), NaN, inf
    n = n_target // 5
    x = _nominal(model, n, rng)
    field_limits = [
        ("ia_a", g["I_TRIP_A"]), ("ib_a", g["I_TRIP_A"]),
        ("uc1_v", g["UC_MIN_V"]), ("uc1_v", g["UC_MAX_V"]), ("uc2_v", g["UC_MIN_V"]), ("uc2_v", g["UC_MAX_V"]),
        ("theta_e_rad", g["ANGLE_GUARD_RAD"]), ("omega_e_rad_s", g["OMEGA_GUARD_RAD_S"]),
        ("torque_ref_nm", g["TORQUE_REF_GUARD_NM"]), ("t_n_prev_s", ts / 3), ("t_n_prev_s", 0.0),
    ]
    specials = np.array([np.nan, np.inf, -np.inf], np.float32)
    which = rng.integers(0, len(field_limits), n)
    kind = rng.integers(0, 5, n)
    for i, (name, lim) in enumerate(field_limits):
        sel = which == i
        lim32 = F(lim)
        signed = name not in ("uc1_v", "uc2_v", "t_n_prev_s")
        sgn = np.where(rng.random(sel.sum()) < 0.5, F(1), F(-1)) if signed else F(1)
        at = (sgn * lim32).astype(np.float32)
        if name == "t_n_prev_s" and lim == 0.0:
            beyond = np.full(sel.sum(), np.nextafter(F(0), F(-1)), np.float32)
            inside = np.full(sel.sum(), np.nextafter(F(0), F(1)), np.float32)
        else:
            beyond = np.nextafter(at, (at * F(2)).astype(np.float32))
            inside = np.nextafter(at, F(0))
        special = specials[rng.integers(0, 3, sel.sum())]
        k_sel = kind[sel]
        vals = np.select([k_sel == 0, k_sel == 1, k_sel == 2], [at, beyond, inside], special)
        x[name][sel] = vals
        if name in ("ia_a", "ib_a"):  # keep the other phase small so only this limit matters
            other = "ib_a" if name == "ia_a" else "ia_a"
            x[other][sel] = 0.0
        if name == "t_n_prev_s":  # only checked for a virtual previous vector
            x["prev_vector"][sel] = rng.integers(27, 63, sel.sum())
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
    return np.concatenate(parts)
