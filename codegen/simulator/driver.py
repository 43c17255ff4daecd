"""The closed-loop simulator's driver, shared by every topology.

The whole period loop of a topology (plant sampling, speed PI, controller
step, RK4 plant integration) runs in C: the topology's ``csrc/`` sources,
the shared dq model, RK4, speed PI and period steps in ``csrc/`` here, and
the generated controller step, compiled by the host build into one cffi
library.  This module prepares the scenario arrays, fills the parameters
every topology's simulator shares, calls ``<topology>_sim_run`` once per
chunk of periods (:func:`run_chunked`, so progress can be reported),
carrying the C state across chunks so a chunked run equals one long run bit
for bit, or runs the same loop one period at a time with the decision given
from outside (:class:`PeriodStepper`, the serial HIL's closed loop) -- both
on one set-up (:class:`ClosedLoop`) -- and builds each topology's ``Trace``
class from its trace field list.
"""
from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from codegen.errors import MpcgenError
from codegen.hostbuild import HostLib
from codegen.model import Model, Plant
from codegen.records import RecordLayout
from codegen.simulator.api import SimApi, firmware_files
from codegen.simulator.records import SimStruct

#: Largest RK4 sub-step (docs/simulation.md "Plant": at most 1 us).
MAX_SUBSTEP_S = 1e-6
#: ``plant.integrator`` values, in the order of ``sim_params_t.integrator`` (csrc/sim_exact.h): RK4
#: sub-steps, or the exact integrator (the Taylor series of each constant-voltage piece)
INTEGRATORS: tuple[str, ...] = Plant.INTEGRATORS
#: Periods per <topology>_sim_run call (one progress report per chunk).
DEFAULT_CHUNK = 10_000

RPM_TO_RAD_S = 2.0 * math.pi / 60.0


def rpm_to_rad_s(speed_rpm: float) -> float:
    """A plant's initial mechanical speed in rad/s: speed_rpm*2*pi/60, rounded in that order."""
    return speed_rpm * 2.0 * math.pi / 60.0

# Tolerance, in periods, when mapping a step time onto the sample grid
# (a step at 2.0 s with dt = 50 us must act from sample 40000 exactly).
_GRID_TOL = 1e-6


class SimulationError(MpcgenError):
    """The closed-loop simulation could not run or diverged."""


def default_substeps(dt_s: float, max_substep_s: float = MAX_SUBSTEP_S) -> int:
    """Fewest equal RK4 sub-steps with dt_s/substeps <= max_substep_s (50 for 50 us)."""
    return max(1, math.ceil(dt_s / max_substep_s - _GRID_TOL))


def n_periods(model: Model) -> int:
    """Number of control periods of the scenario: round(duration_s / dt_s)."""
    return int(round(model.scenario.duration_s / model.controller.dt_s))


def _first_sample_at(t_s: float, dt_s: float) -> int:
    """Index of the first sample instant k*dt_s at or after t_s (grid-tolerant)."""
    return max(0, math.ceil(t_s / dt_s - _GRID_TOL))


def _piecewise(steps: tuple[tuple[float, float], ...], n: int, dt_s: float) -> np.ndarray:
    """Per-period values of piecewise-constant steps (time_s, value); 0 before the first."""
    out = np.zeros(n, dtype=np.float64)
    for t_s, value in sorted(steps, key=lambda s: s[0]):
        k = _first_sample_at(float(t_s), dt_s)
        if k < n:
            out[k:] = float(value)
    return out


def scenario_arrays(model: Model) -> tuple[np.ndarray, np.ndarray]:
    """Speed reference (mechanical, rad/s) and load torque (N*m) per period.

    Period k (t_k = k*dt_s, k = 0 .. n-1, n = round(duration_s/dt_s)) takes the
    value of the last step whose time is <= t_k; before the first step the
    value is 0.  ``scenario.speed_ref_rpm`` is converted from r/min to rad/s.
    """
    n = n_periods(model)
    dt = model.controller.dt_s
    speed = _piecewise(model.scenario.speed_ref_rpm, n, dt) * RPM_TO_RAD_S
    load = _piecewise(model.scenario.load_nm, n, dt)
    return speed, load


