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

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from codegen.model import Model
from codegen.simulator.driver import (
    DEFAULT_CHUNK,
    RPM_TO_RAD_S,
    SHARED_HEADERS,
    SHARED_SOURCES,
    default_substeps,
    fill_common_params,
    run_chunked,
)
from codegen.topologies.twolevel.records import INPUT_DTYPE

#: C of the two-level closed loop (plant + period loop), with its cffi API header.
CSRC = Path(__file__).resolve().parent / "csrc"
SIM_API = CSRC / "sim2l_api.h"
SIM_SOURCES: tuple[Path, ...] = (*SHARED_SOURCES, CSRC / "plant2l.c", CSRC / "sim2l.c")
SIM_HEADERS: tuple[Path, ...] = (*SHARED_HEADERS, CSRC / "plant2l.h")


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


@dataclass(frozen=True, eq=False)
class Trace:
    """One closed-loop run, one entry per control period (read-only arrays).

    Values are taken at the sample instant t_k = k*dt_s, before the period's
    switching state is applied.  Plant quantities are float64; controller
    outputs keep their C types (float32 estimates, uint16 decisions).
    ``sw`` is the controller's decision at k; ``applied_sw`` the state the
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
    applied_sw: np.ndarray
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
_U16_FIELDS = ("sw", "applied_sw", "vector", "n_eval", "fault")
_F32_FIELDS = ("te_est_nm", "psi_est_wb")
#: Trace members: (dtype, values per period), in the order they are allocated.
_FIELDS = {
    **{name: (np.float64, 1) for name in _DOUBLE_FIELDS},
    **{name: (np.uint16, 1) for name in _U16_FIELDS},
    **{name: (np.float32, 1) for name in _F32_FIELDS},
}

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


def controller_inputs(trace: Trace, model: Model) -> np.ndarray:
    """The controller-step inputs of every period, exactly as the C loop built them.

    Returns an ``INPUT_DTYPE`` record array (the states a closed-loop run fed
    to the step), for replaying through the Python reference and the
    generated C (numerics.md "Test states" (a)).  Every float field is the
    float64 sample rounded once to float32, as the C cast does;
    ``prev_sw`` is the previous decision (0 before the first period).
    """
    rec = np.zeros(trace.n, dtype=INPUT_DTYPE)
    rec["ia_a"] = trace.ia_a.astype(np.float32)
    rec["ib_a"] = trace.ib_a.astype(np.float32)
    rec["theta_e_rad"] = trace.theta_e_rad.astype(np.float32)
    rec["omega_e_rad_s"] = (float(model.motor.pole_pairs) * trace.omega_m_rad_s).astype(np.float32)
    rec["udc_v"] = np.float32(model.inverter.udc_v)
    rec["torque_ref_nm"] = trace.torque_ref_nm.astype(np.float32)
    prev_sw = np.zeros(trace.n, dtype=np.uint16)
    prev_sw[1:] = trace.sw[:-1]
    rec["prev_sw"] = prev_sw
    return rec
