"""Closed-loop simulation of the T-type three-level drive: scenario -> compiled loop -> Trace.

The whole period loop (sampling, speed PI, controller step, seven-segment RK4
plant integration with the neutral point) runs in C (``csrc/ttype_sim.c`` +
``csrc/ttype_plant.c`` + the shared ``codegen/simulator/csrc`` + the
generated controller step, compiled into one cffi library); the shared
driver (:mod:`codegen.simulator.driver`) calls ``ttype_sim_run`` once per
chunk of periods and this module wraps the recorded arrays into a
:class:`Trace`.  The plant, PI, sensor and decision-queue state is carried
across chunks in a ``ttype_sim_state_t``, so a chunked run equals one long
run bit for bit.  The plant is the ``[plant]`` section's (actuation delay,
parameter overrides, inverter and sensor non-idealities; every default the
ideal plant of the controller's model).

The simulator's parameter, state and trace structs are the field lists
below (after the shared ones of :mod:`codegen.simulator.records`): the
generated ``sim_api.h``, the cffi cdef and :class:`Trace` derive from them.

Timing: the decision computed at t_k is applied during [t_k+d, t_k+d+1),
d the plant's actuation delay (the MPDTC step always assumes d = 1; the
default d follows ``controller.delay_compensation``); before the first
decisions the inverter holds OOO.  Details: ``csrc/ttype_sim.c``.  Plant model and the V_o sign convention
(dV_o/dt = i_o/(2C), i_o = sum (1-|S_x|) i_x): ``csrc/ttype_plant.h``.
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
    fill_common_params,
    motor_inputs,
    plant_udc_v,
    trace_class,
)
from codegen.simulator.records import SIM_PARAMS, SIM_STATE, SIM_TRACE, SimStruct
from codegen.topologies.ttype.records import INPUT, N_SEGMENTS

PARAMS = SimStruct("ttype_sim_params_t", "T-type simulator parameters", Record("ttype_sim_params", fields("""
    c_f            f64   1  each DC-link capacitor C1 = C2, F
    substep_max_s  f64   1  largest RK4 sub-step, s (1e-6)
""")), base=SIM_PARAMS)

STATE = SimStruct("ttype_sim_state_t", "T-type carried state", Record("ttype_sim_state", fields("""
    vo_v            f64   1      plant neutral-point voltage (u_c1 - u_c2)/2, V
    applied_vector  i32   1      the decision of period k-1: vector (0..62; 13 = OOO before the first)
    applied_t_n_s   f64   1      its T_N, s (as the controller gave it)
    applied_states  u16   N_SEG  its states per segment, 0..26
    applied_seg_s   f64   N_SEG  its segment durations, s (sum = dt_s)
    prior_vector    i32   1      the decision of period k-2: vector (OOO before the first two)
    prior_t_n_s     f64   1      its T_N, s
    prior_states    u16   N_SEG  its states per segment, 0..26
    prior_seg_s     f64   N_SEG  its segment durations, s
    last_state      i32   1      state at the end of the previous period (13 = OOO)
    sampled_vo_v    f64   1      plant V_o at t_k - measurement_delay_s, V
    applied_gates_off  i32   1   the step's gates_off of period k-1 (0 before the first)
    prior_gates_off    i32   1   the step's gates_off of period k-2 (0 before the first two)
    last_open          i32   1   1: the inverter was open (every switch off) during the previous period