def fill_common_params(p: Any, model: Model) -> Any:
    """Set the shared parameters ``p.common``; return ``p``.

    The plant's motor and DC link are the controller's (``motor``,
    ``inverter``) unless ``[plant]`` overrides them (parameter-mismatch
    studies: the generated controller keeps its own values); the timing
    (``dt_s``; the actuation delay ``Plant.delay_periods``), the speed PI,
    the speed mode, and the inverter and sensor non-idealities of
    ``[plant]`` (0 = off; the ADC full scale defaults to ``inverter.i_trip_a``).
    """
    m, c, sl, pl = model.motor, model.controller, model.speed_loop, model.plant
    common = p.common
    common.rs_ohm = pl.value("rs_ohm", model)
    common.ld_h = pl.value("ld_h", model)
    common.lq_h = pl.value("lq_h", model)
    common.psi_f_wb = pl.value("psi_f_wb", model)
    common.pole_pairs = int(m.pole_pairs)
    common.j_kgm2 = pl.value("j_kgm2", model)
    common.b_nms = pl.value("b_nms", model)
    common.udc_v = plant_udc_v(model)
    common.dt_s = c.dt_s
    common.kp = sl.kp
    common.ki = sl.ki
    common.limit_nm = sl.limit_nm
    common.speed_imposed = 1 if model.scenario.speed_mode == "imposed" else 0
    common.delay_periods = int(pl.delay_periods(c.delay_compensation))
    common.dead_time_s = float(pl.dead_time_s)
    common.device_drop_v = float(pl.device_drop_v)
    common.current_gain_error = float(pl.current_gain_error)
    common.current_offset_a = float(pl.current_offset_a)
    common.adc_bits = int(pl.adc_bits)
    common.adc_full_scale_a = pl.value("adc_full_scale_a", model)
    common.noise_a = float(pl.noise_a)
    common.noise_seed = int(pl.noise_seed)
    common.encoder_bits = int(pl.encoder_bits)
    common.measurement_delay_s = float(pl.measurement_delay_s)
    common.integrator = INTEGRATORS.index(pl.integrator)
    return p


def plant_udc_v(model: Model) -> float:
    """The plant's DC-link voltage (``plant.udc_v``, else ``inverter.udc_v``); the controller measures it."""
    return model.plant.value("udc_v", model)


def trace_fields(trace: SimStruct) -> dict[str, tuple[np.dtype, int]]:
    """Every trace member (shared first): (dtype of one value, values per period)."""
    out: dict[str, tuple[np.dtype, int]] = {}
    s: SimStruct | None = trace
    while s is not None:
        out = {**{f.name: (s.np_type(f), f.length) for f in s.fields}, **out}
        s = s.base
    return out


#: leg levels of the three legs, each -1, 0 or +1 (a two-level leg's lower/upper rail: -1/+1)
Levels = tuple[int, int, int]


@dataclasses.dataclass(frozen=True)
class InverterPeriod:
    """The inverter during one control period as the plant applied it, in terms every topology shares:
    the leg levels held before the period, each segment's (duration_s, leg levels) in order (a
    zero-length segment is not applied), ``open``: every switch off during the period, ``after_open``:
    every switch was off during the previous one.  (:mod:`codegen.simulator.tightref` integrates it.)"""

    before: Levels
    segments: tuple[tuple[float, Levels], ...]
    open: bool = False
    after_open: bool = False


class TraceBase:
    """Properties every topology's trace has (the arrays come from its field list)."""

    dt_s: float
    t_s: np.ndarray
    omega_m_rad_s: np.ndarray
    speed_ref_rad_s: np.ndarray

    if TYPE_CHECKING:  # the generated dataclass takes every field as a keyword
        def __init__(self, **fields: Any) -> None: ...

    def __getattr__(self, name: str) -> np.ndarray:
        """Typing aid: the generated dataclass holds one array per trace field (see :func:`trace_class`)."""
        raise AttributeError(f"{type(self).__name__} has no field {name!r}")

    @property
    def n(self) -> int:
        """Number of periods."""
        return int(self.t_s.shape[0])

    def applied_period(self, k: int) -> InverterPeriod:
        """The inverter during [t_k, t_k+1) as the plant applied it (each topology's trace says)."""
        raise NotImplementedError(f"{type(self).__name__} does not describe its applied periods")

    @property
    def duration_s(self) -> float:
        """Simulated time n*dt_s."""
        return self.n * self.dt_s

    @property
    def speed_rpm(self) -> np.ndarray:
        """Mechanical speed in r/min."""
        return self.omega_m_rad_s / RPM_TO_RAD_S

    @property
    def speed_ref_rpm(self) -> np.ndarray:
        """Mechanical speed reference in r/min."""
        return self.speed_ref_rad_s / RPM_TO_RAD_S


