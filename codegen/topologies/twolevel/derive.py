"""Derived tables and constants of the two-level MPTC step.

Everything the generated C and the Python reference share is computed here,
once: gains in float64 rounded once to the number format (numerics.md), the vector set,
the zero-vector choice, the candidate rows of the strategy's switch table, and
(``controller.psi_ref = "mtpa"``) the table of the MTPA flux reference psi*(|T*|)
(``mtpa.py``, eq. (M1)-(M2) of docs/algorithms.md).
Templates only print this; the reference only reads it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from codegen.kernels.consts import Const, HasConsts, fault_action_constants, leading_constants, sector_constants
from codegen.kernels.consts import guard_limits as shared_guard_limits
from codegen.kernels.dq import DqModel
from codegen.kernels.stepformat import motor_ranges, step_format
from codegen.kernels.trig import sincos_table
from codegen.model import Model
from codegen.numfmt import number_format
from codegen.numfmt.scaling import Scaling, Signal
from codegen.topologies.twolevel import mtpa, vectors

#: A switch table: [condition][sector] -> candidate vectors (V0 first).
SwitchTable = tuple[tuple[tuple[int, ...], ...], ...]


@dataclass(frozen=True)
class TwoLevelTables(HasConsts):
    """What a two-level step needs, derived once from a Model."""

    prefix: str
    strategy: str
    predictor: str
    delay_compensation: bool
    consts: tuple[Const, ...]
    sincos_tab: tuple[np.generic, ...]  # sin, cos at 2 pi k / N, interleaved (kernels.trig.sincos_table)
    ux: tuple[np.generic, ...]  # unit vector alpha components, V0..V6
    uy: tuple[np.generic, ...]
    vec_to_sw: tuple[int, ...]
    sw_to_vec: tuple[int, ...]
    zero_sw: tuple[int, ...]
    n_conditions: int  # 1 (no table), 2 (s2: sign dT), 4 (s3: sign dT, sign dpsi)
    n_sectors: int  # 1, 6 or 12
    rows: tuple[tuple[int, ...], ...]  # candidate row = condition * n_sectors + sector
    uses_threshold: bool
    number_format: str = "float32"
    #: fixed point: the Q formats (codegen.numfmt.scaling); None for float32
    scaling: Scaling | None = None
    #: controller.fault_action: what the gates_off output asks on a fault ("gates-off" | "active-short-circuit")
    fault_action: str = "gates-off"
    #: controller.psi_ref: "constant" (PSI_REF_WB) or "mtpa" (psi* interpolated in psi_tab / psi_slope)
    psi_ref: str = "constant"
    #: controller.cost: "rated" or "reference" (flux term weighted by (max(|T*|, T_floor)/T_N)^2)
    cost: str = "rated"
    #: controller.lambda_psi != 1: the squared flux term is multiplied by LAMBDA_PSI (1: the papers' cost,
    #: no multiplication)
    flux_weighted: bool = False
    #: mtpa: psi* at |T*| = i dT (Wb, in the format), i = 0..MTPA_SEGMENTS-1, and the slope to the next node
    psi_tab: tuple[np.generic, ...] = ()
    psi_slope: tuple[np.generic, ...] = ()

    @property
    def row_len(self) -> tuple[int, ...]:
        return tuple(len(r) for r in self.rows)

    @property
    def v0_first(self) -> bool:
        """Every row starts with V0 and the predictor is flux-geometry, whose V0 prediction
        psi + 0 dt is the estimate itself: the step takes V0's Te+ and |psi+| from te and mag."""
        return self.predictor == "flux-geometry" and all(r[0] == 0 for r in self.rows)


#: the dq model's constants by name (codegen.kernels.dq; the templates' dq_fns and flux)
DQ = DqModel("LD_H", "LQ_H", "PSI_F_WB", "RS_OHM", "A_D", "A_Q")


def guard_limits(model: Model) -> dict[str, float]:
    """Input-guard limits (numerics.md "Input guard and safe decision"), float64."""
    return shared_guard_limits(model, "UDC_MIN_V", "UDC_MAX_V", 1.0)


