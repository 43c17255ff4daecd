"""The T-type inverter's part of the long-horizon family (``codegen.mpcc``, docs/mpcc.md).

Per-phase positions {-1, 0, 1} (digit 0, 1, 2: the switching state id 9(Sa+1) + 3(Sb+1) + (Sc+1) of
``vectors``), the jump -1 <-> 1 of a phase forbidden (``max_step`` 1, also against the applied
position); the DC link is uc1 + uc2 (phase voltage Udc/2 u: the neutral-point voltage is not in the
current model), the capacitors (uc1, uc2) give the neutral-point penalty on the first period's
positions (docs/mpcc.md eq. (14), ``controller.lambda_vo_a2_per_v2``), the applied state ``prev_vector``, which must be a switching state 0..26 (the family applies no
virtual vector; the STATE fault otherwise).  The decision keeps the fields the T-type simulator,
modulator and firmware read: one basic state for the whole period (``states`` all the state,
``seg_s`` = [Ts, 0, ...]), ``vector`` = the state, ``t_n_s`` = 0; ``psi_ref_wb`` is the flux of the
current reference, ``vo_v`` the measured neutral-point voltage.
"""
from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np

from codegen.hostbuild import HostLib, build_step_library
from codegen.kernels.consts import Const
from codegen.kernels.guard import AllAtLeast, AllAtMost, Check, IndexAtMost, fault_bits, motor_checks
from codegen.model import Model
from codegen.mpcc import reference as mpcc_reference
from codegen.mpcc.records import output_fields
from codegen.mpcc.render import render_cdef, render_mpcc
from codegen.mpcc.tables import Adapter, MpccTables, derive_mpcc
from codegen.records import Record, fields
from codegen.simulator.api import simulator_of
from codegen.topologies.ttype.derive import guard_limits
from codegen.topologies.ttype.records import INPUT, N_SEGMENTS
from codegen.topologies.ttype.vectors import N_STATES, OOO

__all__ = ["FAMILY", "ADAPTER", "GUARD", "FAULT", "output_record", "derive", "render", "host_library", "step_batch"]

#: the strategy family (and its one strategy) in the T-type section
FAMILY = "mpcc"

_REALS = fields("""
    psi_ref_wb     real  1           flux of the current reference, |L i* + psi_f| = sqrt(psi_f^2 + (L i_q*)^2), Wb
    vo_v           real  1           measured neutral-point voltage V_o(k) = (uc1 - uc2)/2, V
    vo_pred_v      real  1           predicted V_o(k+1) under the applied state (the start of u_0's period, eq. (14)), V
    t_n_s          real  1           0: a basic state for the whole period
    seg_s          real  N_SEGMENTS  segment times, s: [Ts, 0, ...] (one basic state)
""", N_SEGMENTS=N_SEGMENTS)

_DECISION = fields("""
    states         u16   N_SEGMENTS  the sequence's first switching state 0..26 in every segment
    vector         u16   1           the same state id (a basic vector)
""", N_SEGMENTS=N_SEGMENTS)

#: the input guard: the MPDTC's, but the applied vector must be a switching state (no virtual vector)
GUARD: tuple[Check, ...] = motor_checks() + (
    AllAtLeast("UDC_LOW", ("uc1_v", "uc2_v"), "UC_MIN_V"),
    AllAtMost("UDC_HIGH", ("uc1_v", "uc2_v"), "UC_MAX_V"),
    IndexAtMost("STATE", "prev_vector", N_STATES - 1),
)
FAULT_BITS: tuple[tuple[str, int, str], ...] = fault_bits({
    "UDC_LOW": "uc1 or uc2 below udc_min_v/2, or not finite",
    "UDC_HIGH": "uc1 or uc2 above udc_max_v/2, or not finite",
    "STATE": "prev_vector is not a switching state 0..26",
})
FAULT = {name: bit for name, bit, _ in FAULT_BITS}


