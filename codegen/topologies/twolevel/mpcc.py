"""The two-level inverter's part of the long-horizon family (``codegen.mpcc``, docs/mpcc.md).

Per-phase positions {-1, 1} (digit = the leg's bit: 0 lower switch, 1 upper), no jump rule; the
DC link is ``udc_v``, the applied state ``prev_sw`` (Sa*4+Sb*2+Sc, the digits in base 2).  The
decision keeps the fields the two-level simulator, modulator and firmware read: ``sw`` (the first
state of the sequence) and ``vector`` (its V0..V6).  The guard is the MPTC step's.
"""
from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np

from codegen.hostbuild import HostLib, build_step_library
from codegen.kernels.consts import Const
from codegen.model import Model
from codegen.mpcc import reference as mpcc_reference
from codegen.mpcc.records import output_fields
from codegen.mpcc.render import render_cdef, render_mpcc
from codegen.mpcc.tables import Adapter, MpccTables, derive_mpcc
from codegen.records import Record, fields
from codegen.simulator.api import simulator_of
from codegen.topologies.twolevel import vectors
from codegen.topologies.twolevel.derive import guard_limits
from codegen.topologies.twolevel.records import FAULT, FAULT_BITS, GUARD, INPUT

__all__ = ["FAMILY", "ADAPTER", "output_record", "derive", "render", "host_library", "step_batch"]

#: the strategy family (and its one strategy) in the two-level section
FAMILY = "mpcc"

_DECISION = fields("""
    sw             u16   1       chosen switching state Sa*4+Sb*2+Sc (the sequence's first)
    vector         u16   1       its vector index 0..6 (V0: 000 or 111)
""")


@cache
def output_record(horizon: int) -> Record:
    """The two-level long-horizon output record for horizon ``horizon``."""
    return Record("twolevel_mpcc_output", output_fields(horizon, (), _DECISION))


def _decide(t: MpccTables, o: Any, k: Any, out: np.ndarray, state0: np.ndarray, inp: dict[str, np.ndarray]) -> None:
    """``sw`` = the first state, ``vector`` = its V0..V6 (``vectors.sw_to_vec``)."""
    out["sw"] = state0
    out["vector"] = np.array(vectors.sw_to_vec(), np.uint16)[state0]


def _safe(t: MpccTables, out: np.ndarray) -> None:
    """The safe decision: 000 (every output already zero)."""


def _extra_constants(model: Model) -> list[Const]:
    return []


ADAPTER = Adapter(levels=(-1, 1), max_step=None, input_record=INPUT, guard=GUARD, fault=FAULT, fault_bits=FAULT_BITS,
                  udc_fields=("udc_v",), prev_field="prev_sw", guard_limits=guard_limits, output_record=output_record,
                  decide=_decide, safe=_safe, template="twolevel/mpcc_decision.j2",
                  topology_macro="MPC_TOPOLOGY_TWO_LEVEL", extra_constants=_extra_constants,
                  decision_ops=(("load", 1), ("store", 2)))  # the vector looked up; sw, vector

_DOC = """
 * out.sw = Sa*4 + Sb*2 + Sc, one bit per leg a, b, c: 1 = upper switch on
 * (phase at +Udc), 0 = lower switch on (phase at 0), held for the whole
 * period; out.vector is its vector V0..V6."""


def derive(model: Model) -> MpccTables:
    """The long-horizon tables of a two-level model."""
    return derive_mpcc(model, ADAPTER)


def render(model: Model, t: MpccTables, target: str) -> dict[str, str]:
    """The step's files (``codegen.mpcc.render``)."""
    return render_mpcc(model, t, target, "two-level", "switching state 000", _DOC,
                       {"sw_to_vec": vectors.sw_to_vec()})


def host_library(model: Model, t: MpccTables, with_sim: bool = False) -> HostLib:
    """The host build of the step (+ the two-level closed-loop simulator)."""
    sim = simulator_of("codegen.topologies.twolevel.sim") if with_sim else None
    return build_step_library(model, "_mpcc_twolevel", render(model, t, "host"), render_cdef(model, t),
                              (INPUT, output_record(t.horizon)), sim, t.nf)


def step_batch(t: MpccTables, x: np.ndarray) -> np.ndarray:
    """The reference (``codegen.mpcc.reference.step_batch``)."""
    return mpcc_reference.step_batch(t, x)
