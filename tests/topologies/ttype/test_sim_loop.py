"""T-type closed loop (csrc/ttype_sim.c + codegen/topologies/ttype/sim.py) with the stub controller."""
from __future__ import annotations

import dataclasses
import time

import numpy as np
import pytest

from codegen.simulator.driver import SimulationError
from codegen.topologies.ttype.metrics import leg_level_changes
from codegen.topologies.ttype.records import INPUT_DTYPE
from codegen.topologies.ttype.sim import controller_inputs, params_from_model, run_closed_loop
from tests.fixtures.simbuild import assert_traces_identical, echo_mode

from .conftest import seed000_model


def test_chunked_equals_one_long_run(stub):
    ffi, lib, mode = stub
    mode(63)
    model = seed000_model(1800.0, 0.2, imposed=False, load_steps=((0.0, 0.0), (0.1, 1.27)))
    a = run_closed_loop(ffi, lib, model, chunk=4000)
    b = run_closed_loop(ffi, lib, model, chunk=777)
    c = run_closed_loop(ffi, lib, model, chunk=1)
    assert_traces_identical(a, b, c)
    assert np.mean(a.vector >= 27) > 0.2  # virtual vectors (7 segments) were exercised


def test_one_step_delay_timing(stub):
    ffi, lib, mode = stub
    mode(63)
    with echo_mode(lib.stub_ttype_set_echo, 5):  # te_est_nm = prev_vector as the step saw it
        tr = run_closed_loop(ffi, lib, seed000_model(1800.0, 0.05))
    prev = np.concatenate(([13], tr.vector[:-1]))
    np.testing.assert_array_equal(tr.te_est_nm, prev.astype(np.float32))
    # the decision of k is applied during [k+1, k+2)
    np.testing.assert_array_equal(tr.applied_vector, prev)
    assert np.all(tr.seg_states[0] == 13) and tr.seg_s[0, 0] == 50e-6
    # applied segments: the sum is the period; states/durations follow the applied vector
    np.testing.assert_allclose(tr.seg_s.sum(axis=1), 50e-6, rtol=1e-12, atol=0)
    virt = tr.applied_vector >= 27
    assert np.all(np.count_nonzero(tr.seg_s[virt] > 0, axis=1) >= 5)
    basic = ~virt
    np.testing.assert_array_equal(tr.seg_states[basic][:, 0], tr.applied_vector[basic])
    # T_N of the applied virtual vector: first and last segments are T_N/2
    tn = np.concatenate(([0.0], tr.t_n_s[:-1])).astype(np.float64)
    np.testing.assert_allclose(tr.seg_s[virt, 0], tn[virt] / 2, rtol=1e-6)


@pytest.mark.parametrize("echo,fields", [(1, ("torque_ref_nm", "omega_e_rad_s")), (2, ("ia_a", "ib_a")),
                                         (3, ("theta_e_rad", "uc1_v")), (4, ("uc2_v", "t_n_prev_s"))])
def test_controller_inputs_are_what_the_step_saw(stub, echo, fields):
    ffi, lib, mode = stub
    mode(63)
    model = seed000_model(3000.0, 0.05, imposed=False, load_steps=((0.0, 0.5),))
    with echo_mode(lib.stub_ttype_set_echo, echo):
        tr = run_closed_loop(ffi, lib, model)
    rec = controller_inputs(tr, model)
    assert rec.shape == (tr.n,) and set(rec.dtype.names) >= set(INPUT_DTYPE.names)
    assert rec[fields[0]].tobytes() == tr.te_est_nm.tobytes()
    assert rec[fields[1]].tobytes() == tr.psi_est_wb.tobytes()
    assert np.any(tr.vo_v != 0.0)  # uc1 != uc2: the V_o path is exercised
    np.testing.assert_array_equal(rec["prev_vector"], np.concatenate(([13], tr.vector[:-1])))


