"""The plant's actuation delay in the T-type loop (seven-segment periods), stub controller.

The decision from the samples of period k (vector, T_N, seven segments) acts
during [k+d, k+d+1); the step's ``prev_vector`` / ``t_n_prev_s`` describe the
period applied now (the decision of k-d; for d = 0 the one held at the sample
instant, of k-1); OOO (13) with T_N = 0 before the first decisions.
"""
from __future__ import annotations

import numpy as np
import pytest

from codegen.model import Plant
from codegen.topologies.ttype.records import SAFE_STATE as OOO
from codegen.topologies.ttype.sim import controller_inputs, params_from_model, run_closed_loop
from tests.fixtures.simbuild import assert_traces_identical, echo_mode

from .conftest import seed000_model

DT = 50e-6


def _delayed(x: np.ndarray, d: int, first) -> np.ndarray:
    """x shifted by d periods (axis 0), ``first`` before the first."""
    if d == 0:
        return x.copy()
    pad = np.empty((d, *x.shape[1:]), x.dtype)
    pad[...] = first
    return np.concatenate((pad, x[:len(x) - d]))


def _model(d: int | None, comp: bool = True, duration_s: float = 0.03):
    m = seed000_model(1800.0, duration_s, imposed=False, load_steps=((0.0, 0.6),))
    m = m.with_controller(delay_compensation=comp)
    return m if d is None else m.replace(plant=Plant(actuation_delay_periods=d))


@pytest.mark.parametrize("comp", [False, True], ids=["no-comp", "comp"])
@pytest.mark.parametrize("d", [0, 1, 2])
def test_decision_of_k_acts_during_k_plus_d(stub, d, comp):
    ffi, lib, mode = stub
    mode(63)
    model = _model(d, comp)
    assert params_from_model(ffi, model).common.delay_periods == d
    with echo_mode(lib.stub_ttype_set_echo, 5):  # te_est_nm = prev_vector as the step saw it
        tr = run_closed_loop(ffi, lib, model)
    assert np.mean(tr.vector >= 27) > 0.2  # seven-segment periods are exercised
    np.testing.assert_array_equal(tr.applied_vector, _delayed(tr.vector, d, OOO))
    prev = _delayed(tr.vector, max(d, 1), OOO)
    np.testing.assert_array_equal(tr.prev_vector, prev)
    np.testing.assert_array_equal(tr.te_est_nm, prev.astype(np.float32))
    t_n_prev = _delayed(tr.t_n_s, max(d, 1), 0.0)
    np.testing.assert_array_equal(tr.t_n_prev_s, t_n_prev)
    rec = controller_inputs(tr, model)
    np.testing.assert_array_equal(rec["prev_vector"], prev)
    # the applied segments are the decision's, d periods late: a virtual vector's first and last
    # segments are T_N/2 of its own decision
    virt = tr.applied_vector >= 27
    tn_applied = _delayed(tr.t_n_s, d, 0.0)
    np.testing.assert_allclose(tr.seg_s[virt, 0], tn_applied[virt] / 2, rtol=1e-6)
    np.testing.assert_allclose(tr.seg_s.sum(axis=1), DT, rtol=1e-12, atol=0)
    assert np.all(tr.seg_states[:d] == OOO)


def test_t_n_prev_is_what_the_step_saw(stub):
    ffi, lib, mode = stub
    mode(63)
    model = _model(2)
    with echo_mode(lib.stub_ttype_set_echo, 4):  # psi_est_wb = t_n_prev_s
        tr = run_closed_loop(ffi, lib, model)
    assert controller_inputs(tr, model)["t_n_prev_s"].tobytes() == tr.psi_est_wb.tobytes()
    assert np.any(tr.t_n_prev_s > 0)


@pytest.mark.parametrize("comp,d", [(False, 0), (True, 1)])
def test_default_delay_follows_the_controllers_flag(stub, comp, d):
    ffi, lib, mode = stub
    mode(63)
    model = _model(None, comp)
    assert params_from_model(ffi, model).common.delay_periods == d
    assert_traces_identical(run_closed_loop(ffi, lib, model), run_closed_loop(ffi, lib, _model(d, comp)))


def test_chunked_run_with_delay_two(stub):
    ffi, lib, mode = stub
    mode(63)
    model = _model(2)
    assert_traces_identical(run_closed_loop(ffi, lib, model), run_closed_loop(ffi, lib, model, chunk=1),
                            run_closed_loop(ffi, lib, model, chunk=77))


def test_queue_is_carried_state(stub):
    ffi, lib, _ = stub
    p = params_from_model(ffi, _model(2))
    st = ffi.new("ttype_sim_state_t *")
    assert lib.ttype_sim_init(p, st) == 0
    assert st.prior_vector == OOO and list(st.prior_states) == [OOO] * 7 and st.prior_seg_s[0] == DT
    ref = ffi.new("double[1]", [0.0])
    st.prior_states[2] = 27
    assert lib.ttype_sim_run(p, ref, ref, 1, ffi.NULL, st) == -1
    st.prior_states[2] = OOO
    st.prior_vector = 63
    assert lib.ttype_sim_run(p, ref, ref, 1, ffi.NULL, st) == -1
    st.prior_vector = OOO
    assert lib.ttype_sim_run(p, ref, ref, 1, ffi.NULL, st) == 0 and st.common.k == 1
