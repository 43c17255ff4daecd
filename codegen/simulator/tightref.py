"""A tight-tolerance reference of the plant, independent of the C: scipy's DOP853 at ``rtol = 1e-10``.

The simulator's C integrates the plant with RK4 sub-steps (``plant.integrator = "rk4"``) or with the
Taylor series of each constant-voltage piece (``"exact"``, ``csrc/sim_exact.h``).  This module writes
the same plant equations again, in Python from docs/simulation.md, and integrates them with
``scipy.integrate.solve_ivp(method="DOP853", rtol=1e-10, atol=1e-12)`` piece by piece, so that either
integrator's currents can be measured against it:

- :func:`replay`: the inverter a closed-loop run applied (its trace, period by period, open loop) from
  the run's initial state; :func:`current_error` the largest phase-current difference between a trace
  and that replay (``mpcgen bench`` reports it for both integrators);
- :func:`closed_loop`: the closed loop with this plant instead of the C's (a period stepper: the C
  computes the controller's inputs, the speed PI, the decision queue; the plant's state comes from
  DOP853 every period), whose decisions the tests compare with a run's.

The plant, for every topology (leg levels S_x in {-1, 0, +1}; a two-level leg's 0/1 is -1/+1, the
common mode cancelling): leg voltage to the DC-link midpoint u_xo = S_x*Udc/2 + |S_x|*V_o,
u_alpha = (2/3)*(u_ao - (u_bo + u_co)/2), u_beta = (u_bo - u_co)/sqrt(3), Park at theta_e, the dq motor
  Ld*di_d/dt = u_d - Rs*i_d + w_e*Lq*i_q,  Lq*di_q/dt = u_q - Rs*i_q - w_e*Ld*i_d - w_e*psi_f,
  J*dw_m/dt = 1.5*p*(psi_f*i_q + (Ld - Lq)*i_d*i_q) - T_L - B*w_m  (0 with the speed imposed),
  dtheta_e/dt = p*w_m,  dV_o/dt = sum_x (1 - |S_x|)*i_x / (2*C)
(no leg of a two-level inverter is ever at 0: V_o stays 0).  Dead time: at a leg edge a -> b the leg
sits at min(a, b) while its current (at the edge) is positive, max(a, b) while negative, a at zero,
for min(dead time, segment).  Not modelled here (refused): device drops and the open inverter.
"""
from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

from codegen.model import Model
from codegen.simulator.driver import InverterPeriod, Levels

#: the reference's tolerances (solve_ivp's rtol and atol, the state in SI units)
RTOL = 1e-10
ATOL = 1e-12

_SQRT3 = math.sqrt(3.0)


@dataclasses.dataclass(frozen=True)
class ReferencePlant:
    """The plant's parameters (the ``[plant]`` section's, else the controller's model's)."""

    rs_ohm: float
    ld_h: float
    lq_h: float
    psi_f_wb: float
    pole_pairs: int
    j_kgm2: float
    b_nms: float
    udc_v: float
    c_f: float
    dead_time_s: float
    speed_imposed: bool

    @classmethod
    def of(cls, model: Model) -> ReferencePlant:
        pl = model.plant
        if pl.device_drop_v > 0.0:
            raise ValueError("the tight reference does not model device drops (plant.device_drop_v)")
        return cls(pl.value("rs_ohm", model), pl.value("ld_h", model), pl.value("lq_h", model),
                   pl.value("psi_f_wb", model), int(model.motor.pole_pairs), pl.value("j_kgm2", model),
                   pl.value("b_nms", model), pl.value("udc_v", model), pl.value("c_f", model),
                   float(pl.dead_time_s), model.scenario.speed_mode == "imposed")

    def derivs(self, x: Sequence[float], lv: Levels, load_nm: float) -> list[float]:
        """dx/dt of x = (i_d, i_q, w_m, theta_e, V_o) with the legs at levels lv (see the module doc)."""
        i_d, i_q, wm, th, vo = x
        u = [s * 0.5 * self.udc_v + abs(s) * vo for s in lv]
        ual = 2.0 / 3.0 * (u[0] - 0.5 * (u[1] + u[2]))
        ube = (u[1] - u[2]) / _SQRT3
        c, s = math.cos(th), math.sin(th)
        ud, uq = ual * c + ube * s, -ual * s + ube * c
        we = self.pole_pairs * wm
        did = (ud - self.rs_ohm * i_d + we * self.lq_h * i_q) / self.ld_h
        diq = (uq - self.rs_ohm * i_q - we * self.ld_h * i_d - we * self.psi_f_wb) / self.lq_h
        if self.speed_imposed:
            dwm = 0.0
        else:
            te = 1.5 * self.pole_pairs * (self.psi_f_wb * i_q + (self.ld_h - self.lq_h) * i_d * i_q)
            dwm = (te - load_nm - self.b_nms * wm) / self.j_kgm2
        i_abc = phase_currents(i_d, i_q, th)
        i_o = sum((1 - abs(lvl)) * i for lvl, i in zip(lv, i_abc, strict=True))
        return [did, diq, dwm, we, i_o / (2.0 * self.c_f)]

    def piece(self, x: np.ndarray, lv: Levels, load_nm: float, duration_s: float) -> np.ndarray:
        """x after ``duration_s`` at levels lv (DOP853, RTOL/ATOL)."""
        sol = solve_ivp(lambda _t, y: self.derivs(y, lv, load_nm), (0.0, duration_s), x, method="DOP853",
                        rtol=RTOL, atol=ATOL)
        if not sol.success:
            raise RuntimeError(f"DOP853 failed: {sol.message}")
        return np.asarray(sol.y[:, -1], dtype=float)

    def period(self, x: np.ndarray, period: InverterPeriod, load_nm: float) -> np.ndarray:
        """x after one control period (the angle unwrapped), with the dead time of every leg edge."""
        if period.open or (period.after_open and self.dead_time_s > 0.0):
            raise ValueError("the tight reference does not model the open inverter (gates off)")
        prev = period.before
        for dur, lv in period.segments:
            if not dur > 0.0:
                continue
            if self.dead_time_s > 0.0 and lv != prev:
                dead = min(self.dead_time_s, dur)
                i_abc = phase_currents(x[0], x[1], x[3])
                free = tuple(b if a == b else (min(a, b) if i > 0.0 else (max(a, b) if i < 0.0 else a))
                             for a, b, i in zip(prev, lv, i_abc, strict=True))
                x = self.piece(x, (free[0], free[1], free[2]), load_nm, dead)
                if dur - dead > 0.0:
                    x = self.piece(x, lv, load_nm, dur - dead)
            else:
                x = self.piece(x, lv, load_nm, dur)
            prev = lv
        return x


