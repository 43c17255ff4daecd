"""The T-type plant with the gates off (csrc/ttype_plant.c, sim_inverter.h "The open inverter") against
its analytic decay, and the active short circuit (the safe vector OOO applied) against its own.

With every switch off a T-type leg conducts only through the outer diodes (of T1 to P, of T4 from
N); the neutral-point clamp pair T2/T3 is off, so no current leaves the midpoint: V_o is held.
About the midpoint the rails are u_c1 = Udc/2 + V_o and -u_c2 = -(Udc/2 - V_o), Udc apart, so the
open T-type inverter is the open two-level one across the whole DC link (the common mode cancels).

* **Gates off, a winding pair** at standstill (speed imposed 0, no back-EMF; surface PMSM Ls):
  i_a = I0 > 0 on a's lower (N) diode, i_b = -I0 on b's upper (P) diode, c blocked (i_c = 0).  The
  loop a -> b, u_ab = -(u_c1 + u_c2) = -Udc, is R = 2 Rs and L = 2 Ls in series:
      L di/dt = -(Udc + R i)  =>  i(t) = (I0 + Udc/R) exp(-t R/L) - Udc/R,
      zero at t0 = (L/R) ln(1 + R I0/Udc),
  then zero for good (the derivation of the pair's L and R: the two-level test,
  tests/topologies/twolevel/test_plant_gates_off.py).
* **Active short circuit**, OOO (every phase on the midpoint, u = 0, no midpoint current:
  i_o = i_a + i_b + i_c = 0): i_d(t) = i_d0 exp(-t Rs/Ld), i_q(t) = i_q0 exp(-t Rs/Lq), V_o held.

The crossing is compared with t0 at the 1 us sub-step resolution and within 10 ns inside a call,
the decays to a relative 1e-9 (RK4 at 1 us against time constants of a millisecond: rounding).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from tests.fixtures.plantref import plant_params

H = 1e-6
SEED000 = dict(rs_ohm=1.75, ld_h=1.6e-3, lq_h=1.6e-3, psi_f_wb=0.045, pole_pairs=5, j_kgm2=5e-4, b_nms=0.0,
               udc_v=220.0, c_f=1000e-6)
IPM = dict(SEED000, ld_h=1.2e-3, lq_h=2.4e-3, c_f=470e-6)
OOO = 13
VO = 3.5  # V_o of the start, V (held with the gates off)


def _params(ffi, d):
    p = plant_params(ffi, "ttype_sim_params_t", d, imposed=1)
    p.substep_max_s = H
    return p


def _state(ffi, i_a, i_b, theta=0.0):
    ial, ibe = i_a, (i_a + 2 * i_b) / math.sqrt(3)
    i_d, i_q = ial * math.cos(theta) + ibe * math.sin(theta), -ial * math.sin(theta) + ibe * math.cos(theta)
    return ffi.new("ttype_plant_state_t *", {"motor": {"i_d_a": i_d, "i_q_a": i_q, "omega_m_rad_s": 0.0,
                                                       "theta_e_rad": theta}, "vo_v": VO})


def _abc(s):
    m = s.motor
    ial = m.i_d_a * math.cos(m.theta_e_rad) - m.i_q_a * math.sin(m.theta_e_rad)
    ibe = m.i_d_a * math.sin(m.theta_e_rad) + m.i_q_a * math.cos(m.theta_e_rad)
    ia, ib = ial, -0.5 * ial + math.sqrt(3) / 2 * ibe
    return np.array([ia, ib, -ia - ib])


@pytest.mark.parametrize("theta", [0.0, 1.1])
def test_gates_off_winding_pair_reaches_zero_at_t0(stub, theta):
    ffi, lib, _ = stub
    p = _params(ffi, SEED000)
    i0, r, ell, udc = 12.0, 2 * SEED000["rs_ohm"], 2 * SEED000["ld_h"], SEED000["udc_v"]
    t0 = ell / r * math.log(1 + r * i0 / udc)
    s = _state(ffi, i0, -i0, theta)
    n = int(t0 / H) + 200
    i = np.zeros((n, 3))
    for k in range(n):
        assert lib.ttype_plant_advance_open(s, p, 0.0, H, 1) == 0
        i[k] = _abc(s)
        assert s.vo_v == VO  # no midpoint current
    t = H * np.arange(1, n + 1)
    zero = np.all(i == 0.0, axis=1)
    kz = int(np.argmax(zero))
    assert zero[kz] and np.all(zero[kz:])
    assert t[kz] - H < t0 <= t[kz] + 1e-15, (t0, t[kz])
    ana = (i0 + udc / r) * np.exp(-t[:kz] * r / ell) - udc / r
    assert np.max(np.abs(i[:kz, 0] - ana)) <= 1e-9 * (i0 + udc / r)
    assert np.max(np.abs(i[:kz, 2])) <= 1e-9 * i0
    for dt, nonzero in ((t0 - 1e-8, True), (t0 + 1e-8, False)):
        s = _state(ffi, i0, -i0, theta)
        assert lib.ttype_plant_advance_open(s, p, 0.0, dt, math.ceil(dt / H)) == 0
        assert (_abc(s)[0] > 0) == nonzero and (nonzero or np.all(_abc(s) == 0.0))


@pytest.mark.parametrize("motor", [SEED000, IPM], ids=["spmsm", "ipmsm"])
def test_active_short_circuit_ooo_decays_exponentially(stub, motor):
    ffi, lib, _ = stub
    p = _params(ffi, motor)
    i_d0, i_q0 = -4.0, 9.0
    s = ffi.new("ttype_plant_state_t *", {"motor": {"i_d_a": i_d0, "i_q_a": i_q0, "omega_m_rad_s": 0.0,
                                                    "theta_e_rad": 0.9}, "vo_v": VO})
    tau_d, tau_q = motor["ld_h"] / motor["rs_ohm"], motor["lq_h"] / motor["rs_ohm"]
    t, dt = 0.0, 50e-6
    for t_check in (0.1 * tau_d, 0.5 * tau_d, tau_d, 3 * tau_q):
        n = round((t_check - t) / dt)
        for _ in range(n):
            assert lib.ttype_plant_advance(s, p, OOO, 0.0, dt, 50) == 0  # the safe vector OOO
        t += n * dt
        assert s.motor.i_d_a == pytest.approx(i_d0 * math.exp(-t / tau_d), rel=1e-9)
        assert s.motor.i_q_a == pytest.approx(i_q0 * math.exp(-t / tau_q), rel=1e-9)
        assert s.vo_v == VO
    assert t > 2 * tau_q


def test_period_with_the_gates_off(stub):
    """ttype_plant_advance_period_gates: open, the segments' time with the inverter open (V_o held; the
    commanded u_ab recorded); without an open period it is ttype_plant_advance_period bit for bit."""
    ffi, lib, _ = stub
    p = _params(ffi, SEED000)
    states = ffi.new("uint16_t[7]", [22, 25, 26, 25, 22, 13, 13])  # POO PPO PPP PPO POO
    seg = ffi.new("double[7]", [5e-6, 10e-6, 20e-6, 10e-6, 5e-6, 0.0, 0.0])
    uab = ffi.new("double[7]")
    a, b = _state(ffi, 8.0, -3.0, 0.2), _state(ffi, 8.0, -3.0, 0.2)
    assert lib.ttype_plant_advance_period_gates(a, p, OOO, 0, 1, states, seg, 0.0, uab, -1.0, ffi.NULL) == 0
    assert a.vo_v == VO and uab[0] == 0.5 * 220.0 + VO and uab[2] == 0.0  # POO, PPP: as commanded
    assert lib.ttype_plant_advance_open(b, p, 0.0, 50e-6, 50) == 0
    assert np.allclose(_abc(a), _abc(b), rtol=0, atol=1e-9)
    a, b = _state(ffi, 8.0, -3.0, 0.2), _state(ffi, 8.0, -3.0, 0.2)
    assert lib.ttype_plant_advance_period_gates(a, p, OOO, 0, 0, states, seg, 0.0, ffi.NULL, -1.0, ffi.NULL) == 0
    assert lib.ttype_plant_advance_period(b, p, OOO, states, seg, 0.0, ffi.NULL, -1.0, ffi.NULL) == 0
    assert (a.motor.i_d_a, a.motor.i_q_a, a.vo_v) == (b.motor.i_d_a, b.motor.i_q_a, b.vo_v)
    assert lib.ttype_plant_advance_open(b, p, 0.0, 50e-6, 0) == -1
