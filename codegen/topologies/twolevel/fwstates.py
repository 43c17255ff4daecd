"""Firmware self-test states of the two-level step: guard cases and a random mix.

The self-test set is a deterministic mix (verification "Test states"): guard
cases (non-finite values, every guard limit exactly and one float32 step
beyond, invalid switching states, zero and extreme speed and torque) and
random states over the operating range, including T* at the eps_T threshold
and flux vectors on the 30-degree sector borders.
"""
from __future__ import annotations

import math

import numpy as np

from codegen.model import Model
from codegen.numfmt.float32 import F
from codegen.topologies.twolevel.derive import TwoLevelTables, guard_limits
from codegen.topologies.twolevel.records import INPUT_DTYPE
from codegen.topologies.twolevel.reference import step_batch


def _rated(model: Model) -> tuple[float, float]:
    """(rated current estimate, rated electrical speed) of the motor."""
    m = model.motor
    i_rated = m.rated_torque_nm / (1.5 * m.pole_pairs * m.psi_f_wb)
    w_rated = m.rated_speed_rpm * 2 * math.pi / 60 * m.pole_pairs
    return i_rated, w_rated


def _phase_currents(i_d: np.ndarray, i_q: np.ndarray, th: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    i_al = i_d * np.cos(th) - i_q * np.sin(th)
    i_be = i_d * np.sin(th) + i_q * np.cos(th)
    return i_al, (-i_al + math.sqrt(3.0) * i_be) / 2.0


def _records(ia, ib, th, om, udc, tref, sw) -> np.ndarray:
    n = len(ia)
    x = np.zeros(n, INPUT_DTYPE)
    x["ia_a"], x["ib_a"], x["theta_e_rad"] = np.asarray(ia, F), np.asarray(ib, F), np.asarray(th, F)
    x["omega_e_rad_s"], x["udc_v"] = np.asarray(om, F), np.asarray(udc, F)
    x["torque_ref_nm"], x["prev_sw"] = np.asarray(tref, F), np.asarray(sw, np.uint16)
    return x


def _operating(model: Model, rng: np.random.Generator, n: int) -> np.ndarray:
    """Random states inside the operating range (no guard trips)."""
    i_rated, w_rated = _rated(model)
    inv, sl = model.inverter, model.speed_loop
    r = np.sqrt(rng.uniform(0, 1, n)) * min(2.0 * i_rated, 0.55 * inv.i_trip_a)
    ang = rng.uniform(-math.pi, math.pi, n)
    th = rng.uniform(0, 2 * math.pi, n)
    ia, ib = _phase_currents(r * np.cos(ang), r * np.sin(ang), th)
    return _records(ia, ib, th, rng.uniform(-1.2, 1.2, n) * w_rated,
                    rng.uniform(inv.udc_min_v, inv.udc_max_v, n),
                    rng.uniform(-sl.limit_nm, sl.limit_nm, n), rng.integers(0, 8, n))


def _wide(model: Model, rng: np.random.Generator, n: int) -> np.ndarray:
    """Random states over and slightly beyond every guard limit (some trip)."""
    g = guard_limits(model)
    inv = model.inverter
    return _records(rng.uniform(-1.1, 1.1, n) * g["I_TRIP_A"], rng.uniform(-1.1, 1.1, n) * g["I_TRIP_A"],
                    rng.uniform(-1.02, 1.02, n) * g["ANGLE_GUARD_RAD"],
                    rng.uniform(-1.05, 1.05, n) * g["OMEGA_GUARD_RAD_S"],
                    rng.uniform(0.9 * inv.udc_min_v, 1.05 * inv.udc_max_v, n),
                    rng.uniform(-1.05, 1.05, n) * g["TORQUE_REF_GUARD_NM"], rng.integers(0, 10, n))


def _threshold(model: Model, t: TwoLevelTables, rng: np.random.Generator, n: int) -> np.ndarray:
    """T* = Te estimate +- eps_T, and one float32 step either side."""
    x = _operating(model, rng, n)
    te = step_batch(t, x)["te_est_nm"]
    eps = t.const("EPS_T_NM")
    sign = np.where(rng.integers(0, 2, n) == 0, F(1), F(-1))
    tref = (te + sign * eps).astype(F)
    nudge = rng.integers(-1, 2, n)
    tref = np.where(nudge > 0, np.nextafter(tref, F(np.inf)), np.where(nudge < 0, np.nextafter(tref, F(-np.inf)), tref))
    x["torque_ref_nm"] = tref.astype(F)
    return x


def _borders(model: Model, rng: np.random.Generator, n: int) -> np.ndarray:
    """Stator flux on a 30-degree sector border (float rounding puts it either side)."""
    m = model.motor
    phi = rng.integers(0, 12, n) * (math.pi / 6) + rng.choice([0.0, 1e-7, -1e-7, 1e-6, -1e-6], n)
    mag = model.controller.psi_ref_wb * rng.uniform(0.8, 1.2, n)
    th = rng.uniform(0, 2 * math.pi, n)
    i_d = (mag * np.cos(phi - th) - m.psi_f_wb) / m.ld_h
    i_q = mag * np.sin(phi - th) / m.lq_h
    ia, ib = _phase_currents(i_d, i_q, th)
    x = _operating(model, rng, n)
    x["ia_a"], x["ib_a"], x["theta_e_rad"] = ia.astype(F), ib.astype(F), th.astype(F)
    return x


def guard_cases(model: Model) -> np.ndarray:
    """Fixed adversarial states: limits exactly and one float32 step beyond, non-finite values."""
    g = {k: F(v) for k, v in guard_limits(model).items()}
    up = lambda v: np.nextafter(F(v), F(np.inf))  # noqa: E731
    down = lambda v: np.nextafter(F(v), F(-np.inf))  # noqa: E731
    inv = model.inverter
    base = (F(1.0), F(-0.5), F(0.3), F(100.0), F(inv.udc_v), F(2.0), 3)
    rows: list[tuple] = [base, (F(0), F(0), F(0), F(0), F(inv.udc_v), F(0), 0),
                         (F(-0.0), F(-0.0), F(-0.0), F(-0.0), F(inv.udc_v), F(-0.0), 7)]
    special = [F(np.nan), F(np.inf), F(-np.inf)]
    limits = {0: "I_TRIP_A", 1: "I_TRIP_A", 2: "ANGLE_GUARD_RAD", 3: "OMEGA_GUARD_RAD_S",
              5: "TORQUE_REF_GUARD_NM"}
    for col in range(6):
        for v in special:
            rows.append(base[:col] + (v,) + base[col + 1:])
        if col in limits:
            lim = g[limits[col]]
            for v in (lim, up(lim), -lim, down(-lim), down(lim)):
                r = base[:col] + (v,) + base[col + 1:]
                if col == 0:  # keep i_c = -(i_a + i_b) small so only the tested value matters
                    r = (v, -v / F(2)) + base[2:]
                rows.append(r)
    for v in (g["UDC_MIN_V"], down(g["UDC_MIN_V"]), g["UDC_MAX_V"], up(g["UDC_MAX_V"])):
        rows.append(base[:4] + (v,) + base[5:])
    # i_c alone above the trip limit; prev_sw out of range; speed zero and at the guard
    third = F(g["I_TRIP_A"] * F(0.5))
    rows.append((up(third), up(third)) + base[2:])
    rows += [base[:6] + (s,) for s in (8, 9, 255, 0xFFFF)]
    rows += [base[:3] + (w,) + base[4:] for w in (F(0), g["OMEGA_GUARD_RAD_S"], -g["OMEGA_GUARD_RAD_S"])]
    cols = list(zip(*rows))
    return _records(*cols)


def selftest_states(model: Model, t: TwoLevelTables, n: int, seed: int) -> np.ndarray:
    """Two-level: ``n`` deterministic self-test states: guard cases first, then the random mix."""
    if n < 1:
        raise ValueError("n must be >= 1")
    rng = np.random.default_rng(seed)
    fixed = guard_cases(model)
    rest = max(0, n - len(fixed))
    parts = [fixed,
             _operating(model, rng, rest * 50 // 100),
             _wide(model, rng, rest * 15 // 100),
             _threshold(model, t, rng, rest * 20 // 100)]
    parts.append(_borders(model, rng, rest - sum(len(p) for p in parts[1:])))
    return np.concatenate(parts)[:n]