""", N_SEG=N_SEGMENTS)), base=SIM_STATE)

TRACE = SimStruct("ttype_sim_trace_t", "T-type trace", Record("ttype_sim_trace", fields("""
    vo_v            f64   1      plant neutral-point voltage at t_k, V
    vo_meas_v       f64   1      V_o as the controller sampled it (measurement delay), V
    t_n_s           f64   1      out.t_n_s (T_N of the decision), s, exact in every number format
    psi_ref_wb      f32   1      out.psi_ref_wb (the controller's flux reference), Wb
    vo_est_v        f32   1      out.vo_v (the controller's V_o), V
    applied_vector  u16   1      vector applied during [t_k, t_k+1) (the decision of k-d)
    prev_vector     u16   1      in.prev_vector as the controller saw it (the decision of k - max(d, 1))
    t_n_prev_s      f64   1      in.t_n_prev_s before the format conversion, s
    leg_changes     u16   1      one-level leg changes of the applied period (0 with the inverter open)
    uab_v           f64   N_SEG  u_ab per applied segment (V_o at the segment start), V
    seg_s           f64   N_SEG  applied segment durations, s (0: skipped)
    seg_states      u16   N_SEG  applied states per segment
""", N_SEG=N_SEGMENTS)), base=SIM_TRACE, pointers=True)

SIM = api.SimApi("ttype", PARAMS, STATE, TRACE, Path(__file__).resolve().parent / "csrc", {
    -1: "invalid simulator arguments (motor/inverter/speed-loop parameters)",
    -2: "the plant state became non-finite (the drive diverged)",
    -3: "the controller returned an invalid decision (vector, states or segment times)",
}, core=("ttype_rhs.h", "ttype_decision.h"), board=("ttype_onboard.c",))


def levels_of(state: int) -> Levels:
    """Leg levels (Sa, Sb, Sc) in {-1, 0, +1} of switching state 9*(Sa+1) + 3*(Sb+1) + (Sc+1)."""
    return (state // 9 - 1, (state // 3) % 3 - 1, state % 3 - 1)


#: switching state OOO (every leg at the midpoint), held before the first decisions
OOO = 13


class _TraceProperties(TraceBase):
    """The T-type trace's derived quantities."""

    udc_v: float
    vo_v: np.ndarray
    seg_s: np.ndarray
    seg_states: np.ndarray
    inverter_open: np.ndarray

    def _last_state(self, k: int) -> int:
        """The state at the end of the last period before k the inverter was not open (OOO if none): its
        last non-empty segment's."""
        j = k - 1
        while j >= 0 and self.inverter_open[j]:
            j -= 1
        if j < 0:
            return OOO
        return int(self.seg_states[j][np.nonzero(self.seg_s[j] > 0.0)[0][-1]])

    def applied_period(self, k: int) -> InverterPeriod:
        """Period k: its applied segments (``seg_s``, ``seg_states``) from the state the previous period ended in."""
        segs = tuple((float(t), levels_of(int(st))) for t, st in zip(self.seg_s[k], self.seg_states[k], strict=True))
        return InverterPeriod(levels_of(self._last_state(k)), segs, open=bool(self.inverter_open[k]),
                              after_open=k > 0 and bool(self.inverter_open[k - 1]))

    @property
    def uc1_v(self) -> np.ndarray:
        """Upper capacitor voltage u_c1 = Udc/2 + V_o."""
        return 0.5 * self.udc_v + self.vo_v

    @property
    def uc2_v(self) -> np.ndarray:
        """Lower capacitor voltage u_c2 = Udc/2 - V_o."""
        return 0.5 * self.udc_v - self.vo_v


if TYPE_CHECKING:  # a class for annotations; the fields come from TRACE
    class Trace(_TraceProperties):
        """One T-type closed-loop run."""
else:
    Trace = trace_class("Trace", __name__, TRACE, """One T-type closed-loop run (read-only arrays).

        Per-period arrays (n,) are taken at the sample instant t_k = k*dt_s;
        plant quantities float64, controller outputs in their C types.
        ``vector``/``t_n_s`` are the decision of period k (applied during
        [t_k+d, t_k+d+1)); ``applied_vector``, ``uab_v``, ``seg_s``, ``seg_states``
        and ``leg_changes`` describe the period actually applied during
        [t_k, t_k+1); ``prev_vector``/``t_n_prev_s`` the step's inputs.
        Per-segment arrays have shape (n, 7); zero-length segments
        (``seg_s == 0``) were not applied.  ``udc_v`` is the plant's.  ``gates_off``: the
        step's request (every switch off, acting d periods later as its decision does);
        ``inverter_open``: 1 where the inverter was open during [t_k, t_k+1) (the
        segments then as commanded, not applied).
        """, scalars=("udc_v",), base=_TraceProperties)


def params_from_model(ffi: Any, model: Model, substep_max_s: float | None = None) -> Any:
    """A new ``ttype_sim_params_t *`` filled from the model (the plant: :func:`fill_common_params`).

    Udc and each capacitor C from ``model.inverter`` (``udc_v``, ``c_f``) unless ``[plant]`` overrides them;
    ``substep_max_s`` defaults to :data:`MAX_SUBSTEP_S`; ``speed_imposed``
    when ``scenario.speed_mode == "imposed"`` (T* is then the load torque).
    """
    p = fill_common_params(ffi.new(f"{PARAMS.ctype} *"), model)
    p.c_f = model.plant.value("c_f", model)
    p.substep_max_s = float(substep_max_s) if substep_max_s is not None else MAX_SUBSTEP_S
    return p


def controller_inputs(trace: Any, model: Model, nf: NumberFormat | None = None) -> np.ndarray:
    """The controller-step inputs of every period, exactly as the C loop built them.

    Input records in the step's number format ``nf`` (default: the config's, float32), for replaying
    through the Python reference and the generated C.  Every real field is one float64 value converted
    as the C loop's ``MPC_ENCODE_*`` does (float32: rounded once): u_c1 = 0.5*Udc + V_o, u_c2 = 0.5*Udc - V_o
    (the same double expressions as ttype_sim.c, the plant's Udc and V_o as sampled);
    ``prev_vector`` and ``t_n_prev_s`` the recorded inputs (the decision of k - max(d, 1); 13 = OOO
    and 0 before the first decisions).
    """
    udc = plant_udc_v(model)
    layout = INPUT.bind(nf or number_format(model.controller.number_format))
    rec = motor_inputs(trace, model, layout)
    rec["uc1_v"] = layout.encode("uc1_v", 0.5 * udc + trace.vo_meas_v)
    rec["uc2_v"] = layout.encode("uc2_v", 0.5 * udc - trace.vo_meas_v)
    rec["prev_vector"] = trace.prev_vector
    rec["t_n_prev_s"] = layout.encode("t_n_prev_s", trace.t_n_prev_s)
    return rec


#: the trace field holding the controller's decision (the vector it asks for)
DECISION_FIELD = "vector"


def trace_from(arrays: dict[str, np.ndarray], model: Model) -> Any:
    """The :class:`Trace` of trace arrays (``run_chunked``, ``PeriodStepper.result``)."""
    return Trace(dt_s=float(model.controller.dt_s), udc_v=plant_udc_v(model), **arrays)


def trace_metrics(trace: Any, model: Model) -> dict[str, Any]:
    """The metrics ``mpcgen simulate`` reports for a run of this topology."""
    from codegen.topologies.ttype.metrics import three_level_metrics

    return three_level_metrics(trace, model)


#: the closed loop through the compiled C (its runs, period by period, the on-board plant's files)
SIMULATOR = Simulator(SIM, params_from_model, trace_from)
#: ``run_closed_loop(ffi, lib, model, progress=None, *, chunk, substep_max_s, initial_speed_rpm)``: the
#: model's scenario through the compiled loop, its :class:`Trace` (:meth:`Simulator.run`)
run_closed_loop = SIMULATOR.run