def _constants(model: Model) -> list[Const]:
    """The step's constants, float64 (``in_format`` rounds them to the step's format)."""
    m, c = model.motor, model.controller
    f = float
    out = leading_constants(guard_limits(model), number_format(model.controller.number_format))
    out += [
        Const("LD_H", f(m.ld_h), "H", "psi_d = Ld i_d + psi_f"),
        Const("LQ_H", f(m.lq_h), "H", "psi_q = Lq i_q"),
        Const("PSI_F_WB", f(m.psi_f_wb), "Wb", "magnet flux"),
        Const("TE_K", f(1.5 * m.pole_pairs), "", "Te = 1.5 p (psi_d i_q - psi_q i_d)"),
    ] + _flux_reference_constants(model) + [
        Const("INV_TN", f(1 / m.rated_torque_nm), "1/(N*m)", "cost: (Te - T*)/T_N"),
        Const("EPS_T_NM", f(c.eps_t_nm), "N*m", "s1-s3: |dT| <= eps_T -> zero vector"),
    ]
    if c.lambda_psi != 1.0:
        out.append(Const("LAMBDA_PSI", f(c.lambda_psi), "", "cost: g = e_T^2 + lambda_psi e_psi^2"))
    if c.cost == "reference":
        out.append(Const("T_FLOOR_NM", f(T_FLOOR_OF_RATED * m.rated_torque_nm), "N*m",
                         "cost reference: T_n = max(|T*|, T_floor), flux weight (T_n/T_N)^2"))
    out += sector_constants()
    if c.predictor == "flux-geometry":
        out += [
            Const("VDT_K", f(2.0 / 3.0 * c.dt_s), "s", "psi+ = psi + V dt, |V| = 2/3 Udc"),
            Const("TE_GEO_K", f(3 * m.pole_pairs / (2 * m.ld_h)), "1/H", "Te = 3p/(2Ld) psi_f x psi"),
        ]
    else:
        out += [
            Const("VMAG_K", f(2.0 / 3.0), "", "|V| = 2/3 Udc"),
            Const("RS_OHM", f(m.rs_ohm), "ohm", "stator resistance"),
            Const("A_D", f(c.dt_s / m.ld_h), "s/H", "i_d+ = i_d + dt/Ld (u_d - Rs i_d + w Lq i_q)"),
            Const("A_Q", f(c.dt_s / m.lq_h), "s/H", "i_q+ = i_q + dt/Lq (u_q - Rs i_q - w Ld i_d - w psi_f)"),
        ]
    return out + fault_action_constants(model)


#: controller.cost = "reference": T_floor = 0.05 T_N, the normalising torque at |T*| < T_floor
T_FLOOR_OF_RATED = 0.05


def mtpa_table(model: Model) -> tuple[np.ndarray, np.ndarray, float]:
    """psi*(|T*|) table of ``controller.psi_ref = "mtpa"`` over [0, T*_guard] (float64): nodes, slopes, 1/dT
    (``mtpa.flux_table``, eq. (M1)-(M2))."""
    return mtpa.flux_table(model.motor, guard_limits(model)["TORQUE_REF_GUARD_NM"])


def psi_ref_range(model: Model) -> tuple[float, float]:
    """(smallest, largest) psi* the step uses (float64, Wb): psi_ref_wb, or the MTPA table's nodes
    (linear interpolation stays between them)."""
    c = model.controller
    if c.psi_ref == "constant":
        return c.psi_ref_wb, c.psi_ref_wb
    nodes, slopes, _ = mtpa_table(model)
    ends = np.concatenate([nodes, nodes + slopes])
    return float(ends.min()), float(ends.max())


def _flux_reference_constants(model: Model) -> list[Const]:
    """psi* and 1/psi* (constant), or the MTPA table's 1/dT (the table itself: ``psi_tab``, ``psi_slope``)."""
    c = model.controller
    if c.psi_ref == "constant":
        return [Const("PSI_REF_WB", float(c.psi_ref_wb), "Wb", "flux reference psi*"),
                Const("INV_PSI_REF", float(1 / c.psi_ref_wb), "1/Wb", "cost: (|psi| - psi*)/psi*")]
    _, _, inv_step = mtpa_table(model)
    return [Const("MTPA_INV_STEP", float(inv_step), "1/(N*m)",
                  f"psi* table: x = |T*|/dT, {mtpa.MTPA_SEGMENTS} segments up to the T* guard")]


