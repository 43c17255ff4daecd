"""Two-level closed loop (csrc/twolevel_sim.c + codegen/topologies/twolevel/sim.py) with the stub controller."""
from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
import pytest

from codegen.metrics import steady_windows, window_slice
from codegen.simulator.driver import SimulationError, default_substeps, n_periods, scenario_arrays
from codegen.topologies.twolevel.records import INPUT_DTYPE
from codegen.topologies.twolevel.sim import Trace, controller_inputs, params_from_model, run_closed_loop
from tests.fixtures.simbuild import assert_traces_identical, echo_mode

RPM = 2 * math.pi / 60


def _short(model, duration_s=0.3, **ctrl):
    m = model.replace(scenario=dataclasses.replace(model.scenario, duration_s=duration_s))
    return m.with_controller(**ctrl) if ctrl else m


@pytest.fixture(scope="module")
def full_run(stub, spmsm_model):
    ffi, lib = stub
    lib.stub_twolevel_set_echo(0)
    calls = []
    t = time.perf_counter()
    tr = run_closed_loop(ffi, lib, spmsm_model, progress=calls.append)
    elapsed = time.perf_counter() - t
    return tr, calls, elapsed


def test_scenario_arrays_spmsm(spmsm_model):
    speed, load = scenario_arrays(spmsm_model)
    assert speed.shape == load.shape == (80_000,) == (n_periods(spmsm_model),)
    assert np.all(speed[:40_000] == 500 * RPM) and np.all(speed[40_000:] == -500 * RPM)
    assert np.all(load[:20_000] == 10.0) and np.all(load[20_000:60_000] == -10.0)
    assert np.all(load[60_000:] == 10.0)
    assert default_substeps(50e-6) == 50 and default_substeps(100e-6) == 100
    assert default_substeps(62.5e-6) == 63


def test_params_from_model(stub, spmsm_model):
    ffi, _ = stub
    p = params_from_model(ffi, spmsm_model)
    c = p.common
    assert (c.rs_ohm, c.ld_h, c.pole_pairs, c.udc_v, c.dt_s, p.substeps) == (0.2, 8.5e-3, 4, 312.0, 50e-6, 50)
    assert (c.kp, c.ki, c.limit_nm, c.speed_imposed) == (5.0, 10.0, 30.0, 0)


def test_full_scenario_follows_reference(full_run, spmsm_model):
    tr, calls, elapsed = full_run
    assert isinstance(tr, Trace) and tr.n == 80_000 and tr.dt_s == 50e-6
    assert tr.duration_s == pytest.approx(4.0)
    np.testing.assert_array_equal(tr.t_s, np.arange(80_000) * 50e-6)
    # progress once per 10 000-period chunk, ending at 1
    assert calls == pytest.approx([k / 8 for k in range(1, 9)])
    # speed within 2 % of the reference (mean over each steady window)
    for t0, t1 in steady_windows(spmsm_model):
        sl = window_slice(tr.dt_s, t0, t1, tr.n)
        assert abs(np.mean(tr.speed_rpm[sl]) - tr.speed_ref_rpm[sl][0]) < 10.0
        assert abs(np.mean(tr.te_nm[sl] - tr.torque_ref_nm[sl])) < 1.0
        assert abs(np.mean(tr.psi_wb[sl]) - 0.3) < 0.01
    assert np.all(np.abs(tr.torque_ref_nm) <= 30.0)
    assert np.all(tr.fault == 0)
    assert np.all((tr.theta_e_rad >= 0) & (tr.theta_e_rad < 2 * np.pi))
    np.testing.assert_array_equal(tr.applied_sw, tr.sw)  # no delay compensation
    # read-only arrays: the trace is frozen
    with pytest.raises(ValueError):
        tr.te_nm[0] = 1.0
    rate = tr.n / elapsed
    print(f"\nclosed loop, stub controller, 50 RK4 sub-steps: {rate:,.0f} periods/s")  # mpcgen bench measures it


