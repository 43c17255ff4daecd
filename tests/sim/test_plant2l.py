"""Plant (firmware/runtime/plant2l.c) against scipy, and RK4 convergence.

plant-and-metrics.md "Integration": RK4 with sub-steps of at most 1 us, and a
convergence test: halving the sub-step changes the currents by < 1e-6 A.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

DT = 50e-6
N_PERIODS = 200

SPMSM = dict(rs_ohm=0.2, ld_h=8.5e-3, lq_h=8.5e-3, psi_f_wb=0.175, pole_pairs=4,
             j_kgm2=0.01, b_nms=0.002, udc_v=312.0)
IPMSM = dict(rs_ohm=0.25, ld_h=3.3e-3, lq_h=7.3e-3, psi_f_wb=0.2264, pole_pairs=3,
             j_kgm2=0.01, b_nms=0.0, udc_v=312.0)


def _params(ffi, d):
    p = ffi.new("plant2l_params_t *")
    for k, v in d.items():
        setattr(p, k, v)
    return p


def _sequence(seed=1):
    return np.random.default_rng(seed).integers(0, 8, N_PERIODS)


def _u_ab(sw, udc):
    """Amplitude-invariant space vector (2/3)Udc(Sa + a Sb + a^2 Sc), independently of the C."""
    a = np.exp(2j * np.pi / 3)
    sa, sb, sc = (sw >> 2) & 1, (sw >> 1) & 1, sw & 1
    u = 2.0 / 3.0 * udc * (sa + a * sb + a * a * sc)
    return u.real, u.imag


def _rhs(d, ua, ub, load, imposed):
    rs, ld, lq, pf, p = d["rs_ohm"], d["ld_h"], d["lq_h"], d["psi_f_wb"], d["pole_pairs"]

    def f(_t, x):
        i_d, i_q, wm, th = x
        ud = ua * math.cos(th) + ub * math.sin(th)
        uq = -ua * math.sin(th) + ub * math.cos(th)
        we = p * wm
        did = (ud - rs * i_d + we * lq * i_q) / ld
        diq = (uq - rs * i_q - we * ld * i_d - we * pf) / lq
        te = 1.5 * p * ((ld * i_d + pf) * i_q - lq * i_q * i_d)
        dwm = 0.0 if imposed else (te - load - d["b_nms"] * wm) / d["j_kgm2"]
        return [did, diq, dwm, we]

    return f


def _run_c(ffi, lib, d, seq, x0, load, substeps, imposed=0):
    p = _params(ffi, d)
    s = ffi.new("plant2l_state_t *", x0)
    out = np.zeros((len(seq), 4))
    for k, sw in enumerate(seq):
        assert lib.plant2l_advance(s, p, int(sw), load, DT, substeps, imposed) == 0
        out[k] = (s.i_d_a, s.i_q_a, s.omega_m_rad_s, s.theta_e_rad)
    return out


def _run_scipy(d, seq, x0, load, imposed=0):
    x = np.array(x0, dtype=float)
    out = np.zeros((len(seq), 4))
    for k, sw in enumerate(seq):
        ua, ub = _u_ab(int(sw), d["udc_v"])
        sol = solve_ivp(_rhs(d, ua, ub, load, imposed), (0.0, DT), x, method="DOP853",
                        rtol=1e-10, atol=1e-12)
        assert sol.success
        x = sol.y[:, -1]
        out[k] = x
    return out


def _phase(x):
    """(i_a, i_b) from rows (i_d, i_q, w, theta): inverse Park + inverse Clarke."""
    i_d, i_q, th = x[:, 0], x[:, 1], x[:, 3]
    ial = i_d * np.cos(th) - i_q * np.sin(th)
    ibe = i_d * np.sin(th) + i_q * np.cos(th)
    return ial, -0.5 * ial + math.sqrt(3) / 2 * ibe


@pytest.mark.parametrize("motor,imposed", [(SPMSM, 0), (IPMSM, 0), (IPMSM, 1)],
                         ids=["spmsm", "ipmsm", "ipmsm-speed-imposed"])
def test_plant_matches_scipy_dop853(stub_lib, motor, imposed):
    ffi, lib = stub_lib
    seq = _sequence()
    x0 = {"i_d_a": -2.0, "i_q_a": 8.0, "omega_m_rad_s": 40.0, "theta_e_rad": 1.0}
    load = 3.0
    c = _run_c(ffi, lib, motor, seq, x0, load, 50, imposed)
    ref = _run_scipy(motor, seq, list(x0.values()), load, imposed)
    # dq currents and speed
    assert np.max(np.abs(c[:, :2] - ref[:, :2])) < 1e-6
    assert np.max(np.abs(c[:, 2] - ref[:, 2])) < 1e-6
    # angle: C wraps to [0, 2pi) after every period, scipy does not
    dth = np.angle(np.exp(1j * (c[:, 3] - ref[:, 3])))
    assert np.max(np.abs(dth)) < 1e-9
    assert np.all((c[:, 3] >= 0) & (c[:, 3] < 2 * np.pi))
    # phase currents
    ia_c, ib_c = _phase(c)
    ia_r, ib_r = _phase(ref)
    assert max(np.max(np.abs(ia_c - ia_r)), np.max(np.abs(ib_c - ib_r))) < 1e-6
    # the test is not vacuous: the currents did move by amperes
    assert np.ptp(c[:, 0]) > 1.0 and np.ptp(c[:, 1]) > 1.0
    if imposed:
        assert np.all(c[:, 2] == 40.0)


@pytest.mark.parametrize("motor", [SPMSM, IPMSM], ids=["spmsm", "ipmsm"])
def test_rk4_convergence_halving_substep(stub_lib, motor):
    ffi, lib = stub_lib
    seq = _sequence(7)
    x0 = {"i_d_a": 1.0, "i_q_a": -5.0, "omega_m_rad_s": 60.0, "theta_e_rad": 4.0}
    c50 = _run_c(ffi, lib, motor, seq, x0, 2.0, 50)   # 1 us sub-step (the default)
    c100 = _run_c(ffi, lib, motor, seq, x0, 2.0, 100)  # 0.5 us
    diff = np.max(np.abs(c50[:, :2] - c100[:, :2]))
    assert diff < 1e-6, diff
    # and the method is 4th order: with coarse sub-steps (25 us, 12.5 us, where
    # rounding does not hide it) halving the sub-step cuts the error ~16x
    e2 = np.max(np.abs(_run_c(ffi, lib, motor, seq, x0, 2.0, 2)[:, :2] - c100[:, :2]))
    e4 = np.max(np.abs(_run_c(ffi, lib, motor, seq, x0, 2.0, 4)[:, :2] - c100[:, :2]))
    assert 10.0 < e2 / e4 < 24.0, (e2, e4)


def test_space_vectors_and_helpers(stub_lib):
    ffi, lib = stub_lib
    p = _params(ffi, SPMSM)
    ua, ub = ffi.new("double *"), ffi.new("double *")
    # V1..V6 = 100, 110, 010, 011, 001, 101 at (n-1)*60 deg, |V| = 2 Udc / 3
    for n, sw in enumerate([4, 6, 2, 3, 1, 5], start=1):
        lib.plant2l_voltage_ab(p, sw, ua, ub)
        assert math.hypot(ua[0], ub[0]) == pytest.approx(2 * 312.0 / 3, rel=1e-14)
        assert math.degrees(math.atan2(ub[0], ua[0])) % 360 == pytest.approx((n - 1) * 60.0, abs=1e-9)
    for sw in (0, 7):
        lib.plant2l_voltage_ab(p, sw, ua, ub)
        assert abs(ua[0]) < 1e-12 and abs(ub[0]) < 1e-12

    s = ffi.new("plant2l_state_t *", {"i_d_a": 1.5, "i_q_a": 7.0, "omega_m_rad_s": 0.0,
                                      "theta_e_rad": 0.7})
    ia, ib = ffi.new("double *"), ffi.new("double *")
    lib.plant2l_phase_currents(s, ia, ib)
    # Clarke (spec): i_alpha = i_a, i_beta = (i_a + 2 i_b)/sqrt(3); Park back to dq
    ial, ibe = ia[0], (ia[0] + 2 * ib[0]) / math.sqrt(3)
    assert ial * math.cos(0.7) + ibe * math.sin(0.7) == pytest.approx(1.5, abs=1e-12)
    assert -ial * math.sin(0.7) + ibe * math.cos(0.7) == pytest.approx(7.0, abs=1e-12)
    assert lib.plant2l_torque(s, p) == pytest.approx(1.5 * 4 * 0.175 * 7.0, rel=1e-14)
    assert lib.plant2l_flux(s, p) == pytest.approx(math.hypot(8.5e-3 * 1.5 + 0.175, 8.5e-3 * 7.0))
    for x, w in [(-0.1, 2 * math.pi - 0.1), (7.0, 7.0 - 2 * math.pi), (0.0, 0.0), (-1e-300, 0.0)]:
        y = lib.plant2l_wrap_angle(x)
        assert 0.0 <= y < 2 * math.pi and y == pytest.approx(w, abs=1e-15)
    # bad arguments leave the state untouched
    before = (s.i_d_a, s.i_q_a, s.omega_m_rad_s, s.theta_e_rad)
    assert lib.plant2l_advance(s, p, 8, 0.0, DT, 50, 0) == -1
    assert lib.plant2l_advance(s, p, 1, 0.0, DT, 0, 0) == -1
    assert lib.plant2l_advance(s, p, 1, 0.0, -DT, 50, 0) == -1
    assert (s.i_d_a, s.i_q_a, s.omega_m_rad_s, s.theta_e_rad) == before
