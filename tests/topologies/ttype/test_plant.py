"""T-type plant (csrc/ttype_plant.c) against scipy, RK4 convergence, V_o sign convention.

plant-and-metrics.md "Integration": RK4 with sub-steps of at most 1 us over
each constant segment, halving the sub-step changes the currents by < 1e-6 A.
The reference model below is written independently of the C, straight from
the spec: u_xo = S_x*u_c1 (S=+1), 0, -u_c2 (S=-1); u_xn = u_xo - mean;
i_o = sum (1 - |S_x|) i_x; dV_o/dt = i_o/(2C); u_c1 + u_c2 = Udc.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from tests.fixtures.plantref import (
    assert_fourth_order,
    assert_matches,
    integrate,
    motor_derivs,
    park,
    phase_currents,
)
from tests.fixtures.plantref import plant_params as _plant_params

TS = 50e-6
N_PERIODS = 120

SEED000 = dict(rs_ohm=1.75, ld_h=1.6e-3, lq_h=1.6e-3, psi_f_wb=0.045, pole_pairs=5,
               j_kgm2=5e-4, b_nms=1e-4, udc_v=220.0, c_f=1000e-6)
IPM = dict(SEED000, ld_h=1.2e-3, lq_h=2.4e-3, c_f=470e-6)

POO, ONN, OOO = 22, 9, 13


def _params(ffi, d, substep_max=1e-6, imposed=0):
    p = _plant_params(ffi, "ttype_sim_params_t", d, imposed)
    p.substep_max_s = substep_max
    return p


def _levels(st):
    return (st // 9 - 1, (st // 3) % 3 - 1, st % 3 - 1)


def _segments(seed=3, n=N_PERIODS):
    """Random states (0..26) and durations per period; some segments empty; sum = Ts."""
    rng = np.random.default_rng(seed)
    states = rng.integers(0, 27, (n, 7)).astype(np.uint16)
    w = rng.dirichlet(np.ones(7), n)
    w[rng.random((n, 7)) < 0.2] = 0.0
    w[:, 0] += 1e-3
    seg = w / w.sum(axis=1, keepdims=True) * TS
    return states, seg


def _rhs(d, st, load, imposed):
    lv = _levels(int(st))

    def f(_t, x):
        th, vo = x[3], x[4]
        uc1, uc2 = d["udc_v"] / 2 + vo, d["udc_v"] / 2 - vo
        uxo = [uc1 if s == 1 else (-uc2 if s == -1 else 0.0) for s in lv]
        cm = sum(uxo) / 3
        ua, ub, uc = (u - cm for u in uxo)
        ual = 2 / 3 * (ua - 0.5 * ub - 0.5 * uc)
        ube = (ub - uc) / math.sqrt(3)
        c, s = math.cos(th), math.sin(th)
        ial, ibe = x[0] * c - x[1] * s, x[0] * s + x[1] * c
        ix = (ial, -ial / 2 + math.sqrt(3) / 2 * ibe, -ial / 2 - math.sqrt(3) / 2 * ibe)
        io = sum((1 - abs(sx)) * i for sx, i in zip(lv, ix))
        return motor_derivs(d, x, *park(ual, ube, th), load, imposed) + [io / (2 * d["c_f"])]

    return f


def _run_c(ffi, lib, d, states, seg, x0, load, substep_max=1e-6, imposed=0):
    p = _params(ffi, d, substep_max, imposed)
    s = _state(ffi, **x0)
    out = np.zeros((len(states), 5))
    for k in range(len(states)):
        st = ffi.new("uint16_t[7]", states[k].tolist())
        sg = ffi.new("double[7]", seg[k].tolist())
        assert lib.ttype_plant_advance_segments(s, p, st, sg, load, ffi.NULL) == 0
        out[k] = (s.motor.i_d_a, s.motor.i_q_a, s.motor.omega_m_rad_s, s.motor.theta_e_rad, s.vo_v)
    return out


def _run_scipy(d, states, seg, x0, load, imposed=0):
    x = np.array([x0["i_d"], x0["i_q"], x0["w"], x0["th"], x0["vo"]], dtype=float)
    out = np.zeros((len(states), 5))
    for k in range(len(states)):
        for st, dur in zip(states[k], seg[k]):
            if dur > 0:
                x = integrate(_rhs(d, st, load, imposed), x, dur)
        out[k] = x
    return out


def _state(ffi, i_d, i_q, th=0.0, vo=0.0, w=0.0):
    return ffi.new("ttype_plant_state_t *", {"motor": {"i_d_a": i_d, "i_q_a": i_q, "omega_m_rad_s": w,
                                                       "theta_e_rad": th}, "vo_v": vo})


def _values(s):
    return (s.motor.i_d_a, s.motor.i_q_a, s.motor.omega_m_rad_s, s.motor.theta_e_rad, s.vo_v)


X0 = {"i_d": -1.0, "i_q": 3.0, "w": 150.0, "th": 1.0, "vo": 0.5}


@pytest.mark.parametrize("motor,imposed", [(SEED000, 0), (IPM, 0), (SEED000, 1)],
                         ids=["spmsm", "ipmsm", "spmsm-speed-imposed"])
def test_plant_matches_scipy_dop853(stub, motor, imposed):
    ffi, lib, _ = stub
    states, seg = _segments()
    c = _run_c(ffi, lib, motor, states, seg, X0, 0.8, imposed=imposed)
    ref = _run_scipy(motor, states, seg, X0, 0.8, imposed)
    assert_matches(c, ref, extra_cols=1)  # V_o too
    ia_c, _ = phase_currents(c)
    # not vacuous: currents moved by amperes, V_o by volts
    assert np.ptp(ia_c) > 2.0 and np.ptp(c[:, 4]) > 0.2
    if imposed:
        assert np.all(c[:, 2] == 150.0)


@pytest.mark.parametrize("motor", [SEED000, IPM], ids=["spmsm", "ipmsm"])
def test_rk4_convergence_halving_substep(stub, motor):
    ffi, lib, _ = stub
    states, seg = _segments(11)
    c1 = _run_c(ffi, lib, motor, states, seg, X0, 0.5, 1e-6)
    c05 = _run_c(ffi, lib, motor, states, seg, X0, 0.5, 0.5e-6)
    ia1, ib1 = phase_currents(c1)
    ia05, ib05 = phase_currents(c05)
    assert max(np.max(np.abs(ia1 - ia05)), np.max(np.abs(ib1 - ib05))) < 1e-6
    assert np.max(np.abs(c1[:, 4] - c05[:, 4])) < 1e-6
    # 4th order: coarse sub-steps (where rounding does not hide it) cut the error ~16x per halving
    e8 = np.max(np.abs(_run_c(ffi, lib, motor, states, seg, X0, 0.5, 8e-6)[:, :2] - c05[:, :2]))
    e4 = np.max(np.abs(_run_c(ffi, lib, motor, states, seg, X0, 0.5, 4e-6)[:, :2] - c05[:, :2]))
    assert_fourth_order(e8, e4, 8.0)


def test_vo_sign_convention(stub):
    """P-type small POO with i_a > 0: i_o = i_b + i_c = -i_a < 0, so V_o falls
    (dV_o/dt = i_o/(2C)); its N-type partner ONN (i_o = i_a) raises V_o."""
    ffi, lib, _ = stub
    p = _params(ffi, SEED000, imposed=1)
    dt = 2e-6
    for st, sign in ((POO, -1.0), (ONN, +1.0), (OOO, 0.0)):
        s = _state(ffi, 5.0, 0.0)  # theta = 0: i_a = i_d = 5 A, i_b = i_c = -2.5 A
        ia, ib = ffi.new("double *"), ffi.new("double *")
        lib.pmsm_dq_phase_currents(s.motor.i_d_a, s.motor.i_q_a, s.motor.theta_e_rad, ia, ib)
        assert ia[0] == pytest.approx(5.0) and ib[0] == pytest.approx(-2.5)
        assert lib.ttype_plant_io(s, st) == pytest.approx(sign * 5.0, abs=1e-12)
        assert lib.ttype_plant_advance(s, p, st, 0.0, dt, 2) == 0
        expected = sign * 5.0 * dt / (2 * SEED000["c_f"])  # ~ +-5 mV
        if sign == 0.0:
            assert s.vo_v == 0.0
        else:
            assert s.vo_v == pytest.approx(expected, rel=2e-2)
            assert math.copysign(1.0, s.vo_v) == sign


def test_voltages_and_helpers(stub):
    ffi, lib, _ = stub
    p = _params(ffi, SEED000)
    udc = SEED000["udc_v"]
    lv = ffi.new("int[3]")
    for st in range(27):
        assert lib.ttype_plant_levels(st, lv) == 0 and tuple(lv) == _levels(st)
    assert lib.ttype_plant_levels(27, lv) == -1
    ua, ub = ffi.new("double *"), ffi.new("double *")
    # magnitudes at V_o = 0: small Udc/3, medium Udc/sqrt3, large 2Udc/3 (spec)
    for st, mag in ((POO, udc / 3), (ONN, udc / 3), (9 * 2 + 3 * 1 + 0, udc / math.sqrt(3)),
                    (9 * 2 + 0 + 0, 2 * udc / 3), (OOO, 0.0), (0, 0.0), (26, 0.0)):
        lib.ttype_plant_voltage_ab(p, st, 0.0, ua, ub)
        assert math.hypot(ua[0], ub[0]) == pytest.approx(mag, abs=1e-12)
    # with V_o: u_c1 = Udc/2 + V_o -> POO = (2/3) u_c1, ONN = (2/3) u_c2
    lib.ttype_plant_voltage_ab(p, POO, 3.0, ua, ub)
    assert ua[0] == pytest.approx(2 / 3 * (udc / 2 + 3.0)) and ub[0] == pytest.approx(0.0, abs=1e-12)
    lib.ttype_plant_voltage_ab(p, ONN, 3.0, ua, ub)
    assert ua[0] == pytest.approx(2 / 3 * (udc / 2 - 3.0))
    # line voltage u_ab = u_ao - u_bo
    assert lib.ttype_plant_uab(p, 9 * 2 + 0 + 0, 3.0) == pytest.approx(udc)      # PNN
    assert lib.ttype_plant_uab(p, 9 * 0 + 3 * 2 + 0, 3.0) == pytest.approx(-udc)  # NPN
    assert lib.ttype_plant_uab(p, POO, 3.0) == pytest.approx(udc / 2 + 3.0)      # u_c1
    assert lib.ttype_plant_uab(p, 9 * 1 + 0 + 1, 3.0) == pytest.approx(udc / 2 - 3.0)  # ONO: u_c2
    assert lib.ttype_plant_uab(p, OOO, 3.0) == 0.0


def test_segments_skip_empty_and_reject_bad_input(stub):
    ffi, lib, _ = stub
    p = _params(ffi, SEED000)
    a = _state(ffi, 1.0, 2.0, 0.3, 0.1, 100.0)
    b = _state(ffi, 1.0, 2.0, 0.3, 0.1, 100.0)
    st = ffi.new("uint16_t[7]", [POO, 5, 5, 5, 5, 5, 5])
    sg = ffi.new("double[7]", [TS, 0, 0, 0, 0, 0, 0])
    uab = ffi.new("double[7]")
    assert lib.ttype_plant_advance_segments(a, p, st, sg, 0.2, uab) == 0
    assert lib.ttype_plant_advance(b, p, POO, 0.2, TS, 50) == 0
    assert _values(a) == _values(b)
    assert uab[0] == pytest.approx(110.0 + 0.1)
    before = _values(a)
    for bad_st, bad_sg, sub in (([27] * 7, [TS] + [0] * 6, 1e-6), ([13] * 7, [-1e-6] + [TS] * 6, 1e-6),
                                ([13] * 7, [float("nan")] * 7, 1e-6), ([13] * 7, [TS] + [0] * 6, 0.0)):
        assert lib.ttype_plant_advance_segments(a, _params(ffi, SEED000, sub), ffi.new("uint16_t[7]", bad_st),
                                                ffi.new("double[7]", bad_sg), 0.0, ffi.NULL) == -1
    assert _values(a) == before
    assert lib.ttype_plant_advance(a, p, 27, 0.0, TS, 50) == -1
    assert lib.ttype_plant_advance(a, p, 13, 0.0, TS, 0) == -1
