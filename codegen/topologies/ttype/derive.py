"""Derived tables and constants of the three-level MPDTC step.

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
from functools import cache

import numpy as np

from codegen.kernels.consts import Const, HasConsts, fault_action_constants, leading_constants, sector_constants
from codegen.kernels.consts import guard_limits as shared_guard_limits
from codegen.kernels.dq import DqModel
from codegen.kernels.stepformat import motor_ranges, step_format
from codegen.kernels.trig import sincos_table
from codegen.model import Model
from codegen.numfmt import number_format
from codegen.numfmt.scaling import Scaling, Signal
from codegen.topologies.ttype import candidates as cd
from codegen.topologies.ttype import vectors as v
from codegen.topologies.ttype import virtual as vv


@dataclass(frozen=True)
class ThreeLevelTables(HasConsts):
    """What a three-level step needs, derived once from a Model."""

    prefix: str
    strategy: str  # 'mpdtc27' | 'mpdtc63'
    consts: tuple[Const, ...]
    sincos_tab: tuple[np.generic, ...]  # sin, cos at 2 pi k / N, interleaved (kernels.trig.sincos_table)
    # per state (27): neutral-point coefficients i_o = ka i_a + kb i_b + kc i_c
    #: midpoint-current pattern of each state: p = 4 ka + 2 kb + kc, i_o = ka i_a + kb i_b + kc i_c
    #: with (ka, kb, kc) in {0, 1}^3 (eq. (2) corrected); only the 8 values i_o(p) exist per step
    io_pattern: tuple[int, ...]
    #: patterns of each vector's segments [N, b, c, P] (a basic vector: its state's, four times)
    seq_pat: tuple[tuple[int, ...], ...]
    # per vector id (63): period-average voltage / Udc, virtual flag, 7 states
    ux: tuple[np.generic, ...]
    uy: tuple[np.generic, ...]
    is_virtual: tuple[int, ...]
    seq: tuple[tuple[int, ...], ...]
    end_state: tuple[int, ...]
    n_sectors: int  # 12 (mpdtc63) or 1 (mpdtc27)
    row_groups: tuple[tuple[int, ...], ...]  # group indices per row
    groups: tuple[tuple[int, ...], ...]  # member vector ids per group
    row_labels: tuple[str, ...]
    group_labels: tuple[str, ...]
    number_format: str = "float32"
    #: fixed point: the Q formats (codegen.numfmt.scaling); None for float32
    scaling: Scaling | None = None
    #: controller.fault_action: what the gates_off output asks on a fault ("gates-off" | "active-short-circuit")
    fault_action: str = "gates-off"


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


#: the dq model's constants by name (codegen.kernels.dq; the templates' dq_fns and flux)
DQ = DqModel("LS_H", "LS_H", "PSI_F_WB", "RS_OHM", "A_S", "A_S")


def guard_limits(model: Model) -> dict[str, float]:
    """Input-guard limits (numerics.md "Input guard and safe decision"), float64: each capacitor at half the DC link's."""
    return shared_guard_limits(model, "UC_MIN_V", "UC_MAX_V", 0.5)


def t_n_min(model: Model) -> float:
    """T_N clamp minimum (eq. (10)-(11)): config, else Ts/6 as in the seed."""
    c = model.controller
    return c.dt_s / 6.0 if c.t_n_min_s is None else c.t_n_min_s


def _constants(model: Model) -> list[Const]:
    """The step's constants, float64 (``in_format`` rounds them to the step's format)."""
    m, c, inv = model.motor, model.controller, model.inverter
    ts = c.dt_s
    f = float
    out = leading_constants(guard_limits(model), number_format(model.controller.number_format))
    out += [
        Const("SQRT3_2", f(math.sqrt(3) / 2), "", "inverse Clarke: i_b = -i_alpha/2 + sqrt(3)/2 i_beta"),
        Const("HALF", f(0.5), "", "1/2"),
        Const("LS_H", f(m.ld_h), "H", "Ls = Ld = Lq: psi_d = Ls i_d + psi_f, psi_q = Ls i_q"),
        Const("PSI_F_WB", f(m.psi_f_wb), "Wb", "magnet flux"),
        Const("PSI_F_SQ", f(m.psi_f_wb ** 2), "Wb^2", "psi_f^2 (MTPA psi*)"),
        Const("TE_PSI", f(1.5 * m.pole_pairs * m.psi_f_wb), "N*m/A", "Te = 1.5 np psi_f i_q"),
        Const("INV_TE_PSI", f(1.0 / (1.5 * m.pole_pairs * m.psi_f_wb)), "A/(N*m)", "i_q_ref = T_ref / (1.5 np psi_f)"),
        Const("RS_OHM", f(m.rs_ohm), "ohm", "stator resistance"),
        Const("A_S", f(ts / m.ld_h), "s/H", "Euler: i+ = i + Ts/Ls (u - Rs i +- rotation - w psi_f)"),
        Const("TS_S", f(ts), "s", "control period Ts"),
        Const("INV_TS", f(1.0 / ts), "1/s", "deadbeat u* = (psi_ref - psi(k+1))/Ts + Rs i(k+1)"),
        Const("TS3_S", f(ts / 3.0), "s", "Ts/3: T_b = T_c, T_N + T_P (eq. (8)-(9))"),
        Const("TS6_S", f(ts / 6.0), "s", "Ts/6: T_b/2 = T_c/2"),
        Const("TN_MIN_S", f(t_n_min(model)), "s", "T_N clamp minimum (eq. (10)-(11))"),
        Const("K_VO", f(1.0 / (2.0 * inv.c_f)), "V/C", "dV_o/dt = i_o/(2C)"),
        Const("TWO_C", f(2.0 * inv.c_f), "F", "2C: T_N deadbeat numerator V_o 2C"),
        Const("LAMBDA_PSI", f(c.lambda_psi_nm_per_wb), "N*m/Wb", "eq. (7) lambda1"),
        Const("LAMBDA_VO", f(c.lambda_vo_nm_per_v), "N*m/V", "eq. (7) lambda2"),
    ] + sector_constants() + fault_action_constants(model)
    return out