@cache
def output_record(horizon: int) -> Record:
    """The T-type long-horizon output record for horizon ``horizon``."""
    return Record("ttype_mpcc_output", output_fields(horizon, _REALS, _DECISION))


def _decide(t: MpccTables, o: Any, k: Any, out: np.ndarray, state0: np.ndarray, inp: dict[str, np.ndarray]) -> None:
    """One basic state for the period; psi* = sqrt(psi_f^2 + (L i_q*)^2); V_o = (uc1 - uc2) 1/2."""
    iq = o.mul(inp["torque_ref_nm"], k.INV_KT)
    li = o.mul(k.LS_H, iq)
    out["psi_ref_wb"] = o.sqrt(o.add(k.PSI_F_SQ, o.mul(li, li)))
    out["vo_v"] = o.mul(o.sub(inp["uc1_v"], inp["uc2_v"]), k.HALF)
    out["states"] = state0[:, None]
    out["vector"] = state0
    _one_period(k.TS_S, out)


def _one_period(ts: Any, out: np.ndarray) -> None:
    seg = np.zeros((len(out), N_SEGMENTS), np.float32)
    seg[:, 0] = ts
    out["seg_s"] = seg
    out["t_n_s"] = 0


def _safe(t: MpccTables, out: np.ndarray) -> None:
    """The safe decision: OOO for the whole period."""
    out["states"] = OOO
    out["vector"] = OOO
    _one_period(t.const("TS_S"), out)


def _extra_constants(model: Model) -> list[Const]:
    return [Const("PSI_F_SQ", model.motor.psi_f_wb ** 2, "Wb^2", "psi_f^2: |psi*| = sqrt(psi_f^2 + (L i_q*)^2)")]


ADAPTER = Adapter(levels=(-1, 0, 1), max_step=1, input_record=INPUT, guard=GUARD, fault=FAULT, fault_bits=FAULT_BITS,
                  udc_fields=("uc1_v", "uc2_v"), prev_field="prev_vector", guard_limits=guard_limits,
                  output_record=output_record, decide=_decide, safe=_safe, template="ttype/mpcc_decision.j2",
                  topology_macro="MPC_TOPOLOGY_T_TYPE", extra_constants=_extra_constants,
                  neutral_point=("uc1_v", "uc2_v"),
                  # psi* = sqrt(psi_f^2 + (L i_q*)^2) (3 + the root; V_o is the neutral-point block's);
                  # L, psi_f^2 read; psi_ref, vo_v, t_n_s, seg_s[7], states[7], vector stored
                  decision_ops=(("add", 3), ("sqrt", 1), ("load", 2), ("store", 3 + 2 * N_SEGMENTS + 1)))

_DOC = """
 * out.states[0..6] = one switching state id 9(Sa+1) + 3(Sb+1) + (Sc+1)
 * (S = -1 N, 0 O, +1 P) for the whole period (out.seg_s = [Ts, 0, ...]);
 * out.vector is the same id.  A phase never jumps between N and P."""


def derive(model: Model) -> MpccTables:
    """The long-horizon tables of a T-type model."""
    return derive_mpcc(model, ADAPTER)


def render(model: Model, t: MpccTables, target: str) -> dict[str, str]:
    """The step's files (``codegen.mpcc.render``)."""
    return render_mpcc(model, t, target, "T-type", "switching state OOO", _DOC,
                       {"n_segments": N_SEGMENTS, "safe_state": OOO})


def host_library(model: Model, t: MpccTables, with_sim: bool = False) -> HostLib:
    """The host build of the step (+ the T-type closed-loop simulator)."""
    sim = simulator_of("codegen.topologies.ttype.sim") if with_sim else None
    return build_step_library(model, "_mpcc_ttype", render(model, t, "host"), render_cdef(model, t),
                              (INPUT, output_record(t.horizon)), sim, t.nf)


def step_batch(t: MpccTables, x: np.ndarray) -> np.ndarray:
    """The reference (``codegen.mpcc.reference.step_batch``)."""
    return mpcc_reference.step_batch(t, x)
