"""A plant that obeys the controller's safe state (issue 28): the step's ``gates_off`` opens the inverter.

``controller.fault_action`` decides what a tripped guard asks of the power stage: "gates-off"
(``gates_off`` = 1: every switch off) or "active-short-circuit" (``gates_off`` = 0: the safe
vector, which shorts the phases, is applied).  The simulator's plant now does what the output
says (docs/simulation.md "Fault behaviour of the plant"): an open inverter lets each phase current
freewheel through its diodes against the DC link until it reaches zero; the short circuit lets
it ring with the back-EMF.  Before, both gave the same run bit for bit.

* A high-speed spindle (1 pole pair, 150 uH, 30 000 r/min imposed, 25 us periods: the current
  moves by 50 A per period against a 75 A trip) trips its current guard.  The two fault actions
  give the same run up to the first trip's actuation, then different currents: with the gates off
  every open period only lowers the currents (the line back-EMF, 163 V peak, is below the 310 V
  DC link); the short circuit drives them far beyond the trip (its current psi_f/L = 200 A plus
  the transient).
* A guard that stays tripped (T* beyond its guard from 2 ms on): with the gates off the currents
  reach exactly zero and stay there (zero torque); the short circuit settles to its steady state
  at the imposed speed, from u = 0 in the dq equations (surface PMSM, w = w_e):
      0 = -Rs i_d + w Ls i_q,  0 = -Rs i_q - w Ls i_d - w psi_f
      =>  i_d = -w^2 Ls psi_f/(Rs^2 + w^2 Ls^2),  i_q = -w Rs psi_f/(Rs^2 + w^2 Ls^2),
  reached to a relative 1e-4 after more than ten time constants Ls/Rs.  Both topologies (T-type:
  OOO is the short circuit; with the gates off V_o is held, the clamp devices being off).
* A gates-off request takes effect with the actuation delay of a decision, and the closed loop's
  plant follows the analytic decays (through the period-by-period entry points, the output
  records given): from a current I0 in the winding pair a-b at standstill, the held 000 (a short
  circuit) for the first d periods, i = I0 exp(-t Rs/Ls), then the open inverter, the pair (R = 2
  Rs, L = 2 Ls) across the DC link, L di/dt = -(Udc + R i) from I1 = i(d dt), zero at d dt +
  (L/R) ln(1 + R I1/Udc) (derivation: tests/topologies/twolevel/test_plant_gates_off.py); compared
  at the period boundaries to a relative 1e-9 and the zero within the period that contains it.
* The open inverter compiles in float32 (the firmware's on-board plant): the same pair's zero
  crossing within one sub-step of t0.
"""
from __future__ import annotations

import math
import subprocess
from pathlib import Path

import numpy as np
import pytest

from codegen.config import load_config
from codegen.simulator.api import CORE_HEADERS
from codegen.topologies.ttype import sim as ttype_sim
from codegen.topologies.twolevel import sim as twolevel_sim
from codegen.topology import topology_of

from conftest import STRICT_WARN

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
RPM = 2 * math.pi / 60
#: a high-speed spindle on the 400 W servo's inverter and controller: low inductance, 30 000 r/min
SPINDLE = {"motor.rs_ohm": 0.05, "motor.ld_h": 150e-6, "motor.lq_h": 150e-6, "motor.psi_f_wb": 0.03,
           "motor.pole_pairs": 1, "motor.rated_speed_rpm": 30000.0, "motor.rated_torque_nm": 0.6,
           "motor.j_kgm2": 1e-4, "inverter.i_trip_a": 75.0, "controller.psi_ref_wb": 0.035,
           "controller.eps_t_nm": 0.03, "speed_loop.limit_nm": 1.0, "speed_loop.kp": 0.001,
           "speed_loop.ki": 0.1, "scenario.speed_mode": "imposed", "scenario.speed_ref_rpm": [[0.0, 30000.0]],
           "scenario.load_nm": [[0.0, 0.6]], "scenario.duration_s": 0.01}
#: the T-type example at rated speed (line back-EMF peak 122 V, DC link 220 V)
TLEVEL = {"controller.strategy": "mpdtc27", "scenario.set": "config", "scenario.speed_mode": "imposed",
          "scenario.speed_ref_rpm": [[0.0, 3000.0]]}
ACTIONS = ("gates-off", "active-short-circuit")


def _run(config: str, overrides: dict[str, object], sim, initial_rpm: float):
    m = load_config(EXAMPLES / config, overrides)
    topo = topology_of(m)
    lib = topo.host_library(m, topo.derive(m), with_sim=True)
    return m, sim.run_closed_loop(lib.ffi, lib.lib, m, initial_speed_rpm=initial_rpm)


def _imax(tr) -> np.ndarray:
    return np.max(np.abs(np.stack([tr.ia_a, tr.ib_a, tr.ic_a])), axis=0)


@pytest.fixture(scope="module")
def spindle_trips():
    return {fa: _run("servo400w.toml", {**SPINDLE, "controller.fault_action": fa}, twolevel_sim, 30000.0)
            for fa in ACTIONS}


