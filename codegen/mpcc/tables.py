"""The derived tables of a long-horizon step and what a topology supplies (docs/mpcc.md).

:class:`Adapter` is the topology's part: its alphabet of per-phase positions and jump rule, its input
record (reused as it is: the DC link and the applied switching state), its guard and output record,
and the names of its decision template (``templates/<topology>/mpcc_decision.j2``).  Everything else
is derived here once, from the model, in float64, and rounded once to float32
(:func:`derive_mpcc`).
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from codegen.errors import ConfigError
from codegen.kernels.consts import Const, HasConsts, fault_action_constants, leading_constants
from codegen.kernels.guard import Check
from codegen.kernels.stepformat import step_format
from codegen.kernels.trig import sincos_table
from codegen.model import Model
from codegen.mpcc.lattice import CLARKE, default_node_budget, lattice
from codegen.numfmt import number_format
from codegen.records import Record

__all__ = ["Adapter", "MpccTables", "derive_mpcc", "constants"]


@dataclass(frozen=True)
class Adapter:
    """What a topology gives the long-horizon family (module-level functions only: the tables pickle).

    ``levels``: the per-phase positions in digit order (digit d is position ``levels[d]``; a switching
    state is the three digits in base ``len(levels)``, phase a most significant: the two-level's
    Sa*4+Sb*2+Sc, the T-type's 9(Sa+1)+3(Sb+1)+(Sc+1)); ``max_step``: the largest allowed change of
    one phase's digit between consecutive periods (None: any); ``udc_fields``: the input fields whose
    sum (in order) is the measured DC link; ``prev_field``: the input field holding the applied
    switching state; ``guard_limits(model)``: the float64 guard limits by constant name;
    ``output_record(n)``: the output record for horizon n; ``decide(tables, ops, consts, out, state0)``:
    fill the topology's decision fields from the first state of the sequence (``out`` the output
    records of lanes passing the guard); ``safe(tables, out)``: the safe decision's fields;
    ``template``: the jinja file with the C twins of ``decide`` and ``safe``; ``topology_macro``: the
    binding's topology macro; ``extra_constants(model)``: constants ``decide`` reads (float64);
    ``neutral_point``: the input fields (u_c1, u_c2) of a DC link split at a midpoint that position 0
    connects to, for the neutral-point penalty of docs/mpcc.md eq. (14) (None: no midpoint, no term);
    ``decision_ops``: the essential operations of ``decide`` beyond what the step already computed, as
    (kind, count) pairs of ``codegen.mpcc.opcount`` (the cycle bound)."""

    levels: tuple[int, ...]
    max_step: int | None
    input_record: Record
    guard: tuple[Check, ...]
    fault: dict[str, int]
    fault_bits: tuple[tuple[str, int, str], ...]
    udc_fields: tuple[str, ...]
    prev_field: str
    guard_limits: Callable[[Model], dict[str, float]]
    output_record: Callable[[int], Record]
    decide: Callable[[Any, Any, Any, np.ndarray, np.ndarray, dict[str, np.ndarray]], None]
    safe: Callable[[Any, np.ndarray], None]
    template: str
    topology_macro: str
    extra_constants: Callable[[Model], list[Const]]
    neutral_point: tuple[str, str] | None = None
    decision_ops: tuple[tuple[str, int], ...] = ()


@dataclass(frozen=True)
class MpccTables(HasConsts):
    """What a long-horizon step needs, derived once from a model (float32 values)."""

    prefix: str
    strategy: str
    horizon: int
    delay_compensation: bool
    node_budget: int
    consts: tuple[Const, ...]
    sincos_tab: tuple[np.generic, ...]
    h: tuple[tuple[np.generic, ...], ...]  # (3N, 3N) upper triangular, eq. (4)
    w1: tuple[tuple[np.generic, ...], ...]  # (3N, 2N), eq. (5)
    w2: tuple[tuple[np.generic, ...], ...]  # (3N, 3), eq. (5)
    lvl: tuple[np.generic, ...]  # the positions as reals, digit order
    pw: tuple[int, ...]  # |alphabet|^i, the tie-break index's place values
    adapter: Adapter
    number_format: str = "float32"
    scaling: Any = None
    fault_action: str = "gates-off"

    @property
    def n_levels(self) -> int:
        return len(self.adapter.levels)

    @property
    def n_vars(self) -> int:
        """L = 3N, the lattice's dimension."""
        return 3 * self.horizon

    @property
    def neutral_point(self) -> bool:
        """The cost has the neutral-point penalty of docs/mpcc.md eq. (14) on the first period."""
        return self.adapter.neutral_point is not None

    @property
    def mid_digit(self) -> int:
        """The digit of position 0 (a phase connected to the DC-link midpoint)."""
        return self.adapter.levels.index(0)

    @property
    def max_step(self) -> int | None:
        return self.adapter.max_step

    @property
    def delay(self) -> int:
        """d: 1 with delay compensation (the horizon starts at k+1), else 0."""
        return 1 if self.delay_compensation else 0

    def matrix(self, name: str) -> np.ndarray:
        """``h``, ``w1`` or ``w2`` as a float32 array."""
        return np.array(getattr(self, name), np.float32)