def _flux_term_bound(model: Model, psi_max: float) -> float:
    """Largest |w (|psi| - psi*)/psi*| (float64): |psi| <= psi_max; w = 1 (rated) or T_n/T_N
    (reference, T_n = max(|T*|, T_floor) <= T*_guard).  MTPA: per table segment, the weight at
    its upper end over the smaller psi* of its ends (psi* and w are linear in |T*| there)."""
    m, c = model.motor, model.controller
    t_guard = guard_limits(model)["TORQUE_REF_GUARD_NM"]

    def w(t: np.ndarray | float) -> np.ndarray:
        tn = np.maximum(t, T_FLOOR_OF_RATED * m.rated_torque_nm)
        return tn / m.rated_torque_nm if c.cost == "reference" else np.ones_like(np.asarray(t, np.float64))

    if c.psi_ref == "constant":
        return float(w(t_guard) * (psi_max + c.psi_ref_wb) / c.psi_ref_wb)
    nodes, slopes, inv_step = mtpa_table(model)
    t_hi = (np.arange(len(nodes)) + 1.0) / inv_step
    lo = np.minimum(nodes, nodes + slopes)
    return float(np.max(w(t_hi) * (psi_max + lo) / lo))


def cost_bounds(model: Model) -> list[Signal]:
    """Worst cases of the cost and its terms (fixed-point ranges): |e_T| <= (Te_max + T*_guard)/T_N,
    |e_psi| <= max w (psi_max + psi*)/psi* (``_flux_term_bound``; w = 1 rated, T_n/T_N reference),
    g <= e_T^2 + lambda_psi e_psi^2 (dimensionless); the reference cost's w <= T*_guard/T_N; the MTPA table's
    psi* <= its largest node, 1/psi* <= 1/its smallest, position x = |T*|/dT <= segments."""
    m, c = model.motor, model.controller
    _, sigs = motor_ranges(model)
    te_max, psi_max = sigs[2].max_abs, sigs[1].max_abs
    t_guard = guard_limits(model)["TORQUE_REF_GUARD_NM"]
    e_t = (te_max + t_guard) / m.rated_torque_nm
    e_p = _flux_term_bound(model, psi_max)
    field = "controller.psi_ref" if c.psi_ref == "mtpa" else "controller.psi_ref_wb"
    lam = c.lambda_psi
    out = [Signal("e_T (cost torque term)", "", e_t, "motor.rated_torque_nm"),
           Signal("e_psi (cost flux term)", "", e_p, field),
           Signal("g (cost)", "", e_t * e_t + lam * e_p * e_p, "motor.rated_torque_nm")]
    if lam != 1.0:
        out.append(Signal("lambda_psi e_psi^2 (weighted cost flux term)", "", lam * e_p * e_p, "controller.lambda_psi"))
    if c.cost == "reference":
        out.append(Signal("w = T_n/T_N (cost flux weight)", "", t_guard / m.rated_torque_nm, "controller.cost"))
    if c.psi_ref == "mtpa":
        lo, hi = psi_ref_range(model)
        out += [Signal("psi* (MTPA table)", "Wb", hi, "controller.psi_ref"),
                Signal("1/psi* (MTPA)", "1/Wb", 1.0 / lo, "controller.psi_ref"),
                Signal("x = |T*|/dT (MTPA table position)", "", float(mtpa.MTPA_SEGMENTS), "controller.psi_ref")]
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
    nf, consts = step_format(model, _constants, cost_bounds)
    psi_tab: tuple[np.generic, ...] = ()
    psi_slope: tuple[np.generic, ...] = ()
    if c.psi_ref == "mtpa":
        nodes, slopes, _ = mtpa_table(model)
        psi_tab = tuple(nf.const(float(v), "Wb") for v in nodes)
        psi_slope = tuple(nf.const(float(v), "Wb") for v in slopes)
    return TwoLevelTables(
        prefix=model.prefix,
        strategy=c.strategy,
        predictor=c.predictor,
        delay_compensation=c.delay_compensation,
        consts=consts,
        sincos_tab=sincos_table(nf),
        ux=tuple(nf.const(v) for v in ux),
        uy=tuple(nf.const(v) for v in uy),
        vec_to_sw=vectors.VEC_TO_SW,
        sw_to_vec=vectors.sw_to_vec(),
        zero_sw=vectors.zero_sw_table(),
        n_conditions=n_cond,
        n_sectors=n_sec,
        rows=rows,
        uses_threshold=thr,
        number_format=nf.name,
        scaling=nf.scaling,
        fault_action=model.controller.fault_action,
        psi_ref=c.psi_ref,
        cost=c.cost,
        flux_weighted=c.lambda_psi != 1.0,
        psi_tab=psi_tab,
        psi_slope=psi_slope,
    )
