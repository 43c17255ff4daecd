"""Closed-loop simulation of the two-level drive: scenario -> compiled loop -> Trace.

The whole period loop (plant sampling, speed PI, controller step, RK4 plant
integration) runs in C (``firmware/runtime/sim2l.c`` + ``plant2l.c`` + the
generated controller step, compiled by the host build into one cffi
library); Python only prepares the scenario arrays, calls ``sim2l_run`` once
per chunk of periods (so progress can be reported) and wraps the recorded
arrays into a :class:`Trace`.  The plant, PI and previous-switch state is
carried across chunks in a ``sim2l_state_t``, so a chunked run equals one long
run bit for bit.

Specification: shared/spec/plant-and-metrics.md ("Plant", "Sampling",
"Timing", "Fast") and shared/spec/mptc-two-level.md ("Parameters and
scenarios").  Timing and PI details: firmware/runtime/sim2l_api.h.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from .errors import MpcgenError
from .model import Model
from .twolevel.interface import INPUT_DTYPE

__all__ = [
    "MAX_SUBSTEP_S",
    "DEFAULT_CHUNK",
    "SimulationError",
    "Trace",
    "default_substeps",
    "n_periods",
    "scenario_arrays",
    "params_from_model",
    "run_closed_loop",
    "run_chunked",
    "fill_common_params",
    "controller_inputs",
]

#: Largest RK4 sub-step (plant-and-metrics.md "Integration": at most 1 us).
MAX_SUBSTEP_S = 1e-6
#: Periods per sim2l_run call (one progress report per chunk).
DEFAULT_CHUNK = 10_000

RPM_TO_RAD_S = 2.0 * math.pi / 60.0

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


def params_from_model(ffi: Any, model: Model, substeps: int | None = None) -> Any:
    """A new ``sim2l_params_t *`` filled from the model.

    ``substeps`` defaults to :func:`default_substeps` (sub-step <= 1 us).
    ``speed_imposed`` is set when ``scenario.speed_mode == "imposed"`` (the
    load machine holds the speed profile; the torque reference is then the
    scenario's load torque, see sim2l_api.h).
    """
    c = model.controller
    p = fill_common_params(ffi.new("sim2l_params_t *"), model)
    p.substeps = int(substeps) if substeps is not None else default_substeps(c.dt_s)
    p.delay_compensation = 1 if c.delay_compensation else 0
    return p


def fill_common_params(p: Any, model: Model) -> Any:
    """Set the fields sim2l_params_t and sim3l_params_t share (motor, Udc, dt, speed PI, mode)."""
    m, inv, c, sl = model.motor, model.inverter, model.controller, model.speed_loop
    p.rs_ohm = m.rs_ohm
    p.ld_h = m.ld_h
    p.lq_h = m.lq_h
    p.psi_f_wb = m.psi_f_wb
    p.pole_pairs = int(m.pole_pairs)
    p.j_kgm2 = m.j_kgm2
    p.b_nms = m.b_nms
    p.udc_v = inv.udc_v
    p.dt_s = c.dt_s
    p.kp = sl.kp
    p.ki = sl.ki
    p.limit_nm = sl.limit_nm
    p.speed_imposed = 1 if model.scenario.speed_mode == "imposed" else 0
    return p


@dataclass(frozen=True, eq=False)
class Trace:
    """One closed-loop run, one entry per control period (read-only arrays).

    Values are taken at the sample instant t_k = k*dt_s, before the period's
    switching state is applied.  Plant quantities are float64; controller
    outputs keep their C types (float32 estimates, uint16 decisions).
    ``sw`` is the controller's decision at k; ``sw_applied`` the state the
    inverter holds during [t_k, t_k+1) (equal to ``sw`` without delay
    compensation, the previous decision with it).
    """

    dt_s: float
    t_s: np.ndarray
    speed_ref_rad_s: np.ndarray
    load_nm: np.ndarray
    omega_m_rad_s: np.ndarray
    te_nm: np.ndarray  # plant torque
    torque_ref_nm: np.ndarray  # T* (speed-PI output, or the load in imposed-speed runs)
    psi_wb: np.ndarray  # plant stator-flux magnitude
    ia_a: np.ndarray
    ib_a: np.ndarray
    theta_e_rad: np.ndarray
    sw: np.ndarray
    sw_applied: np.ndarray
    vector: np.ndarray
    n_eval: np.ndarray
    fault: np.ndarray
    te_est_nm: np.ndarray  # controller estimate (float32)
    psi_est_wb: np.ndarray  # controller estimate (float32)

    @property
    def n(self) -> int:
        """Number of periods."""
        return int(self.t_s.shape[0])

    @property
    def duration_s(self) -> float:
        """Simulated time n*dt_s."""
        return self.n * self.dt_s

    @property
    def ic_a(self) -> np.ndarray:
        """Phase-c current, i_c = -i_a - i_b (isolated star point)."""
        return -self.ia_a - self.ib_a

    @property
    def speed_rpm(self) -> np.ndarray:
        """Mechanical speed in r/min."""
        return self.omega_m_rad_s / RPM_TO_RAD_S

    @property
    def speed_ref_rpm(self) -> np.ndarray:
        """Mechanical speed reference in r/min."""
        return self.speed_ref_rad_s / RPM_TO_RAD_S


_DOUBLE_FIELDS = (
    "t_s", "speed_ref_rad_s", "omega_m_rad_s", "te_nm", "torque_ref_nm", "psi_wb",
    "ia_a", "ib_a", "theta_e_rad",
)
_U16_FIELDS = ("sw", "sw_applied", "vector", "n_eval", "fault")
_F32_FIELDS = ("te_est_nm", "psi_est_wb")
#: Trace members: (dtype, values per period), in the order they are allocated.
_FIELDS = {
    **{name: (np.float64, 1) for name in _DOUBLE_FIELDS},
    **{name: (np.uint16, 1) for name in _U16_FIELDS},
    **{name: (np.float32, 1) for name in _F32_FIELDS},
}
_CTYPE = {np.dtype(np.float64): "double *", np.dtype(np.uint16): "unsigned short *",
          np.dtype(np.float32): "float *"}

_RUN_ERRORS = {
    -1: "invalid simulator arguments (motor/inverter/speed-loop parameters)",
    -2: "the plant state became non-finite (the drive diverged)",
    -3: "the controller returned a switching state outside 0..7",
}


def run_closed_loop(
    ffi: Any,
    lib: Any,
    model: Model,
    progress: Callable[[float], None] | None = None,
    *,
    chunk: int = DEFAULT_CHUNK,
    substeps: int | None = None,
) -> Trace:
    """Run the model's scenario through the compiled loop; return the trace.

    ``(ffi, lib)`` is a cffi library holding ``sim2l_init`` and ``sim2l_run``
    (built with the controller generated for ``model``).  ``progress`` is
    called after every chunk with the completed fraction in (0, 1].
    Raises :class:`SimulationError` if the simulator refuses the parameters
    or the run diverges.
    """
    params = params_from_model(ffi, model, substeps)
    arrays = run_chunked(ffi, lib, "sim2l", model, params, _FIELDS, _RUN_ERRORS, progress, chunk)
    return Trace(dt_s=float(model.controller.dt_s), **arrays)


def run_chunked(
    ffi: Any,
    lib: Any,
    api: str,
    model: Model,
    params: Any,
    fields: dict[str, tuple[Any, int]],
    errors: dict[int, str],
    progress: Callable[[float], None] | None,
    chunk: int,
    initial_speed_rad_s: float = 0.0,
) -> dict[str, np.ndarray]:
    """Drive ``<api>_init`` + ``<api>_run`` over the model's scenario, chunk by chunk.

    ``initial_speed_rad_s``: mechanical speed of the plant at t = 0 (default
    standstill), e.g. to start a load-step scenario at rated speed.

    ``fields`` maps each trace member to (dtype, values per period); a member
    with w > 1 values per period is returned with shape (n, w).  The returned
    arrays (plus ``load_nm``) are read-only.  ``errors`` maps the C return
    codes to messages.  ``progress`` is called after every chunk with the
    completed fraction in (0, 1].  Raises :class:`SimulationError` if the
    simulator refuses the parameters or the run diverges.
    """
    if chunk < 1:
        raise ValueError("chunk must be >= 1")
    speed_ref, load = scenario_arrays(model)
    n = speed_ref.shape[0]
    state = ffi.new(f"{api}_state_t *")
    where = f"{model.source or model.name}"
    if getattr(lib, f"{api}_init")(params, state) != 0:
        raise SimulationError(f"{where}: {errors[-1]}")
    state.omega_m_rad_s = float(initial_speed_rad_s)
    run = getattr(lib, f"{api}_run")

    arrays: dict[str, np.ndarray] = {k: np.zeros(n * w, dtype=t) for k, (t, w) in fields.items()}
    keep = []  # keep the buffers alive while C holds pointers into them
    base = {}
    for name, arr in arrays.items():
        buf = ffi.from_buffer(arr, require_writable=True)
        keep.append(buf)
        base[name] = ffi.cast(_CTYPE[arr.dtype], buf)
    ref_buf, load_buf = ffi.from_buffer(speed_ref), ffi.from_buffer(load)
    ref_ptr, load_ptr = ffi.cast("double *", ref_buf), ffi.cast("double *", load_buf)
    trace_c = ffi.new(f"{api}_trace_t *")

    k0 = 0
    while k0 < n:
        k1 = min(n, k0 + chunk)
        for name, ptr in base.items():
            setattr(trace_c, name, ptr + k0 * fields[name][1])
        rc = run(params, ref_ptr + k0, load_ptr + k0, k1 - k0, trace_c, state)
        if rc != 0:
            k_fail = int(state.k)
            reason = errors.get(rc, f"simulator error {rc}")
            raise SimulationError(
                f"{where}: closed-loop run stopped at period {k_fail} "
                f"(t = {k_fail * model.controller.dt_s:.6g} s): {reason}"
            )
        k0 = k1
        if progress is not None:
            progress(k1 / n)
    del keep, ref_buf, load_buf

    for name, (_, w) in fields.items():
        if w > 1:
            arrays[name] = arrays[name].reshape(n, w)
    arrays["load_nm"] = load
    for arr in arrays.values():
        arr.flags.writeable = False
    speed_ref.flags.writeable = False
    return arrays


def controller_inputs(trace: Trace, model: Model) -> np.ndarray:
    """The controller-step inputs of every period, exactly as the C loop built them.

    Returns an ``INPUT_DTYPE`` record array (the states a closed-loop run fed
    to the step), for replaying through the Python reference and the
    generated C (numerics.md "Test states" (a)).  Every float field is the
    float64 sample rounded once to float32, as the C cast does;
    ``sw_prev`` is the previous decision (0 before the first period).
    """
    rec = np.zeros(trace.n, dtype=INPUT_DTYPE)
    rec["ia_a"] = trace.ia_a.astype(np.float32)
    rec["ib_a"] = trace.ib_a.astype(np.float32)
    rec["theta_e_rad"] = trace.theta_e_rad.astype(np.float32)
    rec["omega_e_rad_s"] = (float(model.motor.pole_pairs) * trace.omega_m_rad_s).astype(np.float32)
    rec["udc_v"] = np.float32(model.inverter.udc_v)
    rec["torque_ref_nm"] = trace.torque_ref_nm.astype(np.float32)
    sw_prev = np.zeros(trace.n, dtype=np.uint16)
    sw_prev[1:] = trace.sw[:-1]
    rec["sw_prev"] = sw_prev
    return rec
