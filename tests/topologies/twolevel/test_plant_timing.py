"""The plant's actuation delay (``plant.actuation_delay_periods``) in the two-level loop, stub controller.

The decision from the samples of period k acts during [k+d, k+d+1) whatever the
controller assumes; the step's ``prev_sw`` is the state applied during the
current period (the decision of k-d; for d = 0 the state held at the sample
instant, the decision of k-1); 000 before the first decisions.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from codegen.model import Plant
from codegen.topologies.twolevel.sim import controller_inputs, params_from_model, run_closed_loop
from tests.fixtures.simbuild import assert_traces_identical, echo_mode


def _short(model, duration_s=0.05, plant=None, **ctrl):
    m = model.replace(scenario=dataclasses.replace(model.scenario, duration_s=duration_s))
    if plant is not None:
        m = m.replace(plant=plant)
    return m.with_controller(**ctrl) if ctrl else m


def _delayed(x: np.ndarray, d: int) -> np.ndarray:
    """x shifted by d periods, 0 (000) before the first."""
    return np.concatenate((np.zeros(d, x.dtype), x[:len(x) - d])) if d else x.copy()


@pytest.mark.parametrize("comp", [False, True], ids=["no-comp", "comp"])
@pytest.mark.parametrize("d", [0, 1, 2])
def test_decision_of_k_acts_during_k_plus_d(stub, spmsm_model, d, comp):
    ffi, lib = stub
    model = _short(spmsm_model, plant=Plant(actuation_delay_periods=d), delay_compensation=comp)
    assert params_from_model(ffi, model).common.delay_periods == d
    with echo_mode(lib.stub_twolevel_set_echo, 4):  # te_est_nm = prev_sw as the step saw it
        tr = run_closed_loop(ffi, lib, model)
    assert len(set(tr.sw.tolist())) > 3  # the run switches
    np.testing.assert_array_equal(tr.applied_sw, _delayed(tr.sw, d))
    prev = _delayed(tr.sw, max(d, 1))
    np.testing.assert_array_equal(tr.prev_sw, prev)
    np.testing.assert_array_equal(tr.te_est_nm, prev.astype(np.float32))
    if d >= 1:  # the controller's prev_sw is what the inverter applies during the period
        np.testing.assert_array_equal(tr.prev_sw, tr.applied_sw)
    np.testing.assert_array_equal(controller_inputs(tr, model)["prev_sw"], prev)


@pytest.mark.parametrize("comp,d", [(False, 0), (True, 1)])
def test_default_delay_follows_the_controllers_assumption(stub, spmsm_model, comp, d):
    ffi, lib = stub
    model = _short(spmsm_model, delay_compensation=comp)
    assert model.plant.actuation_delay_periods is None
    assert params_from_model(ffi, model).common.delay_periods == d
    lib.stub_twolevel_set_echo(0)
    explicit = run_closed_loop(ffi, lib, model.replace(plant=Plant(actuation_delay_periods=d)))
    assert_traces_identical(run_closed_loop(ffi, lib, model), explicit)


def test_delay_changes_the_closed_loop(stub, spmsm_model):
    """One more period of delay: the torque ripple of the same (uncompensated) controller grows."""
    ffi, lib = stub
    lib.stub_twolevel_set_echo(0)
    rip = []
    for d in (0, 1, 2):
        tr = run_closed_loop(ffi, lib, _short(spmsm_model, 0.3, plant=Plant(actuation_delay_periods=d)))
        sl = slice(2000, None)
        rip.append(float(np.std(tr.te_nm[sl] - tr.torque_ref_nm[sl])))
    assert rip[0] < rip[1] < rip[2], rip


def test_chunked_run_with_delay_two(stub, spmsm_model):
    ffi, lib = stub
    lib.stub_twolevel_set_echo(0)
    model = _short(spmsm_model, 0.05, plant=Plant(actuation_delay_periods=2))
    assert_traces_identical(run_closed_loop(ffi, lib, model), run_closed_loop(ffi, lib, model, chunk=1),
                            run_closed_loop(ffi, lib, model, chunk=333))


def test_queue_is_carried_state(stub, spmsm_model):
    """The queue (prev_sw, prior_sw) and the held state are validated like the rest of the state."""
    ffi, lib = stub
    p = params_from_model(ffi, _short(spmsm_model, plant=Plant(actuation_delay_periods=2)))
    st = ffi.new("twolevel_sim_state_t *")
    assert lib.twolevel_sim_init(p, st) == 0
    assert (st.prev_sw, st.prior_sw, st.held_sw) == (0, 0, 0)
    ref = ffi.new("double[1]", [0.0])
    for name in ("prior_sw", "held_sw"):
        setattr(st, name, 8)
        assert lib.twolevel_sim_run(p, ref, ref, 1, ffi.NULL, st) == -1
        setattr(st, name, 0)
    p.common.delay_periods = 3
    assert lib.twolevel_sim_run(p, ref, ref, 1, ffi.NULL, st) == -1
