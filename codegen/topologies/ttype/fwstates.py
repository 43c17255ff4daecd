"""Firmware self-test states of the T-type step: guard cases, adversarial and random states."""
from __future__ import annotations

from typing import Any

import numpy as np

from codegen.model import Model
from codegen.numfmt.float32 import F
from codegen.teststates import Limit, down, guard_rows, rows_to_records, seeded_mix, up
from codegen.topologies.ttype.derive import ThreeLevelTables
from codegen.topologies.ttype.records import INPUT, INPUT_DTYPE
from codegen.topologies.ttype.states import adversarial_states, random_states

#: the float inputs of the T-type record
FLOATS = ("ia_a", "ib_a", "theta_e_rad", "omega_e_rad_s", "uc1_v", "uc2_v", "torque_ref_nm", "t_n_prev_s")


def _si(t: ThreeLevelTables, name: str) -> Any:
    """The step's own constant ``name`` as a float32 SI value (float32: the constant itself)."""
    c = next(c for c in t.consts if c.name == name)
    return F(t.nf.decode(c.unit, c.value))


def _const_limits(t: ThreeLevelTables) -> tuple[Limit, ...]:
    """The guard limits as the step's own constants (float32 SI values)."""
    lo, hi = _si(t, "UC_MIN_V"), _si(t, "UC_MAX_V")
    return (Limit("ia_a", _si(t, "I_TRIP_A")), Limit("ib_a", _si(t, "I_TRIP_A")),
            Limit("theta_e_rad", _si(t, "ANGLE_GUARD_RAD")), Limit("omega_e_rad_s", _si(t, "OMEGA_GUARD_RAD_S")),
            Limit("torque_ref_nm", _si(t, "TORQUE_REF_GUARD_NM")),
            Limit("uc1_v", lo, "lower"), Limit("uc1_v", hi, "upper"),
            Limit("uc2_v", lo, "lower"), Limit("uc2_v", hi, "upper"))


def guard_cases(model: Model, t: ThreeLevelTables) -> np.ndarray:
    """T-type fixed adversarial states: every guard limit exactly and one float32
    step beyond (the step's own float32 constants), NaN/inf in every float input,
    invalid prev_vector, t_n_prev_s out of [0, Ts/3] for a virtual previous vector."""
    udc = model.inverter.udc_v
    ts3 = _si(t, "TS3_S")
    base = {"ia_a": F(1.0), "ib_a": F(-0.5), "theta_e_rad": F(0.3), "omega_e_rad_s": F(100.0),
            "uc1_v": F(udc / 2), "uc2_v": F(udc / 2), "torque_ref_nm": F(0.5), "prev_vector": 13,
            "t_n_prev_s": F(0.0)}
    rows = guard_rows(base, FLOATS, _const_limits(t), _si(t, "I_TRIP_A"))
    # t_n_prev_s is checked for a virtual previous vector only: non-finite and both bounds
    rows += [{**base, "prev_vector": 40, "t_n_prev_s": v} for v in (F(np.nan), F(np.inf), F(-np.inf))]
    rows += [{**base, "prev_vector": p} for p in (63, 64, 255, 0xFFFF)]
    for p in (13, 26, 27, 45, 62):  # basic (t_n_prev ignored) and virtual previous vectors
        for v in (F(0), F(-0.0), down(F(0)), up(F(0)), ts3, up(ts3), down(ts3), ts3 / F(2)):
            rows.append({**base, "prev_vector": p, "t_n_prev_s": v})
    g_w = _si(t, "OMEGA_GUARD_RAD_S")
    rows += [{**base, "omega_e_rad_s": w} for w in (F(0), g_w, -g_w)]
    return rows_to_records(rows, INPUT_DTYPE)


def selftest_states(model: Model, t: ThreeLevelTables, n: int, seed: int) -> np.ndarray:
    """T-type: ``n`` deterministic self-test states: guard cases, then adversarial
    (codegen.topologies.ttype.states: sector borders, ties, angle reduction, limits, every
    prev_vector) and random states over the operating range, about half each."""
    return seeded_mix(guard_cases(model, t), n, [
        (50, lambda k: adversarial_states(model, t, max(k, 1), seed + 1)),
        (50, lambda k: random_states(model, k, seed)),
    ], INPUT.bind(t.nf))
