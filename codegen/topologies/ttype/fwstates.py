"""Firmware self-test states of the T-type step: guard cases, adversarial and random states."""
from __future__ import annotations

import numpy as np

from codegen.model import Model
from codegen.numfmt.float32 import F
from codegen.topologies.ttype.derive import ThreeLevelTables
from codegen.topologies.ttype.records import INPUT_DTYPE
from codegen.topologies.ttype.states import adversarial_states, random_states


def guard_cases(model: Model, t: ThreeLevelTables) -> np.ndarray:
    """Three-level fixed adversarial states: every guard limit exactly and one float32
    step beyond (the step's own float32 constants), NaN/inf in every float input,
    invalid prev_vector, t_n_prev_s out of [0, Ts/3] for a virtual previous vector."""
    up = lambda v: np.nextafter(F(v), F(np.inf))  # noqa: E731
    down = lambda v: np.nextafter(F(v), F(-np.inf))  # noqa: E731
    udc = model.inverter.udc_v
    ts3 = t.const("TS3_S")
    base = {"ia_a": F(1.0), "ib_a": F(-0.5), "theta_e_rad": F(0.3), "omega_e_rad_s": F(100.0),
            "uc1_v": F(udc / 2), "uc2_v": F(udc / 2), "torque_ref_nm": F(0.5), "prev_vector": 13,
            "t_n_prev_s": F(0.0)}
    rows: list[dict] = [dict(base), {**base, "ia_a": F(0), "ib_a": F(0), "theta_e_rad": F(0), "omega_e_rad_s": F(0),
                                     "torque_ref_nm": F(0)},
                        {**base, "ia_a": F(-0.0), "ib_a": F(-0.0), "theta_e_rad": F(-0.0),
                         "omega_e_rad_s": F(-0.0), "torque_ref_nm": F(-0.0)}]
    floats = ("ia_a", "ib_a", "theta_e_rad", "omega_e_rad_s", "uc1_v", "uc2_v", "torque_ref_nm")
    for name in floats:
        for v in (F(np.nan), F(np.inf), F(-np.inf)):
            rows.append({**base, name: v})
    rows.append({**base, "prev_vector": 40, "t_n_prev_s": F(np.nan)})
    signed = {"ia_a": "I_TRIP_A", "ib_a": "I_TRIP_A", "theta_e_rad": "ANGLE_GUARD_RAD",
              "omega_e_rad_s": "OMEGA_GUARD_RAD_S", "torque_ref_nm": "TORQUE_REF_GUARD_NM"}
    for name, c in signed.items():
        lim = t.const(c)
        for v in (lim, up(lim), -lim, down(-lim), down(lim)):
            r = {**base, name: v}
            if name == "ia_a":  # keep i_c = -(i_a + i_b) small so only the tested value matters
                r["ib_a"] = F(-v / F(2))
            elif name == "ib_a":
                r["ia_a"] = F(-v / F(2))
            rows.append(r)
    lo, hi = t.const("UC_MIN_V"), t.const("UC_MAX_V")
    for name in ("uc1_v", "uc2_v"):
        for v in (lo, down(lo), up(lo), hi, up(hi), down(hi)):
            rows.append({**base, name: v})
    third = F(t.const("I_TRIP_A") * F(0.5))  # i_c alone above the trip limit
    rows.append({**base, "ia_a": up(third), "ib_a": up(third)})
    rows += [{**base, "prev_vector": p} for p in (63, 64, 255, 0xFFFF)]
    for p in (13, 26, 27, 45, 62):  # basic (t_n_prev ignored) and virtual previous vectors
        for v in (F(0), F(-0.0), down(F(0)), ts3, up(ts3), t.const("TS3_S") / F(2)):
            rows.append({**base, "prev_vector": p, "t_n_prev_s": v})
    g_w = t.const("OMEGA_GUARD_RAD_S")
    rows += [{**base, "omega_e_rad_s": w} for w in (F(0), g_w, -g_w)]
    x = np.zeros(len(rows), INPUT_DTYPE)
    for i, r in enumerate(rows):
        for k, v in r.items():
            x[k][i] = v
    return x


def selftest_states(model: Model, t: ThreeLevelTables, n: int, seed: int) -> np.ndarray:
    """Three-level: ``n`` deterministic self-test states: guard cases, then adversarial
    (codegen.topologies.ttype.states: sector borders, ties, angle reduction, limits, every
    prev_vector) and random states over the operating range, about half each."""
    if n < 1:
        raise ValueError("n must be >= 1")
    fixed = guard_cases(model, t)
    rest = max(0, n - len(fixed))
    adv = adversarial_states(model, t, max(rest // 2, 1), seed + 1)[: rest // 2]
    rnd = random_states(model, rest - len(adv), seed)
    return np.concatenate([fixed, adv, rnd])[:n]
