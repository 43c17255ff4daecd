"""Firmware self-test states of the two-level step: guard cases and a random mix.

The self-test set is a deterministic mix (verification "Test states"): guard
cases (non-finite values, every guard limit exactly and one float32 step
beyond, invalid switching states, zero and extreme speed and torque) and
random states over the operating range, including T* at the eps_T threshold
and flux vectors on the 30-degree sector borders.
"""
from __future__ import annotations

import math
from functools import partial
from typing import Any

import numpy as np

from codegen.model import Model
from codegen.numfmt.float32 import F
from codegen.teststates import guard_rows, in_format, phase_currents, rows_to_records, seeded_mix
from codegen.topologies.twolevel.derive import TwoLevelTables, guard_limits
from codegen.topologies.twolevel.records import INPUT, INPUT_DTYPE
from codegen.topologies.twolevel.reference import step_batch
from codegen.topologies.twolevel.states import limits, place_flux_on_border, threshold_states

#: the float inputs of the two-level record
FLOATS = ("ia_a", "ib_a", "theta_e_rad", "omega_e_rad_s", "udc_v", "torque_ref_nm")


def _records(ia: Any, ib: Any, th: Any, om: Any, udc: Any, tref: Any, sw: Any) -> np.ndarray:
    """Input records from per-field columns (float32 fields rounded once)."""
    x = np.zeros(len(ia), INPUT_DTYPE)
    for name, col in zip(FLOATS, (ia, ib, th, om, udc, tref)):
        x[name] = np.asarray(col, F)
    x["prev_sw"] = np.asarray(sw, np.uint16)
    return x


def _operating(model: Model, rng: np.random.Generator, n: int) -> np.ndarray:
    """Random states inside the operating range (no guard trips)."""
    m, inv, sl = model.motor, model.inverter, model.speed_loop
    i_rated = m.rated_torque_nm / (1.5 * m.pole_pairs * m.psi_f_wb)
    w_rated = m.rated_speed_rpm * 2 * math.pi / 60 * m.pole_pairs
    r = np.sqrt(rng.uniform(0, 1, n)) * min(2.0 * i_rated, 0.55 * inv.i_trip_a)
    ang = rng.uniform(-math.pi, math.pi, n)
    th = rng.uniform(0, 2 * math.pi, n)
    ia, ib = phase_currents(r * np.cos(ang), r * np.sin(ang), th)
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
    """T* = Te estimate +- eps_T, and one step of the format either side (in the step's format)."""
    x = in_format(_operating(model, rng, n), INPUT.bind(t.nf))
    threshold_states(x, t, step_batch, rng)
    return x


def _borders(model: Model, rng: np.random.Generator, n: int) -> np.ndarray:
    """Stator flux on a 30-degree sector border (float rounding puts it either side)."""
    x = _operating(model, rng, n)
    x["theta_e_rad"] = rng.uniform(0, 2 * math.pi, n)
    place_flux_on_border(model, x, 0.2, rng)
    return x


def guard_cases(model: Model) -> np.ndarray:
    """Fixed adversarial states: limits exactly and one float32 step beyond, non-finite values,
    invalid switching states, speed zero and at its guard."""
    g = {k: F(v) for k, v in guard_limits(model).items()}
    base = {"ia_a": F(1.0), "ib_a": F(-0.5), "theta_e_rad": F(0.3), "omega_e_rad_s": F(100.0),
            "udc_v": F(model.inverter.udc_v), "torque_ref_nm": F(2.0), "prev_sw": 3}
    rows = guard_rows(base, FLOATS, limits(model), g["I_TRIP_A"])
    rows += [{**rows[1], "prev_sw": 0}, {**rows[2], "prev_sw": 7}]  # zeros in both zero-vector states
    rows += [{**base, "prev_sw": s} for s in (8, 9, 255, 0xFFFF)]
    rows += [{**base, "omega_e_rad_s": w} for w in (F(0), g["OMEGA_GUARD_RAD_S"], -g["OMEGA_GUARD_RAD_S"])]
    return rows_to_records(rows, INPUT_DTYPE)


def selftest_states(model: Model, t: TwoLevelTables, n: int, seed: int) -> np.ndarray:
    """Two-level: ``n`` deterministic self-test states: guard cases first, then the random mix."""
    rng = np.random.default_rng(seed)
    return seeded_mix(guard_cases(model), n, [
        (50, partial(_operating, model, rng)),
        (15, partial(_wide, model, rng)),
        (20, lambda k: _threshold(model, t, rng, k)),
        (15, partial(_borders, model, rng)),
    ], INPUT.bind(t.nf))
