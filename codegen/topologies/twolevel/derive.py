"""Derived tables and float32 constants of the two-level MPTC step.

Everything the generated C and the Python reference share is computed here,
once: gains in float64 rounded once to float32 (numerics.md), the vector set,
the zero-vector choice, and the candidate rows of the strategy's switch table.
Templates only print this; the reference only reads it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from codegen.kernels.trig import ANGLE_GUARD_RAD, sincos_constants
from codegen.model import Model
from codegen.numfmt.float32 import f32
from codegen.topologies.twolevel import vectors
from codegen.units import GUARD_UNITS

#: A switch table: [condition][sector] -> candidate vectors (V0 first).
SwitchTable = tuple[tuple[tuple[int, ...], ...], ...]


@dataclass(frozen=True)
class Const:
    """One float32 constant of the step, with what it is and where it comes from."""

    name: str
    value: np.float32
    unit: str
    doc: str


@dataclass(frozen=True)
class TwoLevelTables:
    """What a two-level step needs, derived once from a Model."""

    prefix: str
    strategy: str
    predictor: str
    delay_compensation: bool
    consts: tuple[Const, ...]
    ux: tuple[np.float32, ...]  # unit vector alpha components, V0..V6
    uy: tuple[np.float32, ...]
    vec_to_sw: tuple[int, ...]
    sw_to_vec: tuple[int, ...]
    zero_sw: tuple[int, ...]
    n_conditions: int  # 1 (no table), 2 (s2: sign dT), 4 (s3: sign dT, sign dpsi)
    n_sectors: int  # 1, 6 or 12
    rows: tuple[tuple[int, ...], ...]  # candidate row = condition * n_sectors + sector
    uses_threshold: bool

    def const(self, name: str) -> np.float32:
        """Value of the constant ``name``."""
        for c in self.consts:
            if c.name == name:
                return c.value
        raise KeyError(name)

    @property
    def row_len(self) -> tuple[int, ...]:
        return tuple(len(r) for r in self.rows)


def guard_limits(model: Model) -> dict[str, float]:
    """Input-guard limits (numerics.md "Inputs are guarded"), float64."""
    m, inv, sl = model.motor, model.inverter, model.speed_loop
    rated_omega_e = m.rated_speed_rpm * 2 * math.pi / 60 * m.pole_pairs
    return {
        "I_TRIP_A": inv.i_trip_a,
        "UDC_MIN_V": inv.udc_min_v,
        "UDC_MAX_V": inv.udc_max_v,
        "ANGLE_GUARD_RAD": ANGLE_GUARD_RAD,
        "OMEGA_GUARD_RAD_S": 5.0 * rated_omega_e,
        "TORQUE_REF_GUARD_NM": 4.0 * max(sl.limit_nm, m.rated_torque_nm),
    }


def _constants(model: Model) -> list[Const]:
    m, c = model.motor, model.controller
    out: list[Const] = [Const(*c) for c in sincos_constants()]
    for name, v in guard_limits(model).items():
        out.append(Const(name, f32(v), GUARD_UNITS.get(name, ""), "input guard limit"))
    out += [
        Const("INV_SQRT3", f32(1 / math.sqrt(3)), "", "Clarke: i_beta = (i_a + 2 i_b)/sqrt(3)"),
        Const("LD_H", f32(m.ld_h), "H", "psi_d = Ld i_d + psi_f"),
        Const("LQ_H", f32(m.lq_h), "H", "psi_q = Lq i_q"),
        Const("PSI_F_WB", f32(m.psi_f_wb), "Wb", "magnet flux"),
        Const("TE_K", f32(1.5 * m.pole_pairs), "", "Te = 1.5 p (psi_d i_q - psi_q i_d)"),
        Const("PSI_REF_WB", f32(c.psi_ref_wb), "Wb", "flux reference psi*"),
        Const("INV_PSI_REF", f32(1 / c.psi_ref_wb), "1/Wb", "cost: (|psi| - psi*)/psi*"),
        Const("INV_TN", f32(1 / m.rated_torque_nm), "1/(N*m)", "cost: (Te - T*)/T_N"),
        Const("EPS_T_NM", f32(c.eps_t_nm), "N*m", "s1-s3: |dT| <= eps_T -> zero vector"),
        Const("TAN30", f32(math.tan(math.pi / 6)), "", "sector borders at 30 deg multiples"),
        Const("TAN60", f32(math.tan(math.pi / 3)), "", "tan(60 deg): sector borders"),
    ]
    if c.predictor == "flux-geometry":
        out += [
            Const("VDT_K", f32(2.0 / 3.0 * c.dt_s), "s", "psi+ = psi + V dt, |V| = 2/3 Udc"),
            Const("TE_GEO_K", f32(3 * m.pole_pairs / (2 * m.ld_h)), "1/H", "Te = 3p/(2Ld) psi_f x psi"),
        ]
    else:
        out += [
            Const("VMAG_K", f32(2.0 / 3.0), "", "|V| = 2/3 Udc"),
            Const("RS_OHM", f32(m.rs_ohm), "ohm", "stator resistance"),
            Const("A_D", f32(c.dt_s / m.ld_h), "s/H", "i_d+ = i_d + dt/Ld (u_d - Rs i_d + w Lq i_q)"),
            Const("A_Q", f32(c.dt_s / m.lq_h), "s/H", "i_q+ = i_q + dt/Lq (u_q - Rs i_q - w Ld i_d - w psi_f)"),
        ]
    return out


def table_layout(strategy: str) -> tuple[int, int, bool]:
    """(n_conditions, n_sectors, uses_threshold) of a strategy."""
    return {
        "conventional": (1, 1, False),
        "s1": (1, 1, True),
        "s2": (2, 6, True),
        "s3": (4, 12, True),
    }[strategy]


def derive_two_level(model: Model, switch_table: SwitchTable | None = None) -> TwoLevelTables:
    """Derive the step's tables.  ``switch_table`` is required for s2 and s3.

    For conventional and s1 the single row is V0..V6 in vector order.
    """
    c = model.controller
    n_cond, n_sec, thr = table_layout(c.strategy)
    if n_sec == 1:
        rows: tuple[tuple[int, ...], ...] = (tuple(range(7)),)
    else:
        if switch_table is None:
            raise ValueError(f"strategy {c.strategy} needs a switch table")
        if len(switch_table) != n_cond or any(len(r) != n_sec for r in switch_table):
            raise ValueError(f"switch table for {c.strategy} must be {n_cond} x {n_sec}")
        rows = tuple(tuple(cell) for row in switch_table for cell in row)
    ux, uy = vectors.unit_vectors()
    return TwoLevelTables(
        prefix=model.prefix,
        strategy=c.strategy,
        predictor=c.predictor,
        delay_compensation=c.delay_compensation,
        consts=tuple(_constants(model)),
        ux=tuple(f32(v) for v in ux),
        uy=tuple(f32(v) for v in uy),
        vec_to_sw=vectors.VEC_TO_SW,
        sw_to_vec=vectors.sw_to_vec(),
        zero_sw=vectors.zero_sw_table(),
        n_conditions=n_cond,
        n_sectors=n_sec,
        rows=rows,
        uses_threshold=thr,
    )