def test_spindle_trip_gates_off_and_short_circuit_differ(spindle_trips):
    (m, off), (_, asc) = spindle_trips["gates-off"], spindle_trips["active-short-circuit"]
    d = m.plant.delay_periods(m.controller.delay_compensation)
    assert d == 1
    k = int(np.argmax(off.fault != 0))
    assert off.fault[k] & 1 and asc.fault[k] & 1  # the CURRENT guard
    # the same run up to the first trip's actuation ...
    for name in ("ia_a", "ib_a", "te_nm", "sw"):
        assert getattr(off, name)[:k + d + 1].tobytes() == getattr(asc, name)[:k + d + 1].tobytes(), name
    # ... then different currents
    assert np.abs(off.ia_a[k + d + 1] - asc.ia_a[k + d + 1]) > 1.0
    # the step's request and the plant's inverter, the request acting d periods later
    assert np.array_equal(off.gates_off, (off.fault != 0).astype(np.uint16))
    assert np.array_equal(off.inverter_open[d:], off.gates_off[:-d]) and not off.inverter_open[:d].any()
    assert not asc.gates_off.any() and not asc.inverter_open.any()
    assert np.all(off.sw[off.fault != 0] == 0) and np.all(asc.sw[asc.fault != 0] == 0)  # the safe vector 000
    # an open period only lowers the currents (the back-EMF is below the DC link) ...
    i_off, i_asc = _imax(off), _imax(asc)
    opened = np.flatnonzero(off.inverter_open[:-1])
    assert len(opened) > 5 and np.all(i_off[opened + 1] < i_off[opened])
    # ... the short circuit rings far beyond the trip
    assert i_asc.max() > 200.0 > 1.5 * i_off.max()


def _asc_steady(m, speed_rpm: float) -> tuple[float, float]:
    """(i_d, i_q) of the short circuit's steady state at the imposed speed (module docstring)."""
    w = m.motor.pole_pairs * speed_rpm * RPM
    rs, ls, pf = m.motor.rs_ohm, m.motor.ld_h, m.motor.psi_f_wb
    den = rs * rs + (w * ls) ** 2
    return -w * w * ls * pf / den, -w * rs * pf / den


@pytest.mark.parametrize("fault_action", ACTIONS)
@pytest.mark.parametrize("case", ["two-level", "T-type"])
def test_a_guard_that_stays_tripped(case, fault_action):
    if case == "two-level":
        config, over, sim, rpm = "servo400w.toml", {**SPINDLE, "scenario.duration_s": 0.04}, twolevel_sim, 30000.0
    else:
        config, over, sim, rpm = "seed000_tlevel.toml", {**TLEVEL, "scenario.duration_s": 0.02}, ttype_sim, 3000.0
    trip_s = 0.002
    over = {**over, "controller.fault_action": fault_action,
            "scenario.load_nm": [[0.0, over.get("scenario.load_nm", [[0.0, 1.27]])[0][1]], [trip_s, 100.0]]}
    m, tr = _run(config, over, sim, rpm)
    k_trip = round(trip_s / m.controller.dt_s)
    assert np.all(tr.fault[k_trip:] & 32)  # TORQUE_REF from then on
    if fault_action == "gates-off":
        assert np.all(tr.inverter_open[k_trip + 1:] == 1)
        zero = (tr.ia_a == 0.0) & (tr.ib_a == 0.0)
        k0 = k_trip + int(np.argmax(zero[k_trip:]))
        assert zero[k0] and np.all(zero[k0:]) and k0 < k_trip + 10  # within a few periods, then for good
        assert np.all(tr.te_nm[k0:] == 0.0)
        if case == "T-type":
            assert np.all(tr.vo_v[k_trip + 2:] == tr.vo_v[k_trip + 1])  # no midpoint current
    else:
        assert not tr.inverter_open.any()
        i_d, i_q = _asc_steady(m, rpm)
        th = tr.theta_e_rad[-1]
        ial, ibe = i_d * math.cos(th) - i_q * math.sin(th), i_d * math.sin(th) + i_q * math.cos(th)
        scale = math.hypot(i_d, i_q)
        assert abs(tr.ia_a[-1] - ial) < 1e-4 * scale and abs(tr.ib_a[-1] - (-0.5 * ial + math.sqrt(3) / 2 * ibe)) < 1e-4 * scale
        assert tr.te_nm[-1] == pytest.approx(1.5 * m.motor.pole_pairs * m.motor.psi_f_wb * i_q, rel=1e-4)


