"""Building blocks of the topologies' verification and firmware self-test states.

Every topology generates (numerics.md "Test states") random states over its
operating range, adversarial states (borders, ties, guard limits, non-finite
values) and a fixed set of firmware guard cases.  What does not depend on the
topology lives here: currents from dq values, the angle-reduction borders,
torque references on the eps_T threshold, values exactly at a guard limit and
one float32 step beyond, non-finite values in every float field, guard-case
rows around a base state and the seeded mixes.  The topology packages import
this module, never each other.

All generators are deterministic for a given ``numpy.random.Generator`` and
vectorised; values are float32 where they enter a record.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from codegen.numfmt.float32 import F
from codegen.records import REAL, RecordLayout

__all__ = [
    "NON_FINITE", "Limit", "phase_currents", "random_currents_and_motion", "random_torque_ref",
    "angle_reduction_borders", "threshold_torque_refs", "apply_limit_cases", "up", "down",
    "guard_rows", "rows_to_records", "seeded_mix", "in_format",
]

#: the non-finite float32 values every float input is tested with
NON_FINITE = np.array([np.nan, np.inf, -np.inf], np.float32)

#: phase-current field -> the other measured phase (kept small when one phase is at its limit)
PHASE_PARTNERS: Mapping[str, str] = {"ia_a": "ib_a", "ib_a": "ia_a"}


def up(v: float | np.floating) -> np.float32:
    """The next float32 above ``v`` (``v`` rounded to float32 first)."""
    return np.nextafter(F(v), F(np.inf))


def down(v: float | np.floating) -> np.float32:
    """The next float32 below ``v`` (``v`` rounded to float32 first)."""
    return np.nextafter(F(v), F(-np.inf))


@dataclass(frozen=True)
class Limit:
    """One guard limit of a float input field.

    ``side`` says where "beyond" is: ``"both"`` a symmetric limit ``|x| <= value``,
    ``"upper"`` ``x <= value``, ``"lower"`` ``x >= value``."""

    field: str
    value: float
    side: Literal["both", "upper", "lower"] = "both"

    def outward(self, at: np.ndarray) -> np.ndarray:
        """+inf or -inf per value: the direction in which ``at`` leaves the allowed range."""
        if self.side == "upper":
            return np.full(at.shape, np.inf, np.float32)
        if self.side == "lower":
            return np.full(at.shape, -np.inf, np.float32)
        return np.where(np.signbit(at), F(-np.inf), F(np.inf)).astype(np.float32)


def phase_currents(i_d: np.ndarray, i_q: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Measured phase currents (i_a, i_b) of the dq currents at electrical angle ``theta``
    (inverse Park, then inverse amplitude-invariant Clarke), in float64."""
    c, s = np.cos(theta), np.sin(theta)
    i_alpha = i_d * c - i_q * s
    i_beta = i_d * s + i_q * c
    return i_alpha, (-i_alpha + math.sqrt(3.0) * i_beta) / 2.0


def random_currents_and_motion(x: np.ndarray, g: Mapping[str, float], rng: np.random.Generator) -> None:
    """Fill ``ia_a``, ``ib_a``, ``theta_e_rad``, ``omega_e_rad_s`` of ``x`` with random values over
    the operating range and a little beyond (``g``: the guard limits ``I_TRIP_A``,
    ``OMEGA_GUARD_RAD_S``): 5 % of the angles far outside one turn, 10 % of the speeds wide."""
    n = len(x)
    i_max = 1.03 * g["I_TRIP_A"] / 2
    x["ia_a"] = rng.uniform(-i_max, i_max, n)
    x["ib_a"] = rng.uniform(-i_max, i_max, n)
    wide = rng.random(n) < 0.05
    x["theta_e_rad"] = np.where(wide, rng.uniform(-260, 260, n), rng.uniform(0, 2 * math.pi, n))
    w = 1.01 * g["OMEGA_GUARD_RAD_S"]
    x["omega_e_rad_s"] = np.where(rng.random(n) < 0.9, rng.uniform(-w / 5, w / 5, n), rng.uniform(-w, w, n))


