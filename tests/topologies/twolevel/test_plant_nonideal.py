"""Inverter and sensor non-idealities of the two-level plant (``[plant]``), each against its model.

Inverter (csrc/twolevel_plant.c, codegen/simulator/csrc/sim_inverter.h), at
standstill (speed imposed at 0, theta_e = 0: the d axis is the alpha axis and
the a phase, L di_d/dt = u_alpha - Rs i_d), so that the effect of a voltage
error is exact: a pulse of du volts for t1 seconds ending t2 seconds before the
period's end changes i_d there by du/Rs (1 - exp(-Rs t1/L)) exp(-Rs t2/L).
Sensors (codegen/simulator/csrc/sim_sensors.c) in closed loop with the stub
controller: the trace records what the controller saw (``*_meas_*``) beside
the plant's values.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from codegen.model import Plant
from codegen.topologies.twolevel.sim import controller_inputs, params_from_model, run_closed_loop
from tests.fixtures.simbuild import assert_traces_identical, echo_mode

DT = 50e-6
RS, LS, UDC, P = 0.2, 8.5e-3, 312.0, 4  # seed001_spmsm


def _pulse(du_v: float, t1_s: float, t2_s: float) -> float:
    """Change of i_d at the period's end from du_v during t1_s, t2_s before the end (R-L response)."""
    return du_v / RS * (1.0 - math.exp(-RS * t1_s / LS)) * math.exp(-RS * t2_s / LS)


def _period(ffi, lib, model, i_d: float, from_sw: int, sw: int) -> float:
    """i_d after one period from i_d (i_q = 0, theta_e = 0, standstill) with from_sw held before it."""
    p = params_from_model(ffi, model)
    p.common.speed_imposed = 1
    s = ffi.new("pmsm_state_t *", (i_d, 0.0, 0.0, 0.0))
    assert lib.twolevel_plant_advance_period(s, ffi.addressof(p.common), from_sw, sw, 0.0, p.substeps,
                                             -1.0, ffi.NULL) == 0
    return s.i_d_a


def _short(model, duration_s=0.2, **plant):
    return model.replace(scenario=dataclasses.replace(model.scenario, duration_s=duration_s), plant=Plant(**plant))


# ------------------------------------------------------------------ dead time

@pytest.mark.parametrize("from_sw,sw,i_d,leg_error", [
    (0b000, 0b100, +5.0, (-1, 0, 0)),  # a rises, i_a > 0: the leg stays low for the dead time
    (0b000, 0b100, -5.0, (0, 0, 0)),   # a rises, i_a < 0: the upper diode takes it at once
    (0b100, 0b000, -5.0, (+1, 0, 0)),  # a falls, i_a < 0: the leg stays high
    (0b100, 0b000, +5.0, (0, 0, 0)),   # a falls, i_a > 0: the lower diode takes it at once
    (0b000, 0b011, +5.0, (0, 0, 0)),   # b, c rise with i_b, i_c < 0: no error
    (0b011, 0b000, +5.0, (0, +1, +1)), # b, c fall with i_b, i_c < 0: both stay high
    (0b011, 0b100, +5.0, (-1, +1, +1)),  # all three legs switch
])
def test_dead_time_error_follows_the_current_sign(stub, spmsm_model, from_sw, sw, i_d, leg_error):
    """Each leg's voltage error during the dead time is 0 or -sign(i_x)*Udc; i_a = i_d, i_b = i_c = -i_d/2."""
    ffi, lib = stub
    td = 2e-6
    i_abc = np.array([i_d, -i_d / 2, -i_d / 2])
    err = np.array(leg_error, dtype=float)
    assert np.all((err == 0) | (np.sign(err) == -np.sign(i_abc)))  # the table states the model
    ideal = _period(ffi, lib, spmsm_model, i_d, from_sw, sw)
    dead = _period(ffi, lib, spmsm_model.replace(plant=Plant(dead_time_s=td)), i_d, from_sw, sw)
    du_alpha = 2 / 3 * UDC * (err[0] - (err[1] + err[2]) / 2)  # Clarke of the legs' error
    assert dead - ideal == pytest.approx(_pulse(du_alpha, td, DT - td), rel=1e-6, abs=1e-10)
    if err.any():
        assert abs(dead - ideal) > 0.04  # 2/3*312 V*2 us/8.5 mH = 49 mA


def test_no_edge_no_dead_time(stub, spmsm_model):
    ffi, lib = stub
    for sw in range(8):
        ideal = _period(ffi, lib, spmsm_model, 5.0, sw, sw)
        assert _period(ffi, lib, spmsm_model.replace(plant=Plant(dead_time_s=2e-6)), 5.0, sw, sw) == ideal


