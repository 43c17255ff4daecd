"""Derived tables and float32 constants of the three-level MPDTC step.

Everything the generated C (templates/ttype) and the Python reference
(``reference.py``) share is computed here, once: gains in float64 rounded
once to float32 (numerics.md), the per-state unit voltages and neutral-point
coefficients, the 63 vectors' period-average voltages and 7-segment
sequences, and the candidate rows flattened into C arrays.

Candidate layout (both strategies):
  row r -> row_n[r] groups, row_groups[r][j] = index into the group table;
  group g -> group_n[g] members, group_members[g][m] = vector id 0..62.
- mpdtc63: 27 x 12 rows, r = prev_state * 12 + sector (``candidates``:
  derived Table 3; prev_state = end state of prev_vector).
- mpdtc27: one row, the 19 basic vectors u0..u18, each a group of its
  redundant states (u0: OOO, NNN, PPP; small pairs: N-type, P-type).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from codegen.kernels.trig import ANGLE_GUARD_RAD, sincos_constants
from codegen.model import Model
from codegen.numfmt.float32 import f32
from codegen.topologies.ttype import candidates as cd
from codegen.topologies.ttype import vectors as v
from codegen.topologies.ttype import virtual as vv
from codegen.topologies.twolevel.derive import Const
from codegen.units import GUARD_UNITS


@dataclass(frozen=True)
class ThreeLevelTables:
    """What a three-level step needs, derived once from a Model."""

    prefix: str
    strategy: str  # 'mpdtc27' | 'mpdtc63'
    consts: tuple[Const, ...]
    # per state (27): neutral-point coefficients i_o = ka i_a + kb i_b + kc i_c
    io_a: tuple[np.float32, ...]
    io_b: tuple[np.float32, ...]
    io_c: tuple[np.float32, ...]
    # per vector id (63): period-average voltage / Udc, virtual flag, 7 states
    ux: tuple[np.float32, ...]
    uy: tuple[np.float32, ...]
    is_virtual: tuple[int, ...]
    seq: tuple[tuple[int, ...], ...]
    end_state: tuple[int, ...]
    n_sectors: int  # 12 (mpdtc63) or 1 (mpdtc27)
    row_groups: tuple[tuple[int, ...], ...]  # group indices per row
    groups: tuple[tuple[int, ...], ...]  # member vector ids per group
    row_labels: tuple[str, ...]
    group_labels: tuple[str, ...]

    def const(self, name: str) -> np.float32:
        for c in self.consts:
            if c.name == name:
                return c.value
        raise KeyError(name)

    @property
    def row_n(self) -> tuple[int, ...]:
        return tuple(len(r) for r in self.row_groups)

    @property
    def group_n(self) -> tuple[int, ...]:
        return tuple(len(g) for g in self.groups)

    @property
    def max_groups(self) -> int:
        return max(self.row_n)

    @property
    def max_members(self) -> int:
        return max(self.group_n)

    def rows_padded(self) -> np.ndarray:
        a = np.zeros((len(self.row_groups), self.max_groups), np.intp)
        for r, gs in enumerate(self.row_groups):
            a[r, : len(gs)] = gs
        return a

    def groups_padded(self) -> np.ndarray:
        a = np.zeros((len(self.groups), self.max_members), np.intp)
        for g, ms in enumerate(self.groups):
            a[g, : len(ms)] = ms
        return a


def guard_limits(model: Model) -> dict[str, float]:
    """Input-guard limits (numerics.md "Inputs are guarded"), float64."""
    m, inv, sl = model.motor, model.inverter, model.speed_loop
    rated_omega_e = m.rated_speed_rpm * 2 * math.pi / 60 * m.pole_pairs
    return {
        "I_TRIP_A": inv.i_trip_a,
        "UC_MIN_V": inv.udc_min_v / 2.0,
        "UC_MAX_V": inv.udc_max_v / 2.0,
        "ANGLE_GUARD_RAD": ANGLE_GUARD_RAD,
        "OMEGA_GUARD_RAD_S": 5.0 * rated_omega_e,
        "TORQUE_REF_GUARD_NM": 4.0 * max(sl.limit_nm, m.rated_torque_nm),
    }


def t_n_min(model: Model) -> float:
    """T_N clamp minimum (eq. (10)-(11)): config, else Ts/6 as in the seed."""
    c = model.controller
    return c.dt_s / 6.0 if c.t_n_min_s is None else c.t_n_min_s


def _constants(model: Model) -> list[Const]:
    m, c, inv = model.motor, model.controller, model.inverter
    ts = c.dt_s
    out: list[Const] = [Const(*c) for c in sincos_constants()]
    for name, val in guard_limits(model).items():
        out.append(Const(name, f32(val), GUARD_UNITS.get(name, ""), "input guard limit"))
    out += [
        Const("INV_SQRT3", f32(1 / math.sqrt(3)), "", "Clarke: i_beta = (i_a + 2 i_b)/sqrt(3)"),
        Const("SQRT3_2", f32(math.sqrt(3) / 2), "", "inverse Clarke: i_b = -i_alpha/2 + sqrt(3)/2 i_beta"),
        Const("HALF", f32(0.5), "", "1/2"),
        Const("LS_H", f32(m.ld_h), "H", "Ls = Ld = Lq: psi_d = Ls i_d + psi_f, psi_q = Ls i_q"),
        Const("PSI_F_WB", f32(m.psi_f_wb), "Wb", "magnet flux"),
        Const("PSI_F_SQ", f32(m.psi_f_wb ** 2), "Wb^2", "psi_f^2 (MTPA psi*)"),
        Const("TE_PSI", f32(1.5 * m.pole_pairs * m.psi_f_wb), "N*m/A", "Te = 1.5 np psi_f i_q"),
        Const("INV_TE_PSI", f32(1.0 / (1.5 * m.pole_pairs * m.psi_f_wb)), "A/(N*m)", "i_q_ref = T_ref / (1.5 np psi_f)"),
        Const("RS_OHM", f32(m.rs_ohm), "ohm", "stator resistance"),
        Const("A_S", f32(ts / m.ld_h), "s/H", "Euler: i+ = i + Ts/Ls (u - Rs i +- rotation - w psi_f)"),
        Const("TS_S", f32(ts), "s", "control period Ts"),
        Const("INV_TS", f32(1.0 / ts), "1/s", "deadbeat u* = (psi_ref - psi(k+1))/Ts + Rs i(k+1)"),
        Const("TS3_S", f32(ts / 3.0), "s", "Ts/3: T_b = T_c, T_N + T_P (eq. (8)-(9))"),
        Const("TS6_S", f32(ts / 6.0), "s", "Ts/6: T_b/2 = T_c/2"),
        Const("TN_MIN_S", f32(t_n_min(model)), "s", "T_N clamp minimum (eq. (10)-(11))"),
        Const("K_VO", f32(1.0 / (2.0 * inv.c_f)), "V/C", "dV_o/dt = i_o/(2C)"),
        Const("TWO_C", f32(2.0 * inv.c_f), "F", "2C: T_N deadbeat numerator V_o 2C"),
        Const("LAMBDA_PSI", f32(c.lambda_psi_nm_per_wb), "N*m/Wb", "eq. (7) lambda1"),
        Const("LAMBDA_VO", f32(c.lambda_vo_nm_per_v), "N*m/V", "eq. (7) lambda2"),
        Const("TAN30", f32(math.tan(math.pi / 6)), "", "u* sector borders at 30 deg multiples"),
        Const("TAN60", f32(math.tan(math.pi / 3)), "", "tan(60 deg): sector borders"),
    ]
    return out


def _label_63(p: int, k: int) -> str:
    row = cd.derive_candidate_table().row(p, k)
    s = f"prev {v.STATES[p].name}, sector {cd.SECTOR_NAMES[k]}"
    if row.fallback:
        s += f" (from {cd.SECTOR_NAMES[row.source_sector]})"
    if row.short:
        s += " (short)"
    return s


def _group_label(g: tuple[int, ...]) -> str:
    return "/".join(vv.vector_name(i) for i in g)


def derive_three_level(model: Model) -> ThreeLevelTables:
    """Derive the step's tables for ``model.controller.strategy``."""
    strategy = model.controller.strategy
    if strategy == "mpdtc63":
        table = cd.derive_candidate_table()
        row_sets = [r.groups for r in table.rows]
        labels = [_label_63(r.prev_state, r.sector) for r in table.rows]
        n_sectors = cd.N_SECTORS
    elif strategy == "mpdtc27":
        gs = []
        for n in range(v.N_BASIC):
            members = list(v.BASIC_STATES[n])
            if n == 0:  # the zero vector: OOO first (ties keep the earlier member)
                members = [v.OOO, v.NNN, v.PPP]
            gs.append(tuple(members))
        row_sets = [tuple(gs)]
        labels = ["all 27 states, 19 voltage groups u0..u18"]
        n_sectors = 1
    else:
        raise ValueError(f"strategy {strategy!r} is not a three-level strategy (mpdtc27, mpdtc63)")
    groups: list[tuple[int, ...]] = []
    index: dict[tuple[int, ...], int] = {}
    row_groups = []
    for gs_row in row_sets:
        idx = []
        for g in gs_row:
            if g not in index:
                index[g] = len(groups)
                groups.append(g)
            idx.append(index[g])
        row_groups.append(tuple(idx))
    ux, uy = vv.vector_voltages()
    seq = []
    for i in range(vv.N_VECTORS):
        seq.append(vv.virtual_of(i).sequence if vv.is_virtual(i) else (i,) * 7)
    return ThreeLevelTables(
        prefix=model.prefix,
        strategy=strategy,
        consts=tuple(_constants(model)),
        io_a=tuple(f32(s.io[0]) for s in v.STATES),
        io_b=tuple(f32(s.io[1]) for s in v.STATES),
        io_c=tuple(f32(s.io[2]) for s in v.STATES),
        ux=tuple(f32(x) for x in ux),
        uy=tuple(f32(y) for y in uy),
        is_virtual=tuple(int(vv.is_virtual(i)) for i in range(vv.N_VECTORS)),
        seq=tuple(seq),
        end_state=tuple(vv.end_state(i) for i in range(vv.N_VECTORS)),
        n_sectors=n_sectors,
        row_groups=tuple(row_groups),
        groups=tuple(groups),
        row_labels=tuple(labels),
        group_labels=tuple(_group_label(g) for g in groups),
    )