def random_torque_ref(n: int, g: Mapping[str, float], rng: np.random.Generator) -> np.ndarray:
    """``n`` random torque references: 90 % within a quarter of the guard, the rest up to 1 % beyond it."""
    t = 1.01 * g["TORQUE_REF_GUARD_NM"]
    return np.where(rng.random(n) < 0.9, rng.uniform(-t / 4, t / 4, n), rng.uniform(-t, t, n))


def angle_reduction_borders(n: int, angle_guard: float, table_n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` float32 angles on the borders of the sin/cos angle reduction of a ``table_n``-entry
    table (codegen.kernels.trig): multiples of pi/table_n (its table points and the rounding borders
    halfway between them) within the guard, one float32 step either side of them, and first 0, -0
    and the guard limit of either sign."""
    k_max = math.floor(angle_guard * table_n / math.pi)
    k = rng.integers(-k_max, k_max + 1, n)
    th = (k * (math.pi / table_n)).astype(np.float32)
    th = np.where(rng.random(n) < 0.5, np.nextafter(th, F(np.inf)), th)
    th = np.where(rng.random(n) < 0.3, np.nextafter(th, F(-np.inf)), th)
    th = np.clip(th, -angle_guard, angle_guard).astype(np.float32)
    th[:4] = [0.0, -0.0, angle_guard, -angle_guard][: min(4, n)]
    return th


def in_format(x: np.ndarray, layout: RecordLayout, source: RecordLayout | None = None) -> np.ndarray:
    """States built as float32 SI values (the builders here), or records of ``source`` (another number
    format's layout of the same record), as input records of ``layout`` (the input record in the
    step's number format): each real field decoded to SI float64 and encoded once (fixed point: round
    half up, saturated, NaN -> 0, so the guard-limit and non-finite cases land on the format's
    extremes), the other fields copied.  Float32 SI records already in the format are returned as
    they are."""
    if source is None and x.dtype == layout.dtype:
        return x
    out = layout.zeros(len(x))
    for f in layout.fields:
        if f.kind != REAL:
            out[f.name] = x[f.name]
            continue
        si = source.decode(f.name, x[f.name]) if source is not None else x[f.name].astype(np.float64)
        out[f.name] = layout.encode(f.name, si)
    return out


def threshold_torque_refs(te: np.ndarray, eps: np.generic, rng: np.random.Generator) -> np.ndarray:
    """Torque references exactly at the torque-error threshold ``te +- eps`` (the step's own
    torque estimate ``te`` and threshold ``eps``, in the step's format), a third of them one step of
    the format (a float32 ulp, or one fixed-point count) above and a third one below."""
    n = len(te)
    if np.issubdtype(te.dtype, np.integer):
        sign = np.where(rng.random(n) < 0.5, 1, -1)
        tref = te.astype(np.int64) + sign * int(eps) + rng.integers(-1, 2, n)
        return np.clip(tref, -(2**31), 2**31 - 1).astype(te.dtype)
    sign = np.where(rng.random(n) < 0.5, F(1), F(-1))
    tref = (te + sign * eps).astype(np.float32)
    step = rng.integers(-1, 2, n)
    return np.where(step > 0, np.nextafter(tref, F(np.inf)),
                    np.where(step < 0, np.nextafter(tref, F(-np.inf)), tref)).astype(np.float32)


def apply_limit_cases(x: np.ndarray, limits: Sequence[Limit], rng: np.random.Generator) -> np.ndarray:
    """Put one guard case in every row of ``x`` (in place) and return which limit each row tests.

    Each row takes a random limit of ``limits`` and one of five kinds: exactly at the limit
    (passes), one float32 step beyond (trips), one step inside, or a non-finite value (two
    kinds: NaN, +inf or -inf).  A symmetric limit is taken with a random sign.  When a phase
    current is tested, the other phase is set to zero so that only the tested value matters."""
    n = len(x)
    which = rng.integers(0, len(limits), n)
    kind = rng.integers(0, 5, n)
    for i, lim in enumerate(limits):
        sel = which == i
        m = int(sel.sum())
        sign = np.where(rng.random(m) < 0.5, F(1), F(-1)) if lim.side == "both" else F(1)
        at = np.asarray(sign * F(lim.value), dtype=np.float32)
        beyond = np.nextafter(at, lim.outward(at))
        inside = np.nextafter(at, -lim.outward(at))
        special = NON_FINITE[rng.integers(0, 3, m)]
        k = kind[sel]
        x[lim.field][sel] = np.select([k == 0, k == 1, k == 2], [at, beyond, inside], special)
        if lim.field in PHASE_PARTNERS:
            x[PHASE_PARTNERS[lim.field]][sel] = 0.0
    return which


def guard_rows(base: Mapping[str, object], floats: Sequence[str], limits: Sequence[Limit],
               i_trip: np.float32) -> list[dict[str, object]]:
    """Fixed guard cases around the valid state ``base``, one changed input per row:

    * ``base`` itself, all-zero and all-negative-zero currents, angle, speed and torque;
    * NaN, +inf and -inf in every field of ``floats``;
    * every limit exactly, one float32 step beyond and one step inside (a symmetric limit
      with both signs); a phase current at its limit keeps i_c = -(i_a + i_b) small;
    * i_c alone one step above the trip limit ``i_trip`` (i_a = i_b just above i_trip / 2).
    """
    zeroed = ("ia_a", "ib_a", "theta_e_rad", "omega_e_rad_s", "torque_ref_nm")
    rows: list[dict[str, object]] = [dict(base), {**base, **{k: F(0) for k in zeroed}},
                                     {**base, **{k: F(-0.0) for k in zeroed}}]
    rows += [{**base, name: v} for name in floats for v in NON_FINITE]
    for lim in limits:
        v = F(lim.value)
        values: tuple[np.float32, ...]
        if lim.side == "both":
            values = (v, up(v), down(v), -v, down(-v), up(-v))
        elif lim.side == "upper":
            values = (v, up(v), down(v))
        else:
            values = (v, down(v), up(v))
        for value in values:
            row = {**base, lim.field: value}
            if lim.field in PHASE_PARTNERS:
                row[PHASE_PARTNERS[lim.field]] = F(-value / F(2))
            rows.append(row)
    half = F(i_trip * F(0.5))
    rows.append({**base, "ia_a": up(half), "ib_a": up(half)})
    return rows


def rows_to_records(rows: Sequence[Mapping[str, object]], dtype: np.dtype) -> np.ndarray:
    """Input records of ``dtype`` from rows of field values (fields a row omits stay zero)."""
    x = np.zeros(len(rows), dtype)
    for i, row in enumerate(rows):
        for name, value in row.items():
            x[name][i] = value
    return x


def seeded_mix(fixed: np.ndarray, n: int,
               parts: Sequence[tuple[int, Callable[[int], np.ndarray]]], layout: RecordLayout) -> np.ndarray:
    """``n`` states of ``layout`` (the input record in the step's format): ``fixed`` first, then the
    rest shared among ``parts``.

    ``parts`` are (percent, generator) pairs; generator(k) returns at least k states (float32 SI
    or already in the format: each part goes through :func:`in_format`); the last part takes
    whatever the percentages leave."""
    if n < 1:
        raise ValueError("n must be >= 1")
    rest = max(0, n - len(fixed))
    out = [in_format(fixed, layout)]
    used = 0
    for i, (percent, make) in enumerate(parts):
        k = rest - used if i == len(parts) - 1 else rest * percent // 100
        out.append(in_format(make(k)[:k], layout))
        used += k
    return np.concatenate(out)[:n]
