"""Inverter and sensor non-idealities of the T-type plant (``[plant]``).

Dead time (codegen/simulator/csrc/sim_inverter.h) at every leg edge of the
seven-segment period and at the period boundary: the period equals the ideal
plant run over the same segments with, at the start of each segment with an
edge, dead_time_s at the levels the freewheeling diodes give (i_x > 0: the
lower of the two levels, i_x < 0: the higher), computed here from the rule.
Device drops: V_d per conducting device (1 at P/N, 2 at O) against the current.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.model import Plant
from codegen.topologies.ttype.records import SAFE_STATE as OOO
from codegen.topologies.ttype.sim import controller_inputs, params_from_model, run_closed_loop
from codegen.topologies.ttype.virtual import VIRTUAL
from tests.fixtures.simbuild import assert_traces_identical, echo_mode

from .conftest import seed000_model

DT = 50e-6
RS, LS, UDC = 1.75, 1.6e-3, 220.0
POO, PNN = 22, 18


def _index(lv) -> int:
    return 9 * (lv[0] + 1) + 3 * (lv[1] + 1) + (lv[2] + 1)


def _levels(state: int) -> list[int]:
    return [state // 9 - 1, (state // 3) % 3 - 1, state % 3 - 1]


def _params(ffi, **plant):
    p = params_from_model(ffi, seed000_model(0.0, 0.01).replace(plant=Plant(**plant)))
    p.common.speed_imposed = 1
    return p


def _state(ffi, i_d, theta=0.0):
    return ffi.new("ttype_plant_state_t *", {"motor": {"i_d_a": i_d, "i_q_a": 0.0, "omega_m_rad_s": 0.0,
                                                       "theta_e_rad": theta}, "vo_v": 0.0})


def _values(s):
    return np.array([s.motor.i_d_a, s.motor.i_q_a, s.motor.theta_e_rad, s.vo_v])


def _period(ffi, lib, p, x, from_state, states, seg_s):
    st, sg = ffi.new("uint16_t[7]", list(states)), ffi.new("double[7]", list(seg_s))
    assert lib.ttype_plant_advance_period(x, p, from_state, st, sg, 0.0, ffi.NULL, -1.0, ffi.NULL) == 0
    return _values(x)


def _pieces(ffi, lib, p, x, pieces):
    """The ideal plant over (state, duration) pieces, 1 us sub-steps at most."""
    for st, dur in pieces:
        if dur > 0:
            assert lib.ttype_plant_advance(x, p, st, 0.0, dur, max(1, math.ceil(dur / 1e-6 - 1e-9))) == 0
    return _values(x)


def _expected_pieces(from_state, states, seg_s, i_abc, td):
    """(state, duration) of the period under the dead-time rule (the currents keep their sign)."""
    prev = _levels(from_state)
    out = []
    for st, dur in zip(states, seg_s):
        if dur <= 0:
            continue
        lv = _levels(st)
        if lv != prev:
            dead = [b if a == b else (min(a, b) if i > 0 else max(a, b)) for a, b, i in zip(prev, lv, i_abc)]
            out += [(_index(dead), min(td, dur)), (st, dur - min(td, dur))]
        else:
            out.append((st, dur))
        prev = lv
    return out


@pytest.mark.parametrize("i_d", [+8.0, -8.0])
@pytest.mark.parametrize("case", ["mid-period O->P", "boundary P->O"])
def test_dead_time_delays_the_edges_against_the_current(stub, case, i_d):
    """i_a = i_d: a rising edge with i_a > 0 (or a falling one with i_a < 0) comes dead_time late."""
    ffi, lib, _ = stub
    td = 2e-6
    if case == "mid-period O->P":
        from_state, states, seg = OOO, (OOO, POO) + (POO,) * 5, (25e-6, 25e-6) + (0.0,) * 5
        late = i_d > 0
        want = [(OOO, 25e-6 + td), (POO, 25e-6 - td)] if late else [(OOO, 25e-6), (POO, 25e-6)]
    else:
        from_state, states, seg = POO, (OOO,) * 7, (DT,) + (0.0,) * 6
        late = i_d < 0
        want = [(POO, td), (OOO, DT - td)] if late else [(OOO, DT)]
    p = _params(ffi, dead_time_s=td)
    got = _period(ffi, lib, p, _state(ffi, i_d), from_state, states, seg)
    ref = _pieces(ffi, lib, _params(ffi), _state(ffi, i_d), want)
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-9)
    ideal = _pieces(ffi, lib, _params(ffi), _state(ffi, i_d), [(s, d) for s, d in zip(states, seg)])
    if late:  # (Udc/2)*td volt-seconds on leg a: 2/3*110 V*2 us/1.6 mH = 92 mA in i_alpha, against i_a
        assert np.sign(got[0] - ideal[0]) == -np.sign(i_d) and abs(got[0] - ideal[0]) > 0.05
    else:
        assert abs(got[0] - ideal[0]) < 1e-9


@pytest.mark.parametrize("vector", [27, 33, 40, 50, 62])
def test_dead_time_at_every_edge_of_a_seven_segment_period(stub, vector):
    ffi, lib, _ = stub
    td = 1.5e-6
    vv = VIRTUAL[vector - 27]
    states = tuple(int(s) for s in vv.sequence)
    t_n = 20e-6  # T_N/2 first and last, the rest spread evenly as the segments of a virtual vector
    inner = (DT - t_n) / 5
    seg = (t_n / 2,) + (inner,) * 5 + (t_n / 2,)
    theta = 0.3  # i_a = 9.6, i_b = -2.2, i_c = -7.3 A: no sign change within the period
    i_abc = [10 * math.cos(theta), 10 * math.cos(theta - 2 * math.pi / 3), 10 * math.cos(theta + 2 * math.pi / 3)]
    from_state = _index([-1, 1, 0])  # NPO before the period: an edge at the boundary too
    p = _params(ffi, dead_time_s=td)
    got = _period(ffi, lib, p, _state(ffi, 10.0, theta), from_state, states, seg)
    pieces = _expected_pieces(from_state, states, seg, i_abc, td)
    assert len(pieces) > 7  # dead-time pieces were inserted
    ref = _pieces(ffi, lib, _params(ffi), _state(ffi, 10.0, theta), pieces)
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-9)
    ideal = _pieces(ffi, lib, _params(ffi), _state(ffi, 10.0, theta), list(zip(states, seg)))
    assert np.max(np.abs(got[:2] - ideal[:2])) > 1e-3


@pytest.mark.parametrize("state,n_dev", [(OOO, 2), (PNN, 1)])
@pytest.mark.parametrize("i_d", [+5.0, -5.0])
def test_device_drops_oppose_the_current(stub, state, n_dev, i_d):
    """i_a = i_d, i_b = i_c = -i_d/2: du_alpha = -(4/3) n V_d sign(i_a) (n devices: 2 at O, 1 at P/N)."""
    ffi, lib, _ = stub
    vd = 1.0
    states, seg = (state,) * 7, (DT,) + (0.0,) * 6
    ideal = _period(ffi, lib, _params(ffi), _state(ffi, i_d), state, states, seg)
    drop = _period(ffi, lib, _params(ffi, device_drop_v=vd), _state(ffi, i_d), state, states, seg)
    du = -4 / 3 * n_dev * vd * np.sign(i_d)
    assert drop[0] - ideal[0] == pytest.approx(du / RS * (1 - math.exp(-RS * DT / LS)), rel=1e-6)


def test_nonideal_closed_loop_chunked_and_inputs(stub):
    """Every non-ideality at once: a chunked run equals one long run bit for bit, and
    controller_inputs are what the step saw."""
    ffi, lib, mode = stub
    mode(63)
    plant = Plant(actuation_delay_periods=1, dead_time_s=1e-6, device_drop_v=1.0, current_gain_error=0.02,
                  current_offset_a=0.05, adc_bits=12, noise_a=0.05, noise_seed=3, encoder_bits=12,
                  measurement_delay_s=20e-6, udc_v=230.0, c_f=800e-6, rs_ohm=2.0)
    model = seed000_model(1800.0, 0.05, imposed=False, load_steps=((0.0, 0.6),)).replace(plant=plant)
    for echo, fields in ((2, ("ia_a", "ib_a")), (3, ("theta_e_rad", "uc1_v")), (4, ("uc2_v", "t_n_prev_s"))):
        with echo_mode(lib.stub_ttype_set_echo, echo):
            a = run_closed_loop(ffi, lib, model)
            b = run_closed_loop(ffi, lib, model, chunk=1)
        assert_traces_identical(a, b)
        rec = controller_inputs(a, model)
        assert rec[fields[0]].tobytes() == a.te_est_nm.tobytes()
        assert rec[fields[1]].tobytes() == a.psi_est_wb.tobytes()
    assert a.udc_v == 230.0 and np.any(a.vo_meas_v != a.vo_v)


def test_measurement_delay_of_one_period_gives_the_previous_samples(stub):
    ffi, lib, mode = stub
    mode(63)
    model = seed000_model(1800.0, 0.03).replace(plant=Plant(measurement_delay_s=DT))
    with echo_mode(lib.stub_ttype_set_echo, 3):  # psi_est_wb = uc1 as the step saw it
        tr = run_closed_loop(ffi, lib, model)
    np.testing.assert_array_equal(tr.vo_meas_v[1:], tr.vo_v[:-1])
    np.testing.assert_array_equal(tr.ia_meas_a[1:], tr.ia_a[:-1])
    np.testing.assert_array_equal(tr.psi_est_wb, (0.5 * UDC + tr.vo_meas_v).astype(np.float32))
