"""Test states for bit-for-bit verification (numerics.md "Test states").

(a) closed-loop states come from ``codegen.simulate`` traces (see verify.py);
(b) random states across the whole operating range (and a little beyond, so
    the guard is exercised); (c) adversarial states: sector borders, quadrant
    borders of the angle reduction, T* exactly at the threshold and one ulp
    either side, equal costs, guard limits exactly and one ulp beyond, NaN and
    infinities in every field, zero and maximum speed, every previous state.
All generators are deterministic for a given seed and vectorised.
"""
from __future__ import annotations

import math

import numpy as np

from codegen.model import Model
from codegen.topologies.twolevel.derive import TwoLevelTables, guard_limits
from codegen.topologies.twolevel.records import INPUT_DTYPE

F = np.float32


def random_states(model: Model, n: int, seed: int = 1) -> np.ndarray:
    """``n`` random states over the operating range (about 3 % trip the guard)."""
    rng = np.random.default_rng(seed)
    g = guard_limits(model)
    x = np.zeros(n, INPUT_DTYPE)
    i_max = 1.03 * g["I_TRIP_A"] / 2
    x["ia_a"] = rng.uniform(-i_max, i_max, n)
    x["ib_a"] = rng.uniform(-i_max, i_max, n)
    wide = rng.random(n) < 0.05
    x["theta_e_rad"] = np.where(wide, rng.uniform(-260, 260, n), rng.uniform(0, 2 * math.pi, n))
    w = 1.01 * g["OMEGA_GUARD_RAD_S"]
    x["omega_e_rad_s"] = np.where(rng.random(n) < 0.9, rng.uniform(-w / 5, w / 5, n), rng.uniform(-w, w, n))
    lo, hi = g["UDC_MIN_V"], g["UDC_MAX_V"]
    x["udc_v"] = rng.uniform(lo - 0.01 * (hi - lo), hi + 0.01 * (hi - lo), n)
    t = 1.01 * g["TORQUE_REF_GUARD_NM"]
    x["torque_ref_nm"] = np.where(rng.random(n) < 0.9, rng.uniform(-t / 4, t / 4, n), rng.uniform(-t, t, n))
    x["prev_sw"] = np.where(rng.random(n) < 0.002, rng.integers(8, 65536, n), rng.integers(0, 8, n))
    return x