def phase_currents(i_d: float, i_q: float, theta_e: float) -> tuple[float, float, float]:
    """(i_a, i_b, i_c) of the dq currents at the electrical angle (amplitude-invariant transforms)."""
    c, s = math.cos(theta_e), math.sin(theta_e)
    ial, ibe = i_d * c - i_q * s, i_d * s + i_q * c
    ia, ib = ial, -0.5 * ial + 0.5 * _SQRT3 * ibe
    return ia, ib, -ia - ib


def initial_state(trace: Any) -> np.ndarray:
    """The plant at the trace's first sample instant: (i_d, i_q, w_m, theta_e, V_o), i_d, i_q from the
    recorded phase currents at theta_e."""
    th = float(trace.theta_e_rad[0])
    ia, ib = float(trace.ia_a[0]), float(trace.ib_a[0])
    ial, ibe = ia, (2.0 * ib + ia) / _SQRT3
    c, s = math.cos(th), math.sin(th)
    vo = float(trace.vo_v[0]) if hasattr(trace, "vo_v") else 0.0
    return np.array([ial * c + ibe * s, -ial * s + ibe * c, float(trace.omega_m_rad_s[0]), th, vo])


def replay(model: Model, trace: Any, n: int) -> np.ndarray:
    """The plant states (i_d, i_q, w_m, theta_e, V_o) at t_1 .. t_n of the trace's run, integrated by
    DOP853 from its first sample with the inverter it applied (``trace.applied_period(k)``) and the
    scenario's load (and imposed speed: w_m set to the reference at every period's start, as the C
    does)."""
    plant = ReferencePlant.of(model)
    x = initial_state(trace)
    out = np.zeros((n, 5))
    for k in range(n):
        if plant.speed_imposed:
            x[2] = float(trace.speed_ref_rad_s[k])
        x = plant.period(x, trace.applied_period(k), float(trace.load_nm[k]))
        out[k] = x
    return out


def current_error(model: Model, trace: Any, n: int) -> float:
    """The largest |i_x(C) - i_x(DOP853)| over the phases and the sample instants t_1 .. t_n of the
    trace's run (the C's recorded plant currents against :func:`replay`), A; n at most the trace's
    periods - 1."""
    n = min(n, int(trace.n) - 1)
    states = replay(model, trace, n)
    worst = 0.0
    for k in range(n):
        ref = phase_currents(states[k, 0], states[k, 1], states[k, 3])
        got = (float(trace.ia_a[k + 1]), float(trace.ib_a[k + 1]), float(trace.ic_a[k + 1]))
        worst = max(worst, *(abs(a - b) for a, b in zip(got, ref, strict=True)))
    return worst


def closed_loop(stepper: Any, step: Callable[[np.ndarray], np.ndarray],
                trace_from: Callable[[dict[str, np.ndarray], Model], Any], n: int) -> Any:
    """Periods 0 .. n-1 of a period stepper's closed loop (:class:`codegen.simulator.driver.PeriodStepper`)
    with this module's plant instead of the C's: before each period the stepper's plant state is set to
    the DOP853 one (the motor, and ``vo_v`` where the state has one), the C computes the controller's
    input (sampling, speed PI, decision queue), ``step`` (input records -> output records, e.g.
    ``HostLib.step_batch``) decides, the C records and applies the decision, and DOP853 integrates the
    period the C applied (the trace's ``applied_period``).  ``trace_from``: the topology's (arrays,
    model) -> Trace.  Returns the Trace of the n periods.  Sensors must sample the plant at t_k (no
    measurement delay, no encoder: the C's kept samples and shaft angle are its own plant's)."""
    model = stepper.model
    plant = ReferencePlant.of(model)
    if model.plant.measurement_delay_s > 0.0 or model.plant.encoder_bits > 0:
        raise ValueError("the reference closed loop samples the plant at t_k (no measurement delay or encoder)")
    st = stepper.state
    has_vo = hasattr(st, "vo_v")
    motor = st.common.motor
    x = np.array([motor.i_d_a, motor.i_q_a, motor.omega_m_rad_s, motor.theta_e_rad,
                  st.vo_v if has_vo else 0.0], dtype=float)
    live = trace_from(stepper.live_arrays(), model)
    for k in range(n):
        if plant.speed_imposed:
            x[2] = float(stepper.speed_ref[k])
        x[3] = float(np.mod(x[3], 2.0 * math.pi))
        motor.i_d_a, motor.i_q_a, motor.omega_m_rad_s, motor.theta_e_rad = (float(v) for v in x[:4])
        if has_vo:
            st.vo_v = float(x[4])
        stepper.finish(step(stepper.input()))
        x = plant.period(x, live.applied_period(k), float(stepper.load[k]))
    return trace_from(stepper.result(n), model)
