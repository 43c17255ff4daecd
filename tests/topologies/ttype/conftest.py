"""Fixtures of the three-level simulator tests: stub-controller build and the seed-000 model.

The model is built directly from the parameters of docs/algorithms.md (T-type MPDTC)
("Parameters and scenarios", Table 4) -- these tests exercise the simulator,
not the config loader.  The controller is the stub of
tests/fixtures/stub_ttype (a nearest-voltage rule), not the product's MPDTC.
"""
from __future__ import annotations

import numpy as np
import pytest

from codegen.model import Controller, Inverter, Model, Motor, Scenario, SpeedLoop
from codegen.topologies.ttype.sim import SIM
from codegen.topologies.ttype.virtual import VIRTUAL
from tests.fixtures.simbuild import build_stub_library

STUB_CDEF = """
void stub_ttype_set_params(float rs_ohm, float ls_h, float psi_f_wb, int pole_pairs,
                           float ts_s, float c_f);
void stub_ttype_set_virtual(const unsigned short *seq, int enable);
void stub_ttype_set_echo(int mode);
"""


def seed000_model(speed_rpm: float = 1800.0, duration_s: float = 0.3, load_nm: float = 1.27,
                  imposed: bool = True, load_steps=None) -> Model:
    return Model(
        name="seed000_tt3l",
        prefix="mpc3",
        source="tests/topologies/ttype (seed 000 parameters)",
        motor=Motor(rs_ohm=1.75, ld_h=1.6e-3, lq_h=1.6e-3, psi_f_wb=0.045, pole_pairs=5,
                    rated_speed_rpm=3000.0, rated_torque_nm=1.27, j_kgm2=5e-4, b_nms=0.0),
        inverter=Inverter(topology="t-type", udc_v=220.0, udc_min_v=150.0, udc_max_v=300.0,
                          i_trip_a=30.0, c_f=1000e-6),
        controller=Controller(strategy="mpdtc63", predictor="dq-euler", delay_compensation=True,
                              tables="derived", dt_s=50e-6, psi_ref_wb=0.045, eps_t_nm=0.0),
        speed_loop=SpeedLoop(kp=0.1, ki=4.0, limit_nm=4.0),
        scenario=Scenario(duration_s=duration_s, speed_ref_rpm=((0.0, speed_rpm),),
                          load_nm=tuple(load_steps) if load_steps else ((0.0, load_nm),),
                          speed_mode="imposed" if imposed else "mechanical"),
    )


@pytest.fixture(scope="session")
def stub(tmp_path_factory):
    ffi, lib = build_stub_library(SIM, STUB_CDEF, tmp_path_factory.mktemp("stub_ttype_build"))
    lib.stub_ttype_set_params(1.75, 1.6e-3, 0.045, 5, 50e-6, 1000e-6)
    seq = np.array([vv.sequence for vv in VIRTUAL], dtype=np.uint16).ravel()
    buf = ffi.new("unsigned short[]", seq.tolist())

    def set_mode(mode: int) -> None:
        lib.stub_ttype_set_virtual(buf, 1 if mode == 63 else 0)

    set_mode(27)
    return ffi, lib, set_mode