@pytest.mark.parametrize("d", [0, 1, 2])
def test_gates_off_acts_with_the_actuation_delay_and_decays_analytically(d):
    m = load_config(EXAMPLES / "seed001_spmsm.toml", {
        "scenario.speed_mode": "imposed", "scenario.speed_ref_rpm": [[0.0, 0.0]], "scenario.load_nm": [[0.0, 0.0]],
        "scenario.duration_s": 0.003, "plant.actuation_delay_periods": d})
    topo = topology_of(m)
    lib = topo.host_library(m, topo.derive(m), with_sim=True)
    stepper = topo.period_stepper(lib, m)
    i0, dt = 20.0, m.controller.dt_s
    rs, ls, udc = m.motor.rs_ohm, m.motor.ld_h, m.inverter.udc_v
    stepper.state.common.motor.i_d_a = i0  # i_a = I0, i_b = -I0, i_c = 0 at theta_e = 0
    stepper.state.common.motor.i_q_a = -i0 / math.sqrt(3)
    out = np.zeros(1, lib.records.output.dtype)
    out["sw"], out["fault"], out["gates_off"] = 0, 1, 1  # every period: the safe 000 with the gates off
    for _ in range(stepper.n):
        stepper.input()
        stepper.finish(out)
    tr = stepper.result()
    assert np.all(tr["gates_off"] == 1)
    assert not tr["inverter_open"][:d].any() and np.all(tr["inverter_open"][d:] == 1)
    ia = tr["ia_a"]  # at t_k = k dt
    t = dt * np.arange(len(ia))
    t_open = d * dt
    i1 = i0 * math.exp(-t_open * rs / ls)  # the held 000 short-circuits the pair until then
    r, ell = 2 * rs, 2 * ls
    t_zero = t_open + ell / r * math.log(1 + r * i1 / udc)
    ana = np.where(t <= t_open, i0 * np.exp(-t * rs / ls),
                   (i1 + udc / r) * np.exp(-(t - t_open) * r / ell) - udc / r)
    before = t < t_zero
    assert np.max(np.abs(ia[before] - ana[before])) <= 1e-9 * (i0 + udc / r)
    assert np.all(tr["ib_a"][before] == pytest.approx(-ia[before], rel=1e-9))
    assert np.all(ia[~before] == 0.0) and np.all(tr["ib_a"][~before] == 0.0)
    k_zero = int(np.argmax(~before))
    assert t[k_zero - 1] < t_zero <= t[k_zero] and k_zero > d + 5


FLOAT32_DRIVER = r"""
#include <stdio.h>

#include "sim_inverter.h"

int main(void)
{
    /* the two-level pair a-b at standstill (i_a = 40 A, i_b = -40 A), gates off, 1 us sub-steps */
    sim_open_t c;
    sim_real_t x[4] = {SIM_R(40.0), SIM_R(-23.094010767585), SIM_R(0.0), SIM_R(0.0)};
    int k;
    sim_open_setup(&c, SIM_R(312.0), SIM_R(0.0), 4);
    pmsm_dq_rhs_setup(&c.m, SIM_R(0.2), SIM_R(8.5e-3), SIM_R(8.5e-3), SIM_R(0.175), 4, SIM_R(0.01),
                      SIM_R(0.0), SIM_R(0.0), 1);
    for (k = 1; k <= 3000; ++k) {
        sim_open_interval(&c, x, SIM_R(1e-6), 1);
        printf("%a %a\n", (double)x[0], (double)x[1]);
    }
    return 0;
}
"""


@pytest.mark.parametrize("real", ["f64", "f32"])
def test_the_open_inverter_compiles_in_both_types(tmp_path, real):
    """The core's open inverter, strict flags, float64 and float32 (-DSIM_REAL_F32: the on-board plant):
    the pair reaches zero within one sub-step of t0 = (L/R) ln(1 + R I0/Udc) (R = 2 Rs, L = 2 Ls) and
    stays there; float32 follows the analytic decay to a relative 1e-5."""
    src = tmp_path / "open.c"
    src.write_text(FLOAT32_DRIVER)
    exe = tmp_path / "open"
    dirs = sorted({p.parent for p in CORE_HEADERS})
    defs = ["-DSIM_REAL_F32"] if real == "f32" else []
    r = subprocess.run(["gcc", *STRICT_WARN, *defs, *[f"-I{d}" for d in dirs], str(src), "-o", str(exe), "-lm"],
                       capture_output=True, text=True)
    assert r.returncode == 0 and not r.stderr, r.stderr
    text = subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout
    xdq = np.array([float.fromhex(v) for v in text.split()]).reshape(-1, 2)
    i_a = xdq[:, 0]  # theta_e = 0: i_a = i_d
    t = 1e-6 * np.arange(1, len(i_a) + 1)
    rr, ll, udc, i0 = 0.4, 17e-3, 312.0, 40.0
    t0 = ll / rr * math.log(1 + rr * i0 / udc)
    zero = np.all(xdq == 0.0, axis=1)
    kz = int(np.argmax(zero))
    assert zero[kz] and np.all(zero[kz:])
    assert t[kz] - 1e-6 < t0 <= t[kz] + (1e-6 if real == "f32" else 1e-15)
    ana = (i0 + udc / rr) * np.exp(-t[:kz] * rr / ll) - udc / rr
    assert np.max(np.abs(i_a[:kz] - ana)) <= (1e-5 if real == "f32" else 1e-9) * (i0 + udc / rr)
