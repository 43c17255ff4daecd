"""Host build of the generated two-level step (+ its closed-loop simulator) through cffi."""
from __future__ import annotations

from codegen.hostbuild import HostLib, Records, SimSources, build_library
from codegen.model import Model
from codegen.numfmt.float32 import FLOAT32
from codegen.topologies.twolevel.derive import TwoLevelTables
from codegen.topologies.twolevel.records import INPUT, OUTPUT
from codegen.topologies.twolevel.render import render_cdef, render_two_level
from codegen.topologies.twolevel.sim import SIM_API, SIM_HEADERS, SIM_SOURCES

RECORDS = Records(INPUT.bind(FLOAT32), OUTPUT.bind(FLOAT32))
SIM = SimSources(SIM_API, SIM_SOURCES, SIM_HEADERS)


def build_host_library(model: Model, t: TwoLevelTables, with_sim: bool = True) -> HostLib:
    """Render the host profile (+ the closed loop), compile strictly, load (cached)."""
    files = render_two_level(model, t, "host")
    return build_library(model.prefix, "_mpc_twolevel", files, render_cdef(model, t), RECORDS,
                         SIM if with_sim else None)