def trace_class(name: str, module: str, trace: SimStruct, doc: str, scalars: tuple[str, ...] = (),
                base: type = TraceBase) -> type:
    """A frozen dataclass of one run: ``dt_s``, ``scalars`` (floats), every trace member, ``load_nm``.

    The array fields are the trace struct's fields (read-only arrays; shape
    (n,) or (n, w) for w values per period).
    """
    fields: list[tuple[str, type]] = [("dt_s", float), *[(s, float) for s in scalars]]
    fields += [(f, np.ndarray) for f in trace_fields(trace)] + [("load_nm", np.ndarray)]
    return dataclasses.make_dataclass(name, fields, bases=(base,), frozen=True, eq=False,
                                      namespace={"__doc__": doc, "__module__": module})


def motor_inputs(trace: Any, model: Model, layout: RecordLayout) -> np.ndarray:
    """Controller-input records (``layout``: the input record in the step's number format) with the
    fields every topology's loop fills alike.

    ``ia_a``, ``ib_a``, ``theta_e_rad``, ``omega_e_rad_s`` = p*omega_m and
    ``torque_ref_nm``: what the controller saw (the trace's ``*_meas_*``
    fields: the samples through the sensors, equal to the plant's values
    with ideal sensors), each float64 value converted to the format as the
    C loop's ``MPC_ENCODE_*`` does (sim_period.h step 4; float32: rounded
    once); the other fields are zero.
    """
    rec = layout.zeros(trace.n)
    rec["ia_a"] = layout.encode("ia_a", trace.ia_meas_a)
    rec["ib_a"] = layout.encode("ib_a", trace.ib_meas_a)
    rec["theta_e_rad"] = layout.encode("theta_e_rad", trace.theta_e_meas_rad)
    rec["omega_e_rad_s"] = layout.encode("omega_e_rad_s", float(model.motor.pole_pairs) * trace.omega_m_meas_rad_s)
    rec["torque_ref_nm"] = layout.encode("torque_ref_nm", trace.torque_ref_nm)
    return rec


def _c_pointer(trace: SimStruct, name: str) -> str:
    """C pointer type of trace member ``name`` (as the generated struct declares it)."""
    s = trace.owner(name)
    return s.layout.c_type(s.record.field(name)) + " *"


class ClosedLoop:
    """The set-up every run of ``<api>_*`` shares, written once: the scenario arrays, the C state
    initialised by ``<api>_init`` (the plant at ``initial_speed_rad_s``), one array per trace member
    and the C trace struct pointing into them (:meth:`point_trace`).

    ``run_chunked`` drives it chunk by chunk, :class:`PeriodStepper` period by period; both
    return :meth:`result`.  Raises :class:`SimulationError` if ``<api>_init`` refuses the parameters.
    """

    def __init__(self, ffi: Any, lib: Any, api: SimApi, model: Model, params: Any,
                 initial_speed_rad_s: float = 0.0) -> None:
        self.ffi, self.lib, self.api, self.model, self.params = ffi, lib, api, model, params
        self.speed_ref, self.load = scenario_arrays(model)
        self.speed_ref.flags.writeable = False
        self.n = int(self.speed_ref.shape[0])
        self.fields = trace_fields(api.trace)
        self.where = f"{model.source or model.name}"
        self.state = ffi.new(f"{api.state.ctype} *")
        if getattr(lib, f"{api.prefix}_init")(params, self.state) != 0:
            raise SimulationError(f"{self.where}: {api.errors[-1]}")
        self.state.common.motor.omega_m_rad_s = float(initial_speed_rad_s)
        self.arrays: dict[str, np.ndarray] = {k: np.zeros(self.n * w, dtype=t) for k, (t, w) in self.fields.items()}
        self.trace_c = ffi.new(f"{api.trace.ctype} *")
        self._keep = []  # keep the buffers alive while C holds pointers into them
        self._base = {}
        for name, arr in self.arrays.items():
            buf = ffi.from_buffer(arr, require_writable=True)
            self._keep.append(buf)
            self._base[name] = ffi.cast(_c_pointer(api.trace, name), buf)
        self._holders = {name: self.trace_c if api.trace.owner(name) is api.trace else self.trace_c.common
                         for name in self.fields}
        self.point_trace(0)
        #: periods done
        self.k = 0

    def point_trace(self, k0: int) -> None:
        """Point every member of the C trace at period ``k0`` of its array."""
        for name, ptr in self._base.items():
            setattr(self._holders[name], name, ptr + k0 * self.fields[name][1])

    def failure(self, rc: int, k: int) -> SimulationError:
        """The error of return code ``rc`` of period ``k`` (``api.errors``)."""
        reason = self.api.errors.get(rc, f"simulator error {rc}")
        return SimulationError(f"{self.where}: closed-loop run stopped at period {k} "
                               f"(t = {k * self.model.controller.dt_s:.6g} s): {reason}")

    def result(self, periods: int | None = None) -> dict[str, np.ndarray]:
        """The trace arrays of the first ``periods`` (default: the periods done), read-only, shape (m,) or
        (m, w) for w values per period, plus ``load_nm``: the whole scenario's arrays themselves once every
        period is done, else copies (a stepper may go on)."""
        m = self.k if periods is None else min(periods, self.k)
        out: dict[str, np.ndarray] = {}
        for name, (_, w) in self.fields.items():
            a = self.arrays[name] if m == self.n else self.arrays[name][:m * w].copy()
            out[name] = a.reshape(m, w) if w > 1 else a
        out["load_nm"] = self.load if m == self.n else self.load[:m].copy()
        for arr in out.values():
            arr.flags.writeable = False
        return out


