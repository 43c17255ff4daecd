"""What the board's plant is made of: the topology's files, constants printed exactly, the simulator's
delay rule, the simulator trace's names on the wire.

The on-board plant comes with the topology (``Topology.firmware_plant``), its
real constants are the float32 values of the config's (exact literals of the
number format), its actuation delay is the simulator's
``Plant.delay_periods`` on the model the host compares with, and a TELEMETRY
sample carries the simulator trace's field names and the topology's decision
field.
"""
from __future__ import annotations

import re

import numpy as np
import pytest
from hil_support import SPMSM, TLEVEL

from codegen.config import load_config
from codegen.simulator.records import SIM_TRACE
from codegen.topology import topology_of
from hil.codecgen import PLANT_FORMAT, board_model, plant_constants, protocol_files
from hil.schema import SAMPLE_TRACE_FIELDS, Schema

#: constant -> the model value it holds (a real: its float32 literal)
REALS = {"ONB_RS": "motor.rs_ohm", "ONB_LD": "motor.ld_h", "ONB_LQ": "motor.lq_h", "ONB_PSI_F": "motor.psi_f_wb",
         "ONB_J": "motor.j_kgm2", "ONB_B": "motor.b_nms", "ONB_UDC": "inverter.udc_v", "ONB_C_F": "inverter.c_f",
         "ONB_DT": "controller.dt_s", "ONB_KP": "speed_loop.kp", "ONB_KI": "speed_loop.ki",
         "ONB_LIMIT": "speed_loop.limit_nm"}
MODELS = [(SPMSM, "conventional", {}), (SPMSM, "s1", {"controller.delay_compensation": True}),
          (SPMSM, "s1", {"controller.delay_compensation": True, "plant.actuation_delay_periods": 2}),
          (TLEVEL, "mpdtc27", {})]


def _model(config, strategy, overrides):
    return load_config(config, {"controller.strategy": strategy, **overrides})


def _value(model, path: str) -> float:
    section, name = path.split(".")
    return float(getattr(getattr(model, section), name))


@pytest.mark.parametrize("config,strategy,overrides", MODELS)
def test_constants_are_exact_float32_literals_and_the_simulators_delay(config, strategy, overrides):
    m = _model(config, strategy, overrides)
    consts = {c.name: c.value for c in plant_constants(m)}
    for name, path in REALS.items():
        lit = consts[name]
        assert re.fullmatch(r"-?0x[0-9a-f.]+p[-+]\d+f", lit), (name, lit)  # the format's exact literal
        assert np.float32(float.fromhex(lit[:-1])) == np.float32(_value(m, path)), name
        assert lit == PLANT_FORMAT.literal(PLANT_FORMAT.const(_value(m, path)))
    assert consts["ONB_POLE_PAIRS"] == str(m.motor.pole_pairs)
    # the simulator's rule on the model the host compares with (the ideal plant: a [plant] section is not
    # modelled on board)
    host = board_model(m)
    d = host.plant.delay_periods(m.controller.delay_compensation)
    assert consts["ONB_DELAY_PERIODS"] == str(d) and d == (1 if m.controller.delay_compensation else 0)
    header = protocol_files(m)["gen/plant_config.h"]
    for name, value in consts.items():
        assert f"#define {name} {value} " in header


@pytest.mark.parametrize("config,strategy", [(SPMSM, "conventional"), (TLEVEL, "mpdtc27")])
def test_the_plant_files_are_the_topologys_and_the_sample_speaks_the_trace_names(config, strategy):
    m = _model(config, strategy, {})
    topo = topology_of(m)
    files = protocol_files(m)
    plant = topo.firmware_plant(m)
    assert plant and all(files[f"firmware/runtime/{name}"] == text for name, text in plant.items())
    trace_names = {f.name for f in SIM_TRACE.fields}
    sample = Schema.of(m).sample.record
    names = [f.name for f in sample.fields]
    assert names == ["k", *[f.name for f in SAMPLE_TRACE_FIELDS], topo.decision_field, "fault"]
    assert {f.name for f in SAMPLE_TRACE_FIELDS} | {"fault"} <= trace_names
    assert topo.decision_field in {f.name for f in topo.output_record(m).fields}
    assert f"#define HIL_DECISION_FIELD {topo.decision_field}\n" in files["gen/hil_codec.h"]
