"""The closed-loop simulator's driver, shared by every topology.

The whole period loop of a topology (plant sampling, speed PI, controller
step, RK4 plant integration) runs in C: the topology's ``csrc/`` sources,
the shared dq model and speed PI in ``csrc/`` here, and the generated
controller step, compiled by the host build into one cffi library.  This
module prepares the scenario arrays, fills the parameters every topology's
simulator shares, and calls ``<api>_run`` once per chunk of periods (so
progress can be reported), carrying the C state across chunks so a chunked
run equals one long run bit for bit.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from codegen.errors import MpcgenError
from codegen.model import Model

#: C sources of the shared dq model and speed PI (float64, host only).
CSRC = Path(__file__).resolve().parent / "csrc"
SHARED_SOURCES: tuple[Path, ...] = (CSRC / "pmsm_dq.c", CSRC / "speed_pi.c")
SHARED_HEADERS: tuple[Path, ...] = (CSRC / "pmsm_dq.h", CSRC / "speed_pi.h")

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


_CTYPE = {np.dtype(np.float64): "double *", np.dtype(np.uint16): "unsigned short *",
          np.dtype(np.float32): "float *"}


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
