"""The gates_off output (numerics.md "Input guard and safe decision"): set on every fault kind
(each FAULT bit alone) for both topologies, in the Python reference and in the compiled C, as
``controller.fault_action`` says; the active short circuit's speed condition at the threshold
exactly and one float32 step below; a NaN speed gives gates off; no fault gives 0."""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.config import load_config
from codegen.topology import topology_of

from conftest import SPMSM, TTYPE

F = np.float32
ASC_RPM = 300.0


def _setup(cfg, strategy, **controller):
    m = load_config(cfg, {"controller.strategy": strategy, **{f"controller.{k}": v for k, v in controller.items()}})
    topo = topology_of(m)
    t = topo.derive(m)
    return m, t, (lambda x: topo.step_batch(t, x)), topo.host_library(m, t).step_batch


def _states(m, t, omega: float | None = None) -> tuple[np.ndarray, list[int]]:
    """Row 0 nominal (no fault), then one row per fault bit, each tripping only that bit."""
    from codegen.stages.fwdata import layouts

    two_level = "udc_v" in layouts(m)[0].dtype.names
    bits = [1 << i for i in range(7 if two_level else 8)]
    x = np.zeros(1 + len(bits), layouts(m)[0].dtype)
    x["ia_a"], x["ib_a"], x["theta_e_rad"], x["torque_ref_nm"] = 1.0, 0.5, 0.5, 0.5
    x["omega_e_rad_s"] = 100.0 if omega is None else omega
    udc = m.inverter.udc_v
    if two_level:
        x["udc_v"], x["prev_sw"] = udc, 0
    else:
        x["uc1_v"], x["uc2_v"], x["prev_vector"], x["t_n_prev_s"] = udc / 2, udc / 2, 13, 0.0
    c = t.const
    r = 1 + np.arange(len(bits))
    x["ia_a"][r[0]] = 2 * c("I_TRIP_A")
    x["udc_v" if two_level else "uc1_v"][r[1]] = 0.5 * c("UDC_MIN_V" if two_level else "UC_MIN_V")
    x["udc_v" if two_level else "uc1_v"][r[2]] = 2 * c("UDC_MAX_V" if two_level else "UC_MAX_V")
    x["theta_e_rad"][r[3]] = 2 * c("ANGLE_GUARD_RAD")
    x["omega_e_rad_s"][r[4]] = 2 * c("OMEGA_GUARD_RAD_S")
    x["torque_ref_nm"][r[5]] = 2 * c("TORQUE_REF_GUARD_NM")
    x["prev_sw" if two_level else "prev_vector"][r[6]] = 8 if two_level else 63
    if not two_level:
        x["prev_vector"][r[7]], x["t_n_prev_s"][r[7]] = 40, 1.0
    return x, bits


CASES = [(SPMSM, "conventional"), (SPMSM, "s1"), (TTYPE, "mpdtc27"), (TTYPE, "mpdtc63")]


@pytest.mark.parametrize("cfg,strategy", CASES)
def test_gates_off_on_every_fault(cfg, strategy):
    m, t, ref, c_step = _setup(cfg, strategy)
    assert m.controller.fault_action == "gates-off"
    x, bits = _states(m, t)
    for label, out in (("reference", ref(x)), ("C", c_step(x))):
        assert list(out["fault"]) == [0, *bits], label
        assert list(out["gates_off"]) == [0] + [1] * len(bits), label
    assert ref(x).tobytes() == c_step(x).tobytes()


@pytest.mark.parametrize("cfg,strategy", CASES)
def test_active_short_circuit_speed_threshold(cfg, strategy):
    m, t, ref, c_step = _setup(cfg, strategy, fault_action="active-short-circuit", asc_min_speed_rpm=ASC_RPM)
    thr = t.const("ASC_OMEGA_MIN_RAD_S")
    assert thr == F(m.motor.pole_pairs * ASC_RPM * 2 * math.pi / 60)
    below = np.nextafter(thr, F(0))
    for omega, want in ((thr, 0), (-thr, 0), (below, 1), (-below, 1)):
        x, bits = _states(m, t, float(omega))
        speed = bits.index(16)  # the SPEED row's speed is beyond the guard, above the threshold
        expect = [0] + [0 if i == speed else want for i in range(len(bits))]
        for label, out in (("reference", ref(x)), ("C", c_step(x))):
            assert list(out["fault"]) == [0, *bits], label
            assert list(out["gates_off"]) == expect, (label, omega)
        assert ref(x).tobytes() == c_step(x).tobytes()
    # a speed that is not a number trips SPEED and gives gates off
    x, _ = _states(m, t)
    x["omega_e_rad_s"] = np.nan
    for label, out in (("reference", ref(x)), ("C", c_step(x))):
        assert (out["fault"] & 16 != 0).all() and (out["gates_off"] == 1).all(), label
    assert ref(x).tobytes() == c_step(x).tobytes()
