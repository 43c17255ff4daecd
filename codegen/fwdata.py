"""Test data embedded in a firmware image: states, expected outputs, digests.

The self-test set is a deterministic mix (numerics.md "Test states"): guard
cases (non-finite values, every guard limit exactly and one float32 step
beyond, invalid switching states, zero and extreme speed and torque) and
random states over the operating range, including T* at the eps_T threshold
and flux vectors on the 30-degree sector borders.  The bench set is a
recorded closed-loop trajectory of the config's own scenario.  Expected
outputs always come from the Python reference ``step_batch``.

Digests: CRC-32 (zlib) of every value in interface order, a float32 as its 4
little-endian octets, a uint16 as 2 (the firmware's ``mpc_values_crc``).
"""
from __future__ import annotations

import math
import zlib
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from .model import Model
from .twolevel.derive import TwoLevelTables, guard_limits
from .twolevel.interface import INPUT_DTYPE, INPUT_FIELDS, OUTPUT_DTYPE, OUTPUT_FIELDS, Field
from .twolevel.reference import step_batch

#: Seed of the self-test states (the set is a pure function of config and n).
SELFTEST_SEED = 20240604
F = np.float32


@dataclass(frozen=True)
class Value:
    """One flattened value of a record: printed name, kind, C read expression."""

    name: str
    kind: str  # "MPC_VALUE_F32" | "MPC_VALUE_U16"
    read: str  # C expression with REC for the record pointer


def flat_values(fields: tuple[Field, ...]) -> list[Value]:
    """The values of a record in interface order (array fields element by element)."""
    out: list[Value] = []
    for f in fields:
        idx = [f"[{j}]" for j in range(f.length)] if f.length > 1 else [""]
        for s in idx:
            if f.ctype == "float":
                out.append(Value(f.name + s, "MPC_VALUE_F32", f"mpc_f32_bits(REC->{f.name}{s})"))
            else:
                out.append(Value(f.name + s, "MPC_VALUE_U16", f"(uint32_t)REC->{f.name}{s}"))
    return out


def _packed_dtype(fields: tuple[Field, ...]) -> np.dtype:
    code = {"float": "<f4", "uint16_t": "<u2"}
    return np.dtype([(f.name, code[f.ctype], (f.length,)) if f.length > 1 else (f.name, code[f.ctype])
                     for f in fields])


def canonical_bytes(records: np.ndarray, fields: tuple[Field, ...]) -> np.ndarray:
    """(n, octets) uint8 array: each record's values, little-endian, no padding."""
    dt = _packed_dtype(fields)
    packed = np.zeros(len(records), dt)
    for f in fields:
        packed[f.name] = records[f.name]
    return packed.view(np.uint8).reshape(len(records), dt.itemsize)


def values_crc(records: np.ndarray, fields: tuple[Field, ...]) -> int:
    """CRC-32 of every value of every record (the firmware's crc_in / crc_out)."""
    return zlib.crc32(canonical_bytes(records, fields).tobytes()) & 0xFFFFFFFF


def record_crcs(records: np.ndarray, fields: tuple[Field, ...]) -> list[int]:
    """CRC-32 of each record's values (compact expected outputs)."""
    return [zlib.crc32(row.tobytes()) & 0xFFFFFFFF for row in canonical_bytes(records, fields)]


# ---------------------------------------------------------------- states

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
    x["torque_ref_nm"], x["sw_prev"] = np.asarray(tref, F), np.asarray(sw, np.uint16)
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
    te = step_batch(t, x)["te_nm"]
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
    # i_c alone above the trip limit; sw_prev out of range; speed zero and at the guard
    third = F(g["I_TRIP_A"] * F(0.5))
    rows.append((up(third), up(third)) + base[2:])
    rows += [base[:6] + (s,) for s in (8, 9, 255, 0xFFFF)]
    rows += [base[:3] + (w,) + base[4:] for w in (F(0), g["OMEGA_GUARD_RAD_S"], -g["OMEGA_GUARD_RAD_S"])]
    cols = list(zip(*rows))
    return _records(*cols)