def _flux_states(model: Model, psi_a: np.ndarray, psi_b: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Phase currents (float64) that give the stator flux (psi_a, psi_b) at theta."""
    m = model.motor
    c, s = np.cos(theta), np.sin(theta)
    psi_d = psi_a * c + psi_b * s
    psi_q = -psi_a * s + psi_b * c
    i_d = (psi_d - m.psi_f_wb) / m.ld_h
    i_q = psi_q / m.lq_h
    i_alpha = i_d * c - i_q * s
    i_beta = i_d * s + i_q * c
    i_a = i_alpha
    i_b = (-i_alpha + math.sqrt(3) * i_beta) / 2
    return i_a, i_b


def adversarial_states(model: Model, t: TwoLevelTables, reference_step, n_target: int = 200_000, seed: int = 2) -> np.ndarray:
    """Adversarial states; ``reference_step(t, x)`` is used to place T* exactly at the threshold."""
    rng = np.random.default_rng(seed)
    g = guard_limits(model)
    parts: list[np.ndarray] = []

    def base(n: int) -> np.ndarray:
        x = random_states(model, n, seed=int(rng.integers(1 << 30)))
        x["theta_e_rad"] = rng.uniform(0, 2 * math.pi, n)
        x["udc_v"] = model.inverter.udc_v
        x["prev_sw"] = rng.integers(0, 8, n)
        return x

    # sector borders: flux exactly on (and next to) every 30 deg border
    n = n_target // 5
    x = base(n)
    ang = (rng.integers(0, 12, n) * (math.pi / 6)) + rng.choice([0.0, 1e-7, -1e-7, 1e-6, -1e-6], n)
    mag = model.controller.psi_ref_wb * rng.uniform(0.9, 1.1, n)
    ia, ib = _flux_states(model, mag * np.cos(ang), mag * np.sin(ang), x["theta_e_rad"].astype(np.float64))
    x["ia_a"], x["ib_a"] = ia, ib
    parts.append(x)

    # angle-reduction borders: multiples of pi/4 and pi/2, +-0, one ulp either side
    k = rng.integers(-320, 321, n_target // 10)
    th = (k * (math.pi / 4)).astype(np.float32)
    th = np.where(rng.random(len(k)) < 0.5, np.nextafter(th, F(np.inf)), th)
    th = np.where(rng.random(len(k)) < 0.3, np.nextafter(th, F(-np.inf)), th)
    x = base(len(k))
    x["theta_e_rad"] = np.clip(th, -g["ANGLE_GUARD_RAD"], g["ANGLE_GUARD_RAD"])
    x["theta_e_rad"][:4] = [0.0, -0.0, g["ANGLE_GUARD_RAD"], -g["ANGLE_GUARD_RAD"]]
    parts.append(x)

    # T* exactly at the threshold and one ulp either side (s1-s3 decision border)
    n = n_target // 5
    x = base(n)
    te = reference_step(t, x)["te_est_nm"]
    eps = t.const("EPS_T_NM")
    sign = np.where(rng.random(n) < 0.5, F(1), F(-1))
    tref = (te + sign * eps).astype(np.float32)
    step = rng.integers(-1, 2, n)
    tref = np.where(step > 0, np.nextafter(tref, F(np.inf)), np.where(step < 0, np.nextafter(tref, F(-np.inf)), tref))
    x["torque_ref_nm"] = tref
    parts.append(x)

    # ties and symmetric states: zero current, zero speed, T* = 0, flux on an axis
    n = n_target // 10
    x = base(n)
    x["ia_a"] = np.where(rng.random(n) < 0.5, 0.0, x["ia_a"])
    x["ib_a"] = np.where(rng.random(n) < 0.5, 0.0, x["ib_a"])
    x["omega_e_rad_s"] = np.where(rng.random(n) < 0.5, 0.0, x["omega_e_rad_s"])
    x["torque_ref_nm"] = np.where(rng.random(n) < 0.5, 0.0, np.round(x["torque_ref_nm"]))
    x["theta_e_rad"] = np.where(rng.random(n) < 0.5, 0.0, x["theta_e_rad"])
    parts.append(x)

    # guard limits: exactly at the limit (passes) and one ulp beyond (trips), NaN, inf
    n = n_target // 5
    x = base(n)
    field_limits = [
        ("ia_a", g["I_TRIP_A"]), ("ib_a", g["I_TRIP_A"]), ("udc_v", g["UDC_MIN_V"]), ("udc_v", g["UDC_MAX_V"]),
        ("theta_e_rad", g["ANGLE_GUARD_RAD"]), ("omega_e_rad_s", g["OMEGA_GUARD_RAD_S"]),
        ("torque_ref_nm", g["TORQUE_REF_GUARD_NM"]),
    ]
    specials = np.array([np.nan, np.inf, -np.inf], np.float32)
    which = rng.integers(0, len(field_limits), n)
    kind = rng.integers(0, 5, n)
    for i, (name, lim) in enumerate(field_limits):
        sel = which == i
        lim32 = F(lim)
        sgn = np.where(rng.random(sel.sum()) < 0.5, F(1), F(-1)) if name != "udc_v" else F(1)
        at = (sgn * lim32).astype(np.float32)
        beyond = np.nextafter(at, (at * F(2)).astype(np.float32))
        inside = np.nextafter(at, F(0))
        special = specials[rng.integers(0, 3, sel.sum())]
        k_sel = kind[sel]
        vals = np.select([k_sel == 0, k_sel == 1, k_sel == 2], [at, beyond, inside], special)
        x[name][sel] = vals
        if name in ("ia_a", "ib_a"):  # keep the other phase small so only this limit matters
            other = "ib_a" if name == "ia_a" else "ia_a"
            x[other][sel] = 0.0
    parts.append(x)

    # every previous state, including invalid encodings, at speed zero and maximum
    n = n_target - sum(len(p) for p in parts)
    x = base(max(n, 16))
    x["prev_sw"] = np.arange(len(x)) % 10
    x["prev_sw"][x["prev_sw"] >= 8] = np.array([8, 65535], np.uint16)[x["prev_sw"][x["prev_sw"] >= 8] - 8]
    x["omega_e_rad_s"] = np.where(rng.random(len(x)) < 0.5, 0.0, F(g["OMEGA_GUARD_RAD_S"]))
    parts.append(x)
    return np.concatenate(parts)