def test_leg_changes_and_uab_trace(stub):
    ffi, lib, mode = stub
    mode(63)
    tr = run_closed_loop(ffi, lib, seed000_model(1800.0, 0.05))
    np.testing.assert_array_equal(leg_level_changes(tr.seg_states, tr.seg_s), tr.leg_changes)
    ss = tr.seg_states.astype(np.int64)
    lv = np.stack([ss // 9 - 1, (ss // 3) % 3 - 1], axis=-1).astype(float)
    # u_ab = (Sa - Sb) Udc/2 + (|Sa| - |Sb|) V_o, V_o within a period moves by ~0.1 V
    approx = (lv[..., 0] - lv[..., 1]) * 110.0 + (np.abs(lv[..., 0]) - np.abs(lv[..., 1])) * tr.vo_v[:, None]
    assert np.max(np.abs(tr.uab_v - approx)) < 0.5
    # a virtual-vector period changes one leg by one level per step: 6 inside + boundary
    assert np.max(tr.leg_changes) <= 12


def test_imposed_speed_and_speed_pi(stub):
    ffi, lib, mode = stub
    mode(63)
    model = seed000_model(1800.0, 0.1)
    tr = run_closed_loop(ffi, lib, model)
    np.testing.assert_array_equal(tr.omega_m_rad_s, tr.speed_ref_rad_s)
    np.testing.assert_array_equal(tr.torque_ref_nm, tr.load_nm)
    assert abs(np.mean(tr.te_nm[1000:]) - 1.27) < 0.1
    assert abs(np.mean(tr.vo_v[1000:])) < 0.5 and np.all(tr.fault == 0)
    model = seed000_model(3000.0, 0.4, imposed=False, load_steps=((0.0, 0.0), (0.25, 1.27)))
    tr = run_closed_loop(ffi, lib, model)
    assert abs(np.mean(tr.speed_rpm[4000:5000]) - 3000.0) < 15.0
    assert abs(np.mean(tr.speed_rpm[-1000:]) - 3000.0) < 15.0
    assert abs(np.mean(tr.te_nm[-1000:]) - 1.27) < 0.1
    assert np.all(np.abs(tr.torque_ref_nm) <= 4.0)


def test_seven_segment_run_prints_its_throughput(stub, capsys):
    """A 1 s closed loop with seven-segment integration (1 us sub-steps) completes and prints its
    periods/s.  No timed assertion (shared machines): `mpcgen bench` measures the closed loop."""
    ffi, lib, mode = stub
    mode(63)
    model = seed000_model(3000.0, 1.0)
    run_closed_loop(ffi, lib, seed000_model(3000.0, 0.01))  # warm-up
    t = time.perf_counter()
    tr = run_closed_loop(ffi, lib, model)
    rate = tr.n / (time.perf_counter() - t)
    with capsys.disabled():
        print(f"\nthree-level closed loop, stub 63-vector controller, {np.mean(tr.applied_vector >= 27):.0%} "
              f"seven-segment periods, 1 us RK4 sub-steps: {rate:,.0f} periods/s")
    assert tr.n == round(1.0 / model.controller.dt_s) and np.mean(tr.applied_vector >= 27) > 0.1


def test_bad_parameters_and_state(stub):
    ffi, lib, _ = stub
    model = seed000_model(1800.0, 0.01, imposed=False)
    bad = model.replace(inverter=dataclasses.replace(model.inverter, c_f=0.0))
    with pytest.raises(SimulationError, match="invalid simulator arguments"):
        run_closed_loop(ffi, lib, bad)
    p = params_from_model(ffi, model)
    assert (p.c_f, p.common.udc_v, p.substep_max_s, p.common.speed_imposed) == (1000e-6, 220.0, 1e-6, 0)
    st = ffi.new("ttype_sim_state_t *")
    assert lib.ttype_sim_init(p, st) == 0
    assert st.applied_vector == 13 and st.last_state == 13 and list(st.applied_states) == [13] * 7
    ref = ffi.new("double[3]", [0.0, 0.0, 0.0])
    st.applied_states[3] = 27
    assert lib.ttype_sim_run(p, ref, ref, 1, ffi.NULL, st) == -1
    st.applied_states[3] = 13
    assert lib.ttype_sim_run(p, ref, ref, 1, ffi.NULL, st) == 0 and st.common.k == 1
    st.vo_v = float("inf")
    assert lib.ttype_sim_run(p, ref, ref, 2, ffi.NULL, st) == -2 and st.common.k == 1