def cost_bounds(model: Model) -> list[Signal]:
    """Worst case of the cost (eq. (7), N*m; fixed-point ranges):
    g <= (T*_guard + Te_max) + lambda1 2 psi_max + lambda2 udc_max/2."""
    c = model.controller
    _, sigs = motor_ranges(model)
    te_max, psi_max = sigs[2].max_abs, sigs[1].max_abs
    g = (guard_limits(model)["TORQUE_REF_GUARD_NM"] + te_max + c.lambda_psi_nm_per_wb * 2.0 * psi_max
         + c.lambda_vo_nm_per_v * model.inverter.udc_max_v / 2.0)
    return [Signal("g (cost, eq. (7))", "N*m", g, "controller.lambda_psi_nm_per_wb")]


def io_patterns() -> tuple[int, ...]:
    """Midpoint-current pattern p = 4 ka + 2 kb + kc of each state (eq. (2) corrected); ValueError if a
    coefficient is not 0 or 1."""
    if any(k not in (0, 1) for s in v.STATES for k in s.io):
        raise ValueError("midpoint coefficients must be 0 or 1")
    return tuple(4 * int(s.io[0]) + 2 * int(s.io[1]) + int(s.io[2]) for s in v.STATES)


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


@cache
def _row_sets(strategy: str) -> tuple[tuple[tuple[tuple[int, ...], ...], ...], tuple[str, ...], int]:
    """The strategy's candidate rows as member sets per group, their labels, and the sector count."""
    if strategy == "mpdtc63":
        table = cd.derive_candidate_table()
        return (tuple(r.groups for r in table.rows), tuple(_label_63(r.prev_state, r.sector) for r in table.rows),
                cd.N_SECTORS)
    if strategy == "mpdtc27":
        gs = []
        for n in range(v.N_BASIC):
            members = list(v.BASIC_STATES[n])
            if n == 0:  # the zero vector: OOO first (ties keep the earlier member)
                members = [v.OOO, v.NNN, v.PPP]
            gs.append(tuple(members))
        return (tuple(gs),), ("all 27 states, 19 voltage groups u0..u18",), 1
    raise ValueError(f"strategy {strategy!r} is not a three-level strategy (mpdtc27, mpdtc63)")


def max_groups_of(strategy: str) -> int:
    """Most voltage groups a row of ``strategy`` holds (= ``ThreeLevelTables.max_groups``): the
    costs a step can evaluate, the length of the output record's ``costs`` and ``cand``."""
    return max(len(row) for row in _row_sets(strategy)[0])


def derive_three_level(model: Model) -> ThreeLevelTables:
    """Derive the step's tables for ``model.controller.strategy``."""
    strategy = model.controller.strategy
    row_sets, labels, n_sectors = _row_sets(strategy)
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
    nf, consts = step_format(model, _constants, cost_bounds)
    f = nf.const
    pat = io_patterns()
    seq = []
    for i in range(vv.N_VECTORS):
        seq.append(vv.virtual_of(i).sequence if vv.is_virtual(i) else (i,) * 7)
    return ThreeLevelTables(
        prefix=model.prefix,
        strategy=strategy,
        consts=consts,
        sincos_tab=sincos_table(nf),
        io_pattern=pat,
        seq_pat=tuple(tuple(pat[s] for s in sq[:4]) for sq in seq),
        ux=tuple(f(x) for x in ux),
        uy=tuple(f(y) for y in uy),
        is_virtual=tuple(int(vv.is_virtual(i)) for i in range(vv.N_VECTORS)),
        seq=tuple(seq),
        end_state=tuple(vv.end_state(i) for i in range(vv.N_VECTORS)),
        n_sectors=n_sectors,
        row_groups=tuple(row_groups),
        groups=tuple(groups),
        row_labels=tuple(labels),
        group_labels=tuple(_group_label(g) for g in groups),
        number_format=nf.name,
        scaling=nf.scaling,
        fault_action=model.controller.fault_action,
    )