def test_chunked_equals_one_long_run(stub, spmsm_model, full_run):
    ffi, lib = stub
    lib.stub_twolevel_set_echo(0)
    tr = full_run[0]
    one = run_closed_loop(ffi, lib, spmsm_model, chunk=80_000)
    odd = run_closed_loop(ffi, lib, spmsm_model, chunk=7_777)
    assert_traces_identical(tr, one, odd)


def test_delay_compensation_timing(stub, spmsm_model):
    ffi, lib = stub
    with echo_mode(lib.stub_twolevel_set_echo, 4):  # te_est_nm = prev_sw as the step saw it
        for dc in (False, True):
            tr = run_closed_loop(ffi, lib, _short(spmsm_model, 0.05, delay_compensation=dc))
            prev = np.concatenate(([0], tr.sw[:-1]))
            np.testing.assert_array_equal(tr.te_est_nm, prev.astype(np.float32))
            if dc:  # decision of k acts during [k+1, k+2): applied = previous decision
                np.testing.assert_array_equal(tr.applied_sw, prev)
            else:
                np.testing.assert_array_equal(tr.applied_sw, tr.sw)
            assert len(set(tr.sw.tolist())) > 3


@pytest.mark.parametrize("mode,fields", [(1, ("torque_ref_nm", "omega_e_rad_s")),
                                         (2, ("ia_a", "ib_a")),
                                         (3, ("theta_e_rad", "udc_v"))])
def test_controller_inputs_are_what_the_step_saw(stub, spmsm_model, mode, fields):
    ffi, lib = stub
    model = _short(spmsm_model, 0.1)
    with echo_mode(lib.stub_twolevel_set_echo, mode):
        tr = run_closed_loop(ffi, lib, model)
    rec = controller_inputs(tr, model)
    assert rec.dtype == INPUT_DTYPE and rec.shape == (tr.n,)
    assert rec[fields[0]].tobytes() == tr.te_est_nm.tobytes()
    assert rec[fields[1]].tobytes() == tr.psi_est_wb.tobytes()


def test_speed_imposed(stub, spmsm_model):
    ffi, lib = stub
    lib.stub_twolevel_set_echo(0)
    model = _short(spmsm_model, 0.2).replace(
        scenario=dataclasses.replace(spmsm_model.scenario, duration_s=0.2, speed_mode="imposed",
                                     load_nm=((0.0, 5.0), (0.1, -5.0))))
    tr = run_closed_loop(ffi, lib, model)
    np.testing.assert_array_equal(tr.omega_m_rad_s, tr.speed_ref_rad_s)
    np.testing.assert_array_equal(tr.torque_ref_nm, tr.load_nm)
    assert abs(np.mean(tr.te_nm[1000:2000]) - 5.0) < 0.5
    assert abs(np.mean(tr.te_nm[3000:4000]) + 5.0) < 0.5


def test_bad_parameters_raise(stub, spmsm_model):
    ffi, lib = stub
    bad = spmsm_model.replace(motor=dataclasses.replace(spmsm_model.motor, j_kgm2=0.0))
    with pytest.raises(SimulationError, match="invalid simulator arguments"):
        run_closed_loop(ffi, lib, bad)
    p = params_from_model(ffi, spmsm_model)
    st = ffi.new("twolevel_sim_state_t *")
    assert lib.twolevel_sim_init(p, st) == 0
    st.prev_sw = 9
    ref = ffi.new("double[1]", [0.0])
    assert lib.twolevel_sim_run(p, ref, ref, 1, ffi.NULL, st) == -1
    st.prev_sw = 0
    assert lib.twolevel_sim_run(p, ref, ref, 1, ffi.NULL, st) == 0  # NULL trace: nothing recorded
    assert st.common.k == 1


def test_divergence_is_reported(stub, spmsm_model):
    ffi, lib = stub
    p = params_from_model(ffi, spmsm_model)
    st = ffi.new("twolevel_sim_state_t *")
    assert lib.twolevel_sim_init(p, st) == 0
    st.common.motor.i_d_a = float("inf")
    ref = ffi.new("double[3]", [0.0, 0.0, 0.0])
    assert lib.twolevel_sim_run(p, ref, ref, 3, ffi.NULL, st) == -2
    assert st.common.k == 0

