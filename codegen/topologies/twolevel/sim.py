"""Closed-loop simulation of the two-level drive: scenario -> compiled loop -> Trace.

The whole period loop (plant sampling, speed PI, controller step, RK4 plant
integration) runs in C (``csrc/twolevel_sim.c`` + ``csrc/twolevel_plant.c``
+ the shared ``codegen/simulator/csrc`` + the generated controller step,
compiled by the host build into one cffi library); the shared driver
(:mod:`codegen.simulator.driver`) calls ``twolevel_sim_run`` once per chunk
of periods and this module wraps the recorded arrays into a :class:`Trace`.
The plant, PI, sensor and decision-queue state is carried across chunks in
a ``twolevel_sim_state_t``, so a chunked run equals one long run bit for
bit.  The plant is the ``[plant]`` section's (actuation delay, parameter
overrides, inverter and sensor non-idealities; every default the ideal
plant of the controller's model).

The simulator's parameter, state and trace structs are the field lists
below (after the shared ones of :mod:`codegen.simulator.records`): the
generated ``sim_api.h``, the cffi cdef and :class:`Trace` derive from them.

Specification: docs/simulation.md ("Plant", "Sampling",
"Timing", "Inverter non-idealities", "Sensors", "Fast") and
docs/algorithms.md (two-level MPTC) ("Parameters and scenarios").  Timing
details: ``csrc/twolevel_sim.c``.
"""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from codegen.model import Model
from codegen.numfmt import NumberFormat, number_format
from codegen.records import Record, fields
from codegen.simulator import api
from codegen.simulator.driver import (
    MAX_SUBSTEP_S,
    InverterPeriod,
    Levels,
    Simulator,
    TraceBase,
    default_substeps,
    fill_common_params,
    motor_inputs,
    plant_udc_v,
    trace_class,
)
from codegen.simulator.records import SIM_PARAMS, SIM_STATE, SIM_TRACE, SimStruct
from codegen.topologies.twolevel.records import INPUT

PARAMS = SimStruct("twolevel_sim_params_t", "two-level simulator parameters", Record("twolevel_sim_params", fields("""
    substeps            i32   1  RK4 sub-steps per period (dt_s/substeps <= 1 us)
""")), base=SIM_PARAMS)

STATE = SimStruct("twolevel_sim_state_t", "two-level carried state", Record("twolevel_sim_state", fields("""
    prev_sw   i32   1  decision of period k-1, Sa*4+Sb*2+Sc (000 before the first)
    prior_sw  i32   1  decision of period k-2 (000 before the first two)
    held_sw   i32   1  state the inverter held during [t_k-1, t_k) (000 before the first period)
    prev_gates_off   i32   1  the step's gates_off of period k-1 (0 before the first)
    prior_gates_off  i32   1  the step's gates_off of period k-2 (0 before the first two)
    held_open        i32   1  1: the inverter was open (every switch off) during [t_k-1, t_k)
""")), base=SIM_STATE)

TRACE = SimStruct("twolevel_sim_trace_t", "two-level trace", Record("twolevel_sim_trace", fields("""
    sw          u16   1  controller decision out.sw, Sa*4+Sb*2+Sc
    applied_sw  u16   1  state the inverter holds during [t_k, t_k+1) (the decision of k-d)
    prev_sw     u16   1  in.prev_sw as the controller saw it (the decision of k - max(d, 1))
""")), base=SIM_TRACE, pointers=True)

SIM = api.SimApi("twolevel", PARAMS, STATE, TRACE, Path(__file__).resolve().parent / "csrc", {
    -1: "invalid simulator arguments (motor/inverter/speed-loop parameters)",
    -2: "the plant state became non-finite (the drive diverged)",
    -3: "the controller returned a switching state outside 0..7",
}, core=("twolevel_rhs.h",), board=("twolevel_onboard.c",))

def levels_of(sw: int) -> Levels:
    """Leg levels of switching state sw = Sa*4 + Sb*2 + Sc in the shared terms (-1 lower, +1 upper rail)."""
    return (2 * ((sw >> 2) & 1) - 1, 2 * ((sw >> 1) & 1) - 1, 2 * (sw & 1) - 1)


