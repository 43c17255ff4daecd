"""Closed-loop simulation of the T-type three-level drive: scenario -> compiled loop -> Trace3.

The whole period loop (sampling, speed PI, controller step, seven-segment RK4
plant integration with the neutral point) runs in C
(``firmware/runtime/sim3l.c`` + ``plant3l.c`` + the generated controller
step, compiled into one cffi library); Python prepares the scenario arrays
(:func:`codegen.simulate.scenario_arrays`), calls ``sim3l_run`` once per
chunk of periods and wraps the recorded arrays into a :class:`Trace3`.  The
plant, PI and applied-decision state is carried across chunks in a
``sim3l_state_t``, so a chunked run equals one long run bit for bit.

Timing (mpdtc-three-level.md: the controller always uses one-step delay
compensation): the decision computed at t_k is applied during
[t_k+1, t_k+2); before the first period the inverter holds OOO.  Details:
firmware/runtime/sim3l_api.h.  Plant model and the V_o sign convention
(dV_o/dt = i_o/(2C), i_o = sum (1-|S_x|) i_x): firmware/runtime/plant3l.h.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from codegen.model import Model
from codegen.simulator.driver import (
    DEFAULT_CHUNK,
    MAX_SUBSTEP_S,
    RPM_TO_RAD_S,
    SHARED_HEADERS,
    SHARED_SOURCES,
    fill_common_params,
    run_chunked,
)
from codegen.topologies.ttype.records import INPUT_DTYPE as INPUT3_DTYPE

#: Segments per control period.
N_SEG = 7
#: State index of OOO (applied before the first decision).
OOO = 13

#: C of the T-type closed loop (plant + period loop), with its cffi API header.
CSRC = Path(__file__).resolve().parent / "csrc"
RUNTIME = CSRC
SIM_API = CSRC / "sim3l_api.h"
SIM_SOURCES: tuple[Path, ...] = (*SHARED_SOURCES, CSRC / "plant3l.c", CSRC / "sim3l.c")
SIM_HEADERS: tuple[Path, ...] = (*SHARED_HEADERS, CSRC / "plant3l.h")
RUNTIME_SOURCES = SIM_SOURCES



def _strip_preprocessor(text: str) -> str:
    return "\n".join(line for line in text.splitlines() if not line.lstrip().startswith("#"))


def runtime_cdef() -> str:
    """cffi cdef of the loop: sim3l_api.h verbatim + plant3l.h without preprocessor lines."""
    api = (RUNTIME / "sim3l_api.h").read_text()
    plant = _strip_preprocessor((RUNTIME / "plant3l.h").read_text())
    return api + "\n" + plant + "\n"


def params_from_model3(ffi: Any, model: Model, substep_max_s: float | None = None) -> Any:
    """A new ``sim3l_params_t *`` filled from the model.

    Udc and each capacitor C from ``model.inverter`` (``udc_v``, ``c_f``);
    ``substep_max_s`` defaults to :data:`MAX_SUBSTEP_S`; ``speed_imposed``
    when ``scenario.speed_mode == "imposed"`` (T* is then the load torque).
    """
    p = fill_common_params(ffi.new("sim3l_params_t *"), model)
    p.c_f = model.inverter.c_f
    p.substep_max_s = float(substep_max_s) if substep_max_s is not None else MAX_SUBSTEP_S
    return p


@dataclass(frozen=True, eq=False)
class Trace3:
    """One three-level closed-loop run (read-only arrays).

    Per-period arrays (n,) are taken at the sample instant t_k = k*dt_s;
    plant quantities float64, controller outputs in their C types.
    ``vector``/``t_n_s`` are the decision of period k (applied during
    [t_k+1, t_k+2)); ``applied_vector``, ``uab_v``, ``seg_s``, ``seg_states``
    and ``leg_changes`` describe the period actually applied during
    [t_k, t_k+1).  Per-segment arrays have shape (n, 7); zero-length
    segments (``seg_s == 0``) were not applied.
    """

    dt_s: float
    udc_v: float
    t_s: np.ndarray
    speed_ref_rad_s: np.ndarray
    load_nm: np.ndarray
    omega_m_rad_s: np.ndarray
    te_nm: np.ndarray  # plant torque
    torque_ref_nm: np.ndarray
    psi_wb: np.ndarray  # plant stator-flux magnitude
    ia_a: np.ndarray
    ib_a: np.ndarray
    ic_a: np.ndarray
    theta_e_rad: np.ndarray
    vo_v: np.ndarray  # plant neutral-point voltage (u_c1 - u_c2)/2
    vector: np.ndarray
    n_eval: np.ndarray
    fault: np.ndarray
    t_n_s: np.ndarray  # float32
    te_est_nm: np.ndarray  # float32
    psi_est_wb: np.ndarray  # float32
    psi_ref_wb: np.ndarray  # float32, the controller's flux reference
    vo_est_v: np.ndarray  # float32
    applied_vector: np.ndarray
    leg_changes: np.ndarray
    uab_v: np.ndarray  # (n, 7)
    seg_s: np.ndarray  # (n, 7)
    seg_states: np.ndarray  # (n, 7)

    @property
    def n(self) -> int:
        return int(self.t_s.shape[0])

    @property
    def duration_s(self) -> float:
        return self.n * self.dt_s

    @property
    def speed_rpm(self) -> np.ndarray:
        return self.omega_m_rad_s / RPM_TO_RAD_S

    @property
    def speed_ref_rpm(self) -> np.ndarray:
        return self.speed_ref_rad_s / RPM_TO_RAD_S

    @property
    def uc1_v(self) -> np.ndarray:
        return 0.5 * self.udc_v + self.vo_v

    @property
    def uc2_v(self) -> np.ndarray:
        return 0.5 * self.udc_v - self.vo_v


_PER_PERIOD = {
    "t_s": np.float64, "speed_ref_rad_s": np.float64, "omega_m_rad_s": np.float64,
    "te_nm": np.float64, "torque_ref_nm": np.float64, "psi_wb": np.float64,
    "ia_a": np.float64, "ib_a": np.float64, "ic_a": np.float64, "theta_e_rad": np.float64,
    "vo_v": np.float64,
    "vector": np.uint16, "n_eval": np.uint16, "fault": np.uint16,
    "t_n_s": np.float32, "te_est_nm": np.float32, "psi_est_wb": np.float32,
    "psi_ref_wb": np.float32, "vo_est_v": np.float32,
    "applied_vector": np.uint16, "leg_changes": np.uint16,
}
_PER_SEGMENT = {"uab_v": np.float64, "seg_s": np.float64, "seg_states": np.uint16}
#: Trace members: (dtype, values per period).
_FIELDS = {**{k: (t, 1) for k, t in _PER_PERIOD.items()}, **{k: (t, N_SEG) for k, t in _PER_SEGMENT.items()}}

_RUN_ERRORS = {
    -1: "invalid simulator arguments (motor/inverter/speed-loop parameters)",
    -2: "the plant state became non-finite (the drive diverged)",
    -3: "the controller returned an invalid decision (vector, states or segment times)",
}


def run_closed_loop3(
    ffi: Any,
    lib: Any,
    model: Model,
    progress: Callable[[float], None] | None = None,
    *,
    chunk: int = DEFAULT_CHUNK,
    substep_max_s: float | None = None,
    initial_speed_rpm: float = 0.0,
) -> Trace3:
    """Run the model's scenario through the compiled three-level loop.

    ``(ffi, lib)``: a cffi library holding ``sim3l_init``/``sim3l_run`` (cdef
    :func:`runtime_cdef`) built with the controller for ``model``.
    ``progress`` is called after every chunk with the completed fraction.
    Raises :class:`SimulationError` on refused parameters or divergence.
    """
    params = params_from_model3(ffi, model, substep_max_s)
    arrays = run_chunked(ffi, lib, "sim3l", model, params, _FIELDS, _RUN_ERRORS, progress, chunk,
                         initial_speed_rad_s=initial_speed_rpm * 2.0 * math.pi / 60.0)
    return Trace3(dt_s=float(model.controller.dt_s), udc_v=float(model.inverter.udc_v), **arrays)


def controller_inputs3(trace: Trace3, model: Model) -> np.ndarray:
    """The controller-step inputs of every period, exactly as the C loop built them.

    ``INPUT3_DTYPE`` records, for replaying through the Python reference and
    the generated C.  Every float field is one float64 value rounded to
    float32 as the C cast does: u_c1 = 0.5*Udc + V_o, u_c2 = 0.5*Udc - V_o
    (the same double expressions as sim3l.c); ``prev_vector`` is the previous
    decision (13 = OOO at k = 0) and ``t_n_prev_s`` its T_N (0 at k = 0).
    """
    udc = float(model.inverter.udc_v)
    rec = np.zeros(trace.n, dtype=INPUT3_DTYPE)
    rec["ia_a"] = trace.ia_a.astype(np.float32)
    rec["ib_a"] = trace.ib_a.astype(np.float32)
    rec["theta_e_rad"] = trace.theta_e_rad.astype(np.float32)
    rec["omega_e_rad_s"] = (float(model.motor.pole_pairs) * trace.omega_m_rad_s).astype(np.float32)
    rec["uc1_v"] = (0.5 * udc + trace.vo_v).astype(np.float32)
    rec["uc2_v"] = (0.5 * udc - trace.vo_v).astype(np.float32)
    rec["torque_ref_nm"] = trace.torque_ref_nm.astype(np.float32)
    prev = np.full(trace.n, OOO, dtype=np.uint16)
    prev[1:] = trace.vector[:-1]
    rec["prev_vector"] = prev
    t_n_prev = np.zeros(trace.n, dtype=np.float32)
    t_n_prev[1:] = trace.t_n_s[:-1]
    rec["t_n_prev_s"] = t_n_prev
    return rec