def test_dead_time_off_is_the_ideal_plant_bit_for_bit(stub, spmsm_model):
    """Without dead time, drops or a snapshot the period is twolevel_plant_advance, bit for bit."""
    ffi, lib = stub
    p = params_from_model(ffi, spmsm_model)
    rng = np.random.default_rng(3)
    a = ffi.new("pmsm_state_t *", (3.0, -4.0, 40.0, 1.0))
    b = ffi.new("pmsm_state_t *", (3.0, -4.0, 40.0, 1.0))
    prev = 0
    for sw in rng.integers(0, 8, 50).tolist():
        assert lib.twolevel_plant_advance(a, ffi.addressof(p.common), sw, 1.0, DT, p.substeps) == 0
        assert lib.twolevel_plant_advance_period(b, ffi.addressof(p.common), prev, sw, 1.0, p.substeps, -1.0,
                                                 ffi.NULL) == 0
        prev = sw
        assert ffi.buffer(a)[:] == ffi.buffer(b)[:]


# ------------------------------------------------------------------ device drops

@pytest.mark.parametrize("sw", [0b000, 0b111, 0b100])
@pytest.mark.parametrize("i_d", [+5.0, -5.0])
def test_device_drops_oppose_the_current(stub, spmsm_model, sw, i_d):
    """i_a = i_d, i_b = i_c = -i_d/2: u_x - V_d sign(i_x) gives du_alpha = -(4/3) V_d sign(i_a), whatever sw."""
    ffi, lib = stub
    vd = 1.5
    ideal = _period(ffi, lib, spmsm_model, i_d, sw, sw)
    drop = _period(ffi, lib, spmsm_model.replace(plant=Plant(device_drop_v=vd)), i_d, sw, sw)
    assert drop - ideal == pytest.approx(_pulse(-4 / 3 * vd * np.sign(i_d), DT, 0.0), rel=1e-6)


def test_nonideal_inverter_in_closed_loop_still_tracks(stub, spmsm_model):
    """Closed loop with dead time and drops: the plant differs from the ideal one, the speed loop still holds it."""
    ffi, lib = stub
    lib.stub_twolevel_set_echo(0)
    ideal = run_closed_loop(ffi, lib, _short(spmsm_model))
    tr = run_closed_loop(ffi, lib, _short(spmsm_model, dead_time_s=2e-6, device_drop_v=2.0))
    assert not np.array_equal(tr.ia_a, ideal.ia_a)
    assert abs(np.mean(tr.speed_rpm[-1000:]) - np.mean(ideal.speed_rpm[-1000:])) < 5.0


# ------------------------------------------------------------------ current sensors

def test_gain_and_offset_scale_and_shift_the_samples(stub, spmsm_model):
    ffi, lib = stub
    model = _short(spmsm_model, 0.1, current_gain_error=0.05, current_offset_a=0.4)
    with echo_mode(lib.stub_twolevel_set_echo, 2):  # te_est = i_a, psi_est = i_b as the step saw them
        tr = run_closed_loop(ffi, lib, model)
    np.testing.assert_array_equal(tr.ia_meas_a, 1.05 * tr.ia_a + 0.4 + 0.0)
    np.testing.assert_array_equal(tr.ib_meas_a, 1.05 * tr.ib_a + 0.4 + 0.0)
    np.testing.assert_array_equal(tr.te_est_nm, tr.ia_meas_a.astype(np.float32))
    rec = controller_inputs(tr, model)
    assert rec["ia_a"].tobytes() == tr.te_est_nm.tobytes() and rec["ib_a"].tobytes() == tr.psi_est_wb.tobytes()
    np.testing.assert_array_equal(tr.theta_e_meas_rad, tr.theta_e_rad)  # the angle is untouched


@pytest.mark.parametrize("bits", [8, 12])
def test_adc_quantises_the_samples_onto_its_grid(stub, spmsm_model, bits):
    ffi, lib = stub
    lib.stub_twolevel_set_echo(0)
    fs = 60.0  # i_trip_a: the default full scale
    tr = run_closed_loop(ffi, lib, _short(spmsm_model, 0.1, adc_bits=bits))
    q = 2 * fs / 2**bits
    for meas, true in ((tr.ia_meas_a, tr.ia_a), (tr.ib_meas_a, tr.ib_a)):
        codes = meas / q
        np.testing.assert_array_equal(codes, np.round(codes))  # on the grid
        assert np.all(np.abs(meas - true) <= q / 2 * (1 + 1e-12))  # nearest code
        assert len(np.unique(meas)) > 10
    assert np.max(np.abs(tr.ia_meas_a - tr.ia_a)) > q / 4  # the quantisation is visible


def test_adc_clips_at_full_scale(stub, spmsm_model):
    ffi, lib = stub
    lib.stub_twolevel_set_echo(0)
    tr = run_closed_loop(ffi, lib, _short(spmsm_model, 0.1, adc_bits=10, adc_full_scale_a=5.0))
    q = 10.0 / 1024
    assert tr.ia_meas_a.max() == pytest.approx(5.0 - q) and tr.ia_meas_a.min() == -5.0
    assert np.max(np.abs(tr.ia_a)) > 6.0