def run_chunked(
    ffi: Any,
    lib: Any,
    api: SimApi,
    model: Model,
    params: Any,
    progress: Callable[[float], None] | None,
    chunk: int,
    initial_speed_rad_s: float = 0.0,
) -> dict[str, np.ndarray]:
    """Drive ``<api>_init`` + ``<api>_run`` over the model's scenario, chunk by chunk.

    ``initial_speed_rad_s``: mechanical speed of the plant at t = 0 (default
    standstill), e.g. to start a load-step scenario at rated speed.

    Every member of ``api.trace`` is recorded; a member with w > 1 values
    per period is returned with shape (n, w).  The returned arrays (plus
    ``load_nm``) are read-only.  ``api.errors`` maps the C return codes to
    messages.  ``progress`` is called after every chunk with the completed
    fraction in (0, 1].  Raises :class:`SimulationError` if the simulator
    refuses the parameters or the run diverges.
    """
    if chunk < 1:
        raise ValueError("chunk must be >= 1")
    loop = ClosedLoop(ffi, lib, api, model, params, initial_speed_rad_s)
    run = getattr(lib, f"{api.prefix}_run")
    ref_buf, load_buf = ffi.from_buffer(loop.speed_ref), ffi.from_buffer(loop.load)
    ref_ptr, load_ptr = ffi.cast("double *", ref_buf), ffi.cast("double *", load_buf)
    n = loop.n
    while loop.k < n:
        k0, k1 = loop.k, min(n, loop.k + chunk)
        loop.point_trace(k0)
        rc = run(params, ref_ptr + k0, load_ptr + k0, k1 - k0, loop.trace_c, loop.state)
        if rc != 0:
            raise loop.failure(rc, int(loop.state.common.k))
        loop.k = k1
        if progress is not None:
            progress(k1 / n)
    del ref_buf, load_buf
    return loop.result()