class _TraceProperties(TraceBase):
    """The two-level trace's applied periods."""

    applied_sw: np.ndarray
    inverter_open: np.ndarray

    def applied_period(self, k: int) -> InverterPeriod:
        """Period k: ``applied_sw[k]`` over the whole period, from ``applied_sw[k-1]`` (000 before the first)."""
        before = int(self.applied_sw[k - 1]) if k > 0 else 0
        return InverterPeriod(levels_of(before), ((self.dt_s, levels_of(int(self.applied_sw[k]))),),
                              open=bool(self.inverter_open[k]), after_open=k > 0 and bool(self.inverter_open[k - 1]))


if TYPE_CHECKING:  # a class for annotations; the fields come from TRACE
    class Trace(_TraceProperties):
        """One closed-loop run."""
else:
    Trace = trace_class("Trace", __name__, TRACE, """One closed-loop two-level run, one entry per control period (read-only arrays).

        Values are taken at the sample instant t_k = k*dt_s, before the period's
        switching state is applied.  Plant quantities are float64; controller
        outputs keep their C types (float32 estimates, uint16 decisions).
        ``sw`` is the controller's decision at k; ``applied_sw`` the state the
        inverter holds during [t_k, t_k+1), the decision of k-d (d the plant's
        actuation delay: equal to ``sw`` for d = 0); ``prev_sw`` the step's
        ``prev_sw`` input.  ``gates_off``: the step's request (every switch off, acting
        d periods later as its decision does); ``inverter_open``: 1 where the inverter
        was open during [t_k, t_k+1).  ``*_meas_*``: what the controller saw (sensors).
        """, base=_TraceProperties)


def params_from_model(ffi: Any, model: Model, substep_max_s: float | None = None) -> Any:
    """A new ``twolevel_sim_params_t *`` filled from the model (the plant: :func:`fill_common_params`).

    ``substeps``: the fewest equal RK4 sub-steps of at most ``substep_max_s`` (default
    :data:`MAX_SUBSTEP_S`, 1 us) per period (:func:`default_substeps`).
    ``speed_imposed`` is set when ``scenario.speed_mode == "imposed"`` (the
    load machine holds the speed profile; the torque reference is then the
    scenario's load torque).
    """
    c = model.controller
    p = fill_common_params(ffi.new(f"{PARAMS.ctype} *"), model)
    p.substeps = default_substeps(c.dt_s, MAX_SUBSTEP_S if substep_max_s is None else float(substep_max_s))
    return p


def controller_inputs(trace: Any, model: Model, nf: NumberFormat | None = None) -> np.ndarray:
    """The controller-step inputs of every period, exactly as the C loop built them.

    Returns input records in the step's number format ``nf`` (default: the config's, float32): the
    states a closed-loop run fed to the step, for replaying through the Python reference and the
    generated C.  Every real field is the float64 sample the controller saw converted as the C
    loop's ``MPC_ENCODE_*`` does (float32: rounded once); ``udc_v`` is the plant's; ``prev_sw``
    the recorded input (the decision of k - max(d, 1), 0 before the first decisions).
    """
    layout = INPUT.bind(nf or number_format(model.controller.number_format))
    rec = motor_inputs(trace, model, layout)
    rec["udc_v"] = layout.encode("udc_v", plant_udc_v(model))
    rec["prev_sw"] = trace.prev_sw
    return rec


#: the trace field holding the controller's decision (the inverter state it asks for)
DECISION_FIELD = "sw"


def trace_from(arrays: dict[str, np.ndarray], model: Model) -> Any:
    """The :class:`Trace` of trace arrays (``run_chunked``, ``PeriodStepper.result``)."""
    return Trace(dt_s=float(model.controller.dt_s), **arrays)


def trace_metrics(trace: Any, model: Model) -> dict[str, Any]:
    """The metrics ``mpcgen simulate`` reports for a run of this topology."""
    from codegen.topologies.twolevel.metrics import two_level_metrics

    return two_level_metrics(trace, model)


#: the closed loop through the compiled C (its runs, period by period, the on-board plant's files)
SIMULATOR = Simulator(SIM, params_from_model, trace_from)
#: ``run_closed_loop(ffi, lib, model, progress=None, *, chunk, substep_max_s, initial_speed_rpm)``: the
#: model's scenario through the compiled loop, its :class:`Trace` (:meth:`Simulator.run`)
run_closed_loop = SIMULATOR.run