def test_noise_is_reproducible_from_its_seed(stub, spmsm_model):
    ffi, lib = stub
    lib.stub_twolevel_set_echo(0)
    sigma = 0.5
    a = run_closed_loop(ffi, lib, _short(spmsm_model, noise_a=sigma, noise_seed=7))
    b = run_closed_loop(ffi, lib, _short(spmsm_model, noise_a=sigma, noise_seed=7), chunk=999)
    c = run_closed_loop(ffi, lib, _short(spmsm_model, noise_a=sigma, noise_seed=8))
    assert_traces_identical(a, b)  # the same seed: the same run, chunked or not
    assert not np.array_equal(a.ia_meas_a, c.ia_meas_a)
    for tr in (a, c):
        ea, eb = tr.ia_meas_a - tr.ia_a, tr.ib_meas_a - tr.ib_a
        n = tr.n
        for e in (ea, eb):  # zero-mean Gaussian of the configured std
            assert abs(np.mean(e)) < 4 * sigma / math.sqrt(n)
            assert np.std(e) == pytest.approx(sigma, rel=4 / math.sqrt(2 * n))
            assert abs(np.mean(e**4) / np.var(e) ** 2 - 3.0) < 0.3  # kurtosis of a normal
        assert abs(np.corrcoef(ea, eb)[0, 1]) < 4 / math.sqrt(n)  # independent phases
        assert abs(np.corrcoef(ea[1:], ea[:-1])[0, 1]) < 4 / math.sqrt(n)  # white


# ------------------------------------------------------------------ encoder

def test_encoder_steps_angle_and_speed(stub, spmsm_model):
    ffi, lib = stub
    lib.stub_twolevel_set_echo(0)
    bits, window = 10, 16
    n_counts = 2**bits
    tr = run_closed_loop(ffi, lib, _short(spmsm_model, encoder_bits=bits))
    # angle: p*count*2*pi/N, lagging the plant by less than one count (floor)
    counts = tr.theta_e_meas_rad * n_counts / (2 * np.pi)
    np.testing.assert_allclose(counts, np.round(counts), atol=1e-6)
    lag = np.angle(np.exp(1j * (tr.theta_e_rad - tr.theta_e_meas_rad)))
    assert np.all(lag >= -1e-12) and np.all(lag < P * 2 * np.pi / n_counts)
    assert np.all(np.diff(tr.theta_e_meas_rad)[np.abs(np.diff(tr.theta_e_meas_rad)) < 1] >= -1e-12)  # steps forward
    # speed: count differences over 16 periods
    steps = tr.omega_m_meas_rad_s[window:] * window * DT * n_counts / (2 * np.pi)
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-9)
    res = 2 * np.pi / n_counts / (window * DT)  # 7.7 rad/s per count
    assert len(np.unique(tr.omega_m_meas_rad_s[window:])) > 3
    err = tr.omega_m_meas_rad_s[2000:] - tr.omega_m_rad_s[2000:]
    assert abs(np.mean(err)) < 0.1 * res and np.max(np.abs(err)) < 2 * res
    assert tr.omega_m_meas_rad_s[0] == tr.omega_m_rad_s[0]  # no history at k = 0


# ------------------------------------------------------------------ measurement delay

def test_measurement_delay_of_one_period_gives_the_previous_samples(stub, spmsm_model):
    ffi, lib = stub
    with echo_mode(lib.stub_twolevel_set_echo, 3):  # te_est = theta_e as the step saw it
        tr = run_closed_loop(ffi, lib, _short(spmsm_model, 0.1, measurement_delay_s=DT))
    for meas, true in ((tr.ia_meas_a, tr.ia_a), (tr.ib_meas_a, tr.ib_a), (tr.theta_e_meas_rad, tr.theta_e_rad),
                       (tr.omega_m_meas_rad_s, tr.omega_m_rad_s)):
        np.testing.assert_array_equal(meas[1:], true[:-1])
        assert meas[0] == true[0]  # before t = 0 the plant rests as at t = 0
    np.testing.assert_array_equal(tr.te_est_nm, tr.theta_e_meas_rad.astype(np.float32))


def test_measurement_delay_samples_inside_the_previous_period(stub, spmsm_model):
    """tau = dt/2: the plant at the middle of the previous period (the current is nearly linear within a
    period of constant voltage, so the sample is the mean of the period's end values up to its curvature)."""
    ffi, lib = stub
    lib.stub_twolevel_set_echo(0)
    tr = run_closed_loop(ffi, lib, _short(spmsm_model, 0.1, measurement_delay_s=DT / 2))
    mid = 0.5 * (tr.ia_a[:-1] + tr.ia_a[1:])
    step = np.max(np.abs(np.diff(tr.ia_a)))
    assert np.max(np.abs(tr.ia_meas_a[1:] - mid)) < 0.01 * step
    assert np.max(np.abs(tr.ia_meas_a[1:] - tr.ia_a[1:])) > 0.3 * step
