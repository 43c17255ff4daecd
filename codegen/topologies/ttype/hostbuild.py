"""Host build of the generated T-type step (+ its closed-loop simulator) through cffi."""
from __future__ import annotations

from codegen.hostbuild import HostLib, Records, SimSources, build_library
from codegen.model import Model
from codegen.numfmt.float32 import FLOAT32
from codegen.topologies.ttype.derive import ThreeLevelTables
from codegen.topologies.ttype.records import INPUT, OUTPUT
from codegen.topologies.ttype.render import render_cdef, render_three_level
from codegen.topologies.ttype.sim import SIM_API, SIM_HEADERS, SIM_SOURCES

RECORDS = Records(INPUT.bind(FLOAT32), OUTPUT.bind(FLOAT32))
SIM = SimSources(SIM_API, SIM_SOURCES, SIM_HEADERS)


def build_three_level_library(model: Model, tables: ThreeLevelTables, with_sim: bool = False) -> HostLib:
    """Render the host profile (+ the closed loop), compile strictly, load (cached)."""
    files = render_three_level(model, tables, "host")
    return build_library(model.prefix, "_mpc_ttype", files, render_cdef(model, tables), RECORDS,
                         SIM if with_sim else None)
