"""Test states for bit-for-bit verification (numerics.md "Test states").

(a) closed-loop states come from ``codegen.simulate`` traces (see verify.py);
(b) random states across the whole operating range (and a little beyond, so
    the guard is exercised); (c) adversarial states: sector borders, quadrant
    borders of the angle reduction, T* exactly at the threshold and one ulp
    either side, equal costs, guard limits exactly and one ulp beyond, NaN and
    infinities in every field, zero and maximum speed, every previous state.
All generators are deterministic for a given seed and vectorised; the
topology-independent pieces are :mod:`codegen.teststates`.
"""
from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from codegen import teststates as common
from codegen.model import Model
from codegen.numfmt.float32 import F
from codegen.topologies.twolevel.derive import TwoLevelTables, guard_limits
from codegen.topologies.twolevel.records import INPUT, INPUT_DTYPE

#: the reference step over a batch (``reference.step_batch``)
StepBatch = Callable[[TwoLevelTables, np.ndarray], np.ndarray]


def random_states(model: Model, n: int, seed: int = 1) -> np.ndarray:
    """``n`` random states over the operating range (about 3 % trip the guard), float32 SI values
    (``common.in_format`` converts them to the step's format)."""
    rng = np.random.default_rng(seed)
    g = guard_limits(model)
    x = np.zeros(n, INPUT_DTYPE)
    common.random_currents_and_motion(x, g, rng)
    lo, hi = g["UDC_MIN_V"], g["UDC_MAX_V"]
    x["udc_v"] = rng.uniform(lo - 0.01 * (hi - lo), hi + 0.01 * (hi - lo), n)
    x["torque_ref_nm"] = common.random_torque_ref(n, g, rng)
    x["prev_sw"] = np.where(rng.random(n) < 0.002, rng.integers(8, 65536, n), rng.integers(0, 8, n))
    return x


def limits(model: Model) -> tuple[common.Limit, ...]:
    """Every guard limit of the two-level input record."""
    g = guard_limits(model)
    return (common.Limit("ia_a", g["I_TRIP_A"]), common.Limit("ib_a", g["I_TRIP_A"]),
            common.Limit("udc_v", g["UDC_MIN_V"], "lower"), common.Limit("udc_v", g["UDC_MAX_V"], "upper"),
            common.Limit("theta_e_rad", g["ANGLE_GUARD_RAD"]), common.Limit("omega_e_rad_s", g["OMEGA_GUARD_RAD_S"]),
            common.Limit("torque_ref_nm", g["TORQUE_REF_GUARD_NM"]))


def place_flux_on_border(model: Model, x: np.ndarray, spread: float, rng: np.random.Generator) -> None:
    """Set the phase currents of ``x`` (in place) so that the flux the step takes its sector from is on
    a 30-degree border (or 1e-7 / 1e-6 rad next to it), magnitude psi_ref * (1 +- ``spread``).

    Without delay compensation that is the flux at k.  With it, the step advances to k+1 under the
    applied vector: those states get a zero vector (prev_sw 000 or 111) and speed zero, so
    flux-geometry keeps psi(k+1) = psi(k), and dq-euler gives i(k+1) = (1 - dt Rs/L) i(k) per axis,
    which is inverted here."""
    m, c = model.motor, model.controller
    n = len(x)
    theta = x["theta_e_rad"].astype(np.float64)
    ang = rng.integers(0, 12, n) * (math.pi / 6) + rng.choice([0.0, 1e-7, -1e-7, 1e-6, -1e-6], n)
    mag = c.psi_ref_wb * rng.uniform(1 - spread, 1 + spread, n)
    i_d = (mag * np.cos(ang - theta) - m.psi_f_wb) / m.ld_h
    i_q = mag * np.sin(ang - theta) / m.lq_h
    if c.delay_compensation:
        x["prev_sw"] = rng.choice([0, 7], n)
        x["omega_e_rad_s"] = 0.0
        if c.predictor == "dq-euler":
            i_d = i_d / (1.0 - c.dt_s * m.rs_ohm / m.ld_h)
            i_q = i_q / (1.0 - c.dt_s * m.rs_ohm / m.lq_h)
    x["ia_a"], x["ib_a"] = common.phase_currents(i_d, i_q, theta)


def threshold_states(x: np.ndarray, t: TwoLevelTables, reference_step: StepBatch, rng: np.random.Generator) -> None:
    """Set T* of ``x`` exactly at the s1-s3 decision border (estimate +- eps_T) and one ulp either side."""
    te = reference_step(t, x)["te_est_nm"]
    x["torque_ref_nm"] = common.threshold_torque_refs(te, t.const("EPS_T_NM"), rng)


def adversarial_states(model: Model, t: TwoLevelTables, reference_step: StepBatch, n_target: int = 200_000,
                       seed: int = 2) -> np.ndarray:
    """Adversarial states in the step's format (``t.nf``); ``reference_step(t, x)`` is used to place T*
    exactly at the threshold."""
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
    x = base(n_target // 5)
    place_flux_on_border(model, x, 0.1, rng)
    parts.append(x)

    # sin/cos angle-reduction borders: multiples of pi/N, +-0, one ulp either side
    x = base(n_target // 10)
    x["theta_e_rad"] = common.angle_reduction_borders(len(x), g["ANGLE_GUARD_RAD"], t.nf.sincos_form.table_n, rng)
    parts.append(x)

    # T* exactly at the threshold and one ulp either side (s1-s3 decision border)
    x = common.in_format(base(n_target // 5), INPUT.bind(t.nf))
    threshold_states(x, t, reference_step, rng)
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

    # guard limits: exactly at the limit (passes), one ulp beyond (trips), one inside, NaN, inf
    x = base(n_target // 5)
    common.apply_limit_cases(x, limits(model), rng)
    parts.append(x)

    # every previous state, including invalid encodings, at speed zero and maximum
    n = n_target - sum(len(p) for p in parts)
    x = base(max(n, 16))
    x["prev_sw"] = np.arange(len(x)) % 10
    x["prev_sw"][x["prev_sw"] >= 8] = np.array([8, 65535], np.uint16)[x["prev_sw"][x["prev_sw"] >= 8] - 8]
    x["omega_e_rad_s"] = np.where(rng.random(len(x)) < 0.5, 0.0, F(g["OMEGA_GUARD_RAD_S"]))
    parts.append(x)
    return np.concatenate([common.in_format(p, INPUT.bind(t.nf)) for p in parts])