def constants(model: Model, adapter: Adapter) -> list[Const]:
    """The step's scalar constants (float64; eq. (1) and the reference of docs/mpcc.md)."""
    m, c = model.motor, model.controller
    a_i, b_i = lattice_of(model).a, lattice_of(model).b
    kt = 1.5 * m.pole_pairs * m.psi_f_wb
    out = leading_constants(adapter.guard_limits(model), number_format(c.number_format))
    out += [
        Const("TS_S", c.dt_s, "s", "control period Ts: the back-EMF turns by omega_e Ts per period"),
        Const("A_I", a_i, "", "a = exp(-Rs Ts/L), eq. (1)"),
        Const("HALF_B", 0.5 * b_i, "A/V", "b/2, b = (1 - a)/Rs: g b = Udc b/2, eq. (2)"),
        Const("B_PSI", b_i * m.psi_f_wb, "A*s/rad", "b psi_f: b e = omega_e b psi_f (-sin, cos), eq. (1)"),
        Const("INV_KT", 1.0 / kt, "A/(N*m)", "i_q* = T* / (1.5 p psi_f), i_d* = 0"),
        Const("TE_K", kt, "N*m/A", "Te = 1.5 p psi_f i_q (surface PMSM)"),
        Const("LS_H", m.ld_h, "H", "psi = L i + psi_f (cos, sin)"),
        Const("PSI_F_WB", m.psi_f_wb, "Wb", "magnet flux"),
        Const("K_AA", CLARKE[0, 0], "", "Clarke K row alpha: (2/3, -1/3, -1/3)"),
        Const("K_AB", CLARKE[0, 1], "", "Clarke K row alpha, phases b and c"),
        Const("K_BB", CLARKE[1, 1], "", "Clarke K row beta: (0, 1/sqrt3, -1/sqrt3)"),
        Const("K_BC", CLARKE[1, 2], "", "Clarke K row beta, phase c"),
    ]
    if adapter.neutral_point is not None:  # docs/mpcc.md eq. (14)
        out += [
            Const("HALF", 0.5, "", "V_o = (uc1 - uc2)/2; i_b = sqrt3/2 i_beta - i_alpha/2"),
            Const("SQRT3_2", 0.5 * math.sqrt(3.0), "", "i_b = sqrt3/2 i_beta - i_alpha/2, eq. (14)"),
            Const("K_VO_TS", c.dt_s / (2.0 * model.inverter.c_f), "V/A",
                  "Ts/(2C): V_o moves by Ts/(2C) i_o over a period, eq. (14)"),
            Const("LAMBDA_VO", c.lambda_vo_a2_per_v2, "A^2/V^2", "neutral-point weight lambda_vo, eq. (14)"),
        ]
    return out + adapter.extra_constants(model) + fault_action_constants(model)


def lattice_of(model: Model) -> Any:
    """The float64 matrices of ``model`` (:func:`codegen.mpcc.lattice.lattice`)."""
    m, c = model.motor, model.controller
    return lattice(m.rs_ohm, m.ld_h, c.dt_s, model.inverter.udc_v, c.lambda_u, c.horizon)


def node_budget_of(model: Model, adapter: Adapter) -> int:
    """``controller.node_budget``, or its estimate (:func:`codegen.mpcc.lattice.default_node_budget`)."""
    c = model.controller
    return c.node_budget if c.node_budget is not None else default_node_budget(c.dt_s, c.horizon, len(adapter.levels))


def derive_mpcc(model: Model, adapter: Adapter) -> MpccTables:
    """The tables of ``model``'s long-horizon step (float64 once, rounded once to float32).  A quantised
    number format is a ConfigError (the config loader refuses it already; a variant made with
    ``Model.with_controller``, e.g. ``bench --emulated``'s other formats, is refused here)."""
    c = model.controller
    if number_format(c.number_format).quantised:
        raise ConfigError(model.source, "controller.number_format", c.number_format,
                          f"controller.strategy = '{c.strategy}' runs in float32 only (no fixed-point sphere "
                          "decoder, docs/mpcc.md \"Limits\")")
    if adapter.neutral_point is not None and 0 not in adapter.levels:
        raise ValueError("a neutral-point term needs position 0 (the midpoint) in the alphabet")
    if adapter.max_step is not None and list(adapter.levels) != list(range(adapter.levels[0], adapter.levels[-1] + 1)):
        raise ValueError("a jump rule needs consecutive integer positions (digit steps = position steps)")
    nf, consts = step_format(model, lambda mdl: constants(mdl, adapter))
    lat = lattice_of(model)
    b = len(adapter.levels)

    def rounded(a: np.ndarray) -> tuple[tuple[np.generic, ...], ...]:
        return tuple(tuple(nf.const(float(v)) for v in row) for row in a)

    return MpccTables(
        prefix=model.prefix, strategy=c.strategy, horizon=c.horizon, delay_compensation=c.delay_compensation,
        node_budget=node_budget_of(model, adapter), consts=consts, sincos_tab=sincos_table(nf),
        h=rounded(np.triu(lat.h)), w1=rounded(lat.w1), w2=rounded(lat.w2),
        lvl=tuple(nf.const(float(v)) for v in adapter.levels), pw=tuple(b ** i for i in range(3 * c.horizon)),
        adapter=adapter, number_format=nf.name, scaling=nf.scaling, fault_action=c.fault_action)

