"""Two-level plant (csrc/twolevel_plant.c) against scipy, and RK4 convergence.

plant-and-metrics.md "Integration": RK4 with sub-steps of at most 1 us, and a
convergence test: halving the sub-step changes the currents by < 1e-6 A.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from tests.fixtures.plantref import assert_fourth_order, assert_matches, integrate, motor_derivs, park
from tests.fixtures.plantref import plant_params as _plant_params

DT = 50e-6
N_PERIODS = 200

SPMSM = dict(rs_ohm=0.2, ld_h=8.5e-3, lq_h=8.5e-3, psi_f_wb=0.175, pole_pairs=4,
             j_kgm2=0.01, b_nms=0.002, udc_v=312.0)
IPMSM = dict(rs_ohm=0.25, ld_h=3.3e-3, lq_h=7.3e-3, psi_f_wb=0.2264, pole_pairs=3,
             j_kgm2=0.01, b_nms=0.0, udc_v=312.0)


def _params(ffi, d, imposed=0):
    return _plant_params(ffi, "sim_params_t", d, imposed)


def _sequence(seed=1):
    return np.random.default_rng(seed).integers(0, 8, N_PERIODS)


def _u_ab(sw, udc):
    """Amplitude-invariant space vector (2/3)Udc(Sa + a Sb + a^2 Sc), independently of the C."""
    a = np.exp(2j * np.pi / 3)
    sa, sb, sc = (sw >> 2) & 1, (sw >> 1) & 1, sw & 1
    u = 2.0 / 3.0 * udc * (sa + a * sb + a * a * sc)
    return u.real, u.imag


def _run_c(ffi, lib, d, seq, x0, load, substeps, imposed=0):
    p = _params(ffi, d, imposed)
    s = ffi.new("pmsm_state_t *", x0)
    out = np.zeros((len(seq), 4))
    for k, sw in enumerate(seq):
        assert lib.twolevel_plant_advance(s, p, int(sw), load, DT, substeps) == 0
        out[k] = (s.i_d_a, s.i_q_a, s.omega_m_rad_s, s.theta_e_rad)
    return out


def _run_scipy(d, seq, x0, load, imposed=0):
    x = np.array(x0, dtype=float)
    out = np.zeros((len(seq), 4))
    for k, sw in enumerate(seq):
        ua, ub = _u_ab(int(sw), d["udc_v"])
        x = integrate(lambda _t, y, ua=ua, ub=ub: motor_derivs(d, y, *park(ua, ub, y[3]), load, imposed),
                      x, DT)
        out[k] = x
    return out


@pytest.mark.parametrize("motor,imposed", [(SPMSM, 0), (IPMSM, 0), (IPMSM, 1)],
                         ids=["spmsm", "ipmsm", "ipmsm-speed-imposed"])
def test_plant_matches_scipy_dop853(stub, motor, imposed):
    ffi, lib = stub
    seq = _sequence()
    x0 = {"i_d_a": -2.0, "i_q_a": 8.0, "omega_m_rad_s": 40.0, "theta_e_rad": 1.0}
    c = _run_c(ffi, lib, motor, seq, x0, 3.0, 50, imposed)
    assert_matches(c, _run_scipy(motor, seq, list(x0.values()), 3.0, imposed))
    # the test is not vacuous: the currents did move by amperes
    assert np.ptp(c[:, 0]) > 1.0 and np.ptp(c[:, 1]) > 1.0
    if imposed:
        assert np.all(c[:, 2] == 40.0)


@pytest.mark.parametrize("motor", [SPMSM, IPMSM], ids=["spmsm", "ipmsm"])
def test_rk4_convergence_halving_substep(stub, motor):
    ffi, lib = stub
    seq = _sequence(7)
    x0 = {"i_d_a": 1.0, "i_q_a": -5.0, "omega_m_rad_s": 60.0, "theta_e_rad": 4.0}
    c50 = _run_c(ffi, lib, motor, seq, x0, 2.0, 50)   # 1 us sub-step (the default)
    c100 = _run_c(ffi, lib, motor, seq, x0, 2.0, 100)  # 0.5 us
    diff = np.max(np.abs(c50[:, :2] - c100[:, :2]))
    assert diff < 1e-6, diff
    # 4th order at coarse sub-steps of 25 us and 12.5 us
    e2 = np.max(np.abs(_run_c(ffi, lib, motor, seq, x0, 2.0, 2)[:, :2] - c100[:, :2]))
    e4 = np.max(np.abs(_run_c(ffi, lib, motor, seq, x0, 2.0, 4)[:, :2] - c100[:, :2]))
    assert_fourth_order(e2, e4, 10.0)


def test_space_vectors_and_helpers(stub):
    ffi, lib = stub
    p = _params(ffi, SPMSM)
    ua, ub = ffi.new("double *"), ffi.new("double *")
    # V1..V6 = 100, 110, 010, 011, 001, 101 at (n-1)*60 deg, |V| = 2 Udc / 3
    for n, sw in enumerate([4, 6, 2, 3, 1, 5], start=1):
        lib.twolevel_plant_voltage_ab(p, sw, ua, ub)
        assert math.hypot(ua[0], ub[0]) == pytest.approx(2 * 312.0 / 3, rel=1e-14)
        assert math.degrees(math.atan2(ub[0], ua[0])) % 360 == pytest.approx((n - 1) * 60.0, abs=1e-9)
    for sw in (0, 7):
        lib.twolevel_plant_voltage_ab(p, sw, ua, ub)
        assert abs(ua[0]) < 1e-12 and abs(ub[0]) < 1e-12

    ia, ib = ffi.new("double *"), ffi.new("double *")
    lib.pmsm_dq_phase_currents(1.5, 7.0, 0.7, ia, ib)
    # Clarke (spec): i_alpha = i_a, i_beta = (i_a + 2 i_b)/sqrt(3); Park back to dq
    ial, ibe = ia[0], (ia[0] + 2 * ib[0]) / math.sqrt(3)
    assert ial * math.cos(0.7) + ibe * math.sin(0.7) == pytest.approx(1.5, abs=1e-12)
    assert -ial * math.sin(0.7) + ibe * math.cos(0.7) == pytest.approx(7.0, abs=1e-12)
    assert lib.pmsm_dq_torque(1.5, 7.0, 8.5e-3, 8.5e-3, 0.175, 4) == pytest.approx(1.5 * 4 * 0.175 * 7.0, rel=1e-14)
    assert lib.pmsm_dq_flux(1.5, 7.0, 8.5e-3, 8.5e-3, 0.175) == pytest.approx(math.hypot(8.5e-3 * 1.5 + 0.175, 8.5e-3 * 7.0))
    for x, w in [(-0.1, 2 * math.pi - 0.1), (7.0, 7.0 - 2 * math.pi), (0.0, 0.0), (-1e-300, 0.0)]:
        y = lib.pmsm_dq_wrap_angle(x)
        assert 0.0 <= y < 2 * math.pi and y == pytest.approx(w, abs=1e-15)
    # bad arguments leave the state untouched
    s = ffi.new("pmsm_state_t *", {"i_d_a": 1.5, "i_q_a": 7.0, "omega_m_rad_s": 0.0, "theta_e_rad": 0.7})
    before = (s.i_d_a, s.i_q_a, s.omega_m_rad_s, s.theta_e_rad)
    assert lib.twolevel_plant_advance(s, p, 8, 0.0, DT, 50) == -1
    assert lib.twolevel_plant_advance(s, p, 1, 0.0, DT, 0) == -1
    assert lib.twolevel_plant_advance(s, p, 1, 0.0, -DT, 50) == -1
    assert (s.i_d_a, s.i_q_a, s.omega_m_rad_s, s.theta_e_rad) == before
