"""The period-by-period loop (``PeriodStepper``, the serial HIL's closed loop) with a non-ideal plant.

Fed the compiled step's decisions, the stepper reproduces ``run_closed_loop`` bit
for bit with every ``[plant]`` non-ideality on: the decision queue, the
measurement-delay samples, the encoder history and the counter-based noise are
carried state or functions of (seed, k), never advanced by reading an input.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from codegen.config import load_config
from codegen.topologies.ttype import sim as ttype_sim
from codegen.topologies.twolevel import sim as twolevel_sim
from codegen.topology import topology_of

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
PLANT = {"plant.dead_time_s": 1e-6, "plant.device_drop_v": 1.0, "plant.current_gain_error": 0.01,
         "plant.current_offset_a": 0.05, "plant.adc_bits": 12, "plant.noise_a": 0.05, "plant.noise_seed": 11,
         "plant.encoder_bits": 14, "plant.measurement_delay_s": 10e-6}
CASES = [
    ("seed001_spmsm", "conventional", twolevel_sim, {"scenario.duration_s": 0.05, "scenario.speed_ref_rpm": [[0.0, 500.0]],
                                                     "scenario.load_nm": [[0.0, 5.0]]}),
    ("seed000_tlevel", "mpdtc63", ttype_sim, {"scenario.set": "config", "scenario.duration_s": 0.05}),
]


@pytest.mark.parametrize("d", [0, 2])
@pytest.mark.parametrize("name,strategy,sim,short", CASES, ids=[c[0] for c in CASES])
def test_stepper_equals_run_with_a_nonideal_plant(name, strategy, sim, short, d):
    model = load_config(EXAMPLES / f"{name}.toml", {"controller.strategy": strategy, **short, **PLANT,
                                                     "plant.actuation_delay_periods": d})
    topo = topology_of(model)
    lib = topo.host_library(model, topo.derive(model), with_sim=True)
    run = sim.run_closed_loop(lib.ffi, lib.lib, model)
    stepper = topo.period_stepper(lib, model)  # the simulation facet's
    for _ in range(stepper.n):
        first = stepper.input().copy()
        rec = stepper.input()  # reading the input changes nothing
        assert all(first[f].tobytes() == rec[f].tobytes() for f in rec.dtype.names)
        stepper.finish(lib.step_batch(rec))
    got = stepper.result()
    assert stepper.k == stepper.n == run.n == 1000
    for field, arr in got.items():
        assert arr.tobytes() == np.asarray(getattr(run, field)).tobytes(), field
    assert np.any(run.ia_meas_a != run.ia_a)