def _selftest_states2(model: Model, t: TwoLevelTables, n: int, seed: int = SELFTEST_SEED) -> np.ndarray:
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


def _trajectory_states2(model: Model, t: TwoLevelTables, n: int) -> np.ndarray:
    """Two-level: ``n`` states evenly spaced over the conventional controller's closed-loop run.

    Every strategy is benchmarked on the same recorded trajectory (that of
    the conventional variant, as seed 001 section 7 does).  Runs the compiled simulator (host build of the generated controller with
    the float64 plant, codegen.simulate) and keeps the controller inputs of
    periods spaced evenly over the whole scenario.  The host build is taken
    under a file lock (parallel test workers share the build cache).
    """
    import fcntl

    from .hostbuild import build_host_library, cache_root
    from .simulate import controller_inputs, run_closed_loop
    from .twolevel.derive import derive_two_level

    model = model.with_controller(strategy="conventional")
    t = derive_two_level(model)

    # parallel test workers may build the same cached library: one at a time
    cache_root().mkdir(parents=True, exist_ok=True)
    with open(cache_root() / f"{model.prefix}.fwdata.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        lib = build_host_library(model, t, with_sim=True)
    trace = run_closed_loop(lib.ffi, lib.lib, model)
    return _evenly_spaced(controller_inputs(trace, model), n)


def _evenly_spaced(x: np.ndarray, n: int) -> np.ndarray:
    idx = np.linspace(0, len(x) - 1, num=min(n, len(x))).round().astype(np.intp)
    return x[idx]


# ---------------------------------------------------------------- three-level states

def guard_cases3(model: Model, t: Any) -> np.ndarray:
    """Three-level fixed adversarial states: every guard limit exactly and one float32
    step beyond (the step's own float32 constants), NaN/inf in every float input,
    invalid prev_vector, t_n_prev_s out of [0, Ts/3] for a virtual previous vector."""
    from .threelevel.interface import INPUT_DTYPE as IN3

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
    x = np.zeros(len(rows), IN3)
    for i, r in enumerate(rows):
        for k, v in r.items():
            x[k][i] = v
    return x


def _selftest_states3(model: Model, t: Any, n: int, seed: int = SELFTEST_SEED) -> np.ndarray:
    """Three-level: ``n`` deterministic self-test states: guard cases, then adversarial
    (codegen.threelevel.states: sector borders, ties, angle reduction, limits, every
    prev_vector) and random states over the operating range, about half each."""
    from .threelevel.states import adversarial_states, random_states

    if n < 1:
        raise ValueError("n must be >= 1")
    fixed = guard_cases3(model, t)
    rest = max(0, n - len(fixed))
    adv = adversarial_states(model, t, max(rest // 2, 1), seed + 1)[: rest // 2]
    rnd = random_states(model, rest - len(adv), seed)
    return np.concatenate([fixed, adv, rnd])[:n]


def _trajectory_states3(model: Model, t: Any, n: int) -> np.ndarray:
    """Three-level: ``n`` states evenly spaced over the 27-MPDTC run at rated speed and
    rated torque (``codegen.runs3l.steady_model``), the trajectory every three-level
    strategy is benchmarked on (as ``mpcgen bench`` does on the host)."""
    import fcntl

    from .hostbuild import cache_root
    from .runs3l import steady_model
    from .simulate3l import controller_inputs3, run_closed_loop3
    from .threelevel.derive import derive_three_level
    from .threelevel.hostbuild import build_three_level_library

    model = steady_model(model.with_controller(strategy="mpdtc27"), model.motor.rated_speed_rpm)
    t = derive_three_level(model)
    cache_root().mkdir(parents=True, exist_ok=True)
    with open(cache_root() / f"{model.prefix}.fwdata3l.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        lib = build_three_level_library(model, t, with_sim=True)
    trace = run_closed_loop3(lib.ffi, lib.lib, model)
    return _evenly_spaced(controller_inputs3(trace, model), n)


# ---------------------------------------------------------------- topology adapter

def _render2(model: Model, t: Any, target: str) -> dict[str, str]:
    from .render import render_two_level

    return render_two_level(model, t, target)


def _render3(model: Model, t: Any, target: str) -> dict[str, str]:
    from .threelevel.render import render_three_level

    return render_three_level(model, t, target)


def _step3(t: Any, x: np.ndarray) -> np.ndarray:
    from .threelevel.reference import step_batch as step3

    return step3(t, x)


@dataclass(frozen=True)
class Topology:
    """What the firmware projects need of one inverter topology's controller."""

    name: str  # model.inverter.topology
    input_fields: tuple[Field, ...]
    output_fields: tuple[Field, ...]
    input_dtype: np.dtype
    output_dtype: np.dtype
    reference: str  # dotted name of the reference step (for generated comments)
    step_batch: Callable[[Any, np.ndarray], np.ndarray]
    render: Callable[[Model, Any, str], dict[str, str]]  # (model, tables, target) -> files
    selftest_states: Callable[..., np.ndarray]  # (model, tables, n, seed)
    trajectory_states: Callable[[Model, Any, int], np.ndarray]  # (model, tables, n)
    trajectory_doc: str


def _three_level() -> Topology:
    from .threelevel import interface as i3

    return Topology("t-type", i3.INPUT_FIELDS, i3.OUTPUT_FIELDS, i3.INPUT_DTYPE, i3.OUTPUT_DTYPE,
                    "codegen.threelevel.reference.step_batch", _step3, _render3, _selftest_states3,
                    _trajectory_states3, "states evenly spaced over the 27-MPDTC run at rated speed")


TWO_LEVEL = Topology("two-level", INPUT_FIELDS, OUTPUT_FIELDS, INPUT_DTYPE, OUTPUT_DTYPE,
                     "codegen.twolevel.reference.step_batch", step_batch, _render2, _selftest_states2,
                     _trajectory_states2, "states evenly spaced over the closed-loop scenario")
_TOPOLOGIES: dict[str, Callable[[], Topology]] = {"two-level": lambda: TWO_LEVEL, "t-type": _three_level}


def topology_of(model: Model) -> Topology:
    """The adapter of ``model.inverter.topology``."""
    return _TOPOLOGIES[model.inverter.topology]()


def _topology_of_tables(t: Any) -> Topology:
    return TWO_LEVEL if isinstance(t, TwoLevelTables) else _three_level()


def selftest_states(model: Model, t: Any, n: int, seed: int = SELFTEST_SEED) -> np.ndarray:
    """``n`` deterministic self-test states of the model's topology (guard cases first)."""
    return topology_of(model).selftest_states(model, t, n, seed)


def trajectory_states(model: Model, t: Any, n: int) -> np.ndarray:
    """``n`` states evenly spaced over the topology's recorded benchmark trajectory."""
    return topology_of(model).trajectory_states(model, t, n)


def expected_outputs(t: Any, states: np.ndarray) -> np.ndarray:
    """The reference's outputs; every float output must be finite (numerics.md)."""
    topo = _topology_of_tables(t)
    out = topo.step_batch(t, states)
    for f in topo.output_fields:
        if f.ctype == "float" and not np.all(np.isfinite(out[f.name])):
            raise ValueError(f"reference output {f.name} is not finite for some state (input guard bug)")
    return out


def record_dicts(records: np.ndarray, fields: tuple[Field, ...]) -> list[dict]:
    """Plain Python rows for the templates (float32 values as exact Python floats)."""
    cols = {f.name: records[f.name].tolist() for f in fields}
    return [{f.name: cols[f.name][i] for f in fields} for i in range(len(records))]


__all__ = ["INPUT_FIELDS", "OUTPUT_FIELDS", "SELFTEST_SEED", "Topology", "TWO_LEVEL", "topology_of",
           "guard_cases3", "Value", "flat_values", "canonical_bytes",
           "values_crc", "record_crcs", "guard_cases", "selftest_states", "trajectory_states",
           "expected_outputs", "record_dicts"]