class PeriodStepper(ClosedLoop):
    """The closed loop of ``run_chunked``, one period at a time, with the decision given from outside.

    For a controller computed elsewhere (the serial HIL's closed loop, where a
    board computes each decision): :meth:`input` is the controller-input
    record of the next period (``in_dtype``, exactly what ``<api>_run`` would
    give the step), :meth:`finish` takes that period's output record
    (``out_dtype``), records the trace entry, integrates the plant and
    commits the period.  The C code is the same as ``<api>_run``'s
    (``<api>_hil_input`` / ``<api>_hil_finish``), so decisions equal to the
    compiled step's give the simulator's trace bit for bit.
    """

    def __init__(self, ffi: Any, lib: Any, api: SimApi, model: Model, params: Any, in_dtype: np.dtype,
                 out_dtype: np.dtype, initial_speed_rad_s: float = 0.0) -> None:
        super().__init__(ffi, lib, api, model, params, initial_speed_rad_s)
        self.in_dtype, self.out_dtype = np.dtype(in_dtype), np.dtype(out_dtype)
        self._input = getattr(lib, f"{api.prefix}_hil_input")
        self._finish = getattr(lib, f"{api.prefix}_hil_finish")
        self._in = np.zeros(1, self.in_dtype)
        self._out = np.zeros(1, self.out_dtype)
        self._in_buf = ffi.from_buffer(self._in, require_writable=True)
        self._out_buf = ffi.from_buffer(self._out, require_writable=True)

    def input(self) -> np.ndarray:
        """The controller input of period ``k`` (a length-1 record array, valid until the next call)."""
        k = self.k
        if k >= self.n:
            raise IndexError(f"the scenario has {self.n} periods")
        if self._input(self.params, self.state, float(self.speed_ref[k]), float(self.load[k]), self._in_buf) != 0:
            raise SimulationError(f"{self.where}: {self.api.errors[-1]}")
        return self._in

    def live_arrays(self) -> dict[str, np.ndarray]:
        """Views of the whole scenario's trace arrays (shape (n,) or (n, w)) and ``load_nm``, filled as the
        periods are done (entries beyond ``k`` are zero); no copy, unlike :meth:`result`."""
        out = {name: (self.arrays[name].reshape(self.n, w) if w > 1 else self.arrays[name])
               for name, (_, w) in self.fields.items()}
        out["load_nm"] = self.load
        return out

    def finish(self, out: np.ndarray) -> None:
        """Apply period ``k``'s decision ``out`` (one output record) and commit the period."""
        k = self.k
        self._out[0] = out.reshape(-1)[0]
        rc = self._finish(self.params, self.state, float(self.speed_ref[k]), float(self.load[k]), self._out_buf,
                          self.trace_c, k)
        if rc != 0:
            raise self.failure(rc, k)
        self.k = k + 1


@dataclasses.dataclass(frozen=True)
class Simulator:
    """One topology's closed-loop simulator, the runs its plugin's simulation facet offers
    (:class:`codegen.topology.Topology`), written once: its C API, how a model fills its parameters
    (``params_from_model(ffi, model, substep_max_s)``, RK4 sub-steps of at most ``substep_max_s``, None:
    :data:`MAX_SUBSTEP_S`) and how trace arrays become its ``Trace`` (``trace_from(arrays, model)``)."""

    api: SimApi
    params_from_model: Callable[[Any, Model, float | None], Any]
    trace_from: Callable[[dict[str, np.ndarray], Model], Any]

    def run(self, ffi: Any, lib: Any, model: Model, progress: Callable[[float], None] | None = None, *,
            chunk: int = DEFAULT_CHUNK, substep_max_s: float | None = None, initial_speed_rpm: float = 0.0) -> Any:
        """Run the model's scenario through the compiled loop (``(ffi, lib)``: a cffi library holding
        ``<api>_init``/``<api>_run`` built with the controller for ``model``), the plant starting at
        ``initial_speed_rpm``; return the ``Trace``.  ``progress`` is called after every chunk with the
        completed fraction.  Raises :class:`SimulationError` on refused parameters or divergence."""
        params = self.params_from_model(ffi, model, substep_max_s)
        arrays = run_chunked(ffi, lib, self.api, model, params, progress, chunk,
                             initial_speed_rad_s=rpm_to_rad_s(initial_speed_rpm))
        return self.trace_from(arrays, model)

    def closed_loop_trace(self, model: Model, lib: HostLib) -> Any:
        """The ``Trace`` of the model's scenario through ``lib`` (built with the simulator): ``mpcgen
        simulate``'s run."""
        return self.run(lib.ffi, lib.lib, model)

    def period_stepper(self, lib: HostLib, model: Model, *, substep_max_s: float | None = None,
                       initial_speed_rpm: float = 0.0) -> PeriodStepper:
        """The closed loop of :meth:`run` one period at a time, the decision given from outside (``lib``:
        built with the simulator; its ffi, library and the step's records)."""
        return PeriodStepper(lib.ffi, lib.lib, self.api, model, self.params_from_model(lib.ffi, model, substep_max_s),
                             lib.records.input.dtype, lib.records.output.dtype,
                             initial_speed_rad_s=rpm_to_rad_s(initial_speed_rpm))

    def firmware_plant(self, model: Model) -> dict[str, str]:
        """File name -> text of the on-board plant (the serial HIL's mode onboard): the plant core, compiled
        there in float32, and the topology's part of firmware/runtime/onboard.h's loop
        (:func:`codegen.simulator.api.firmware_files`)."""
        return firmware_files(self.api)
