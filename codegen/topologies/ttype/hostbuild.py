"""Host build of the generated T-type step (+ its closed-loop simulator) through cffi."""
from __future__ import annotations

from codegen.hostbuild import HostLib, build_step_library
from codegen.model import Model
from codegen.simulator.api import simulator_of
from codegen.topologies.ttype.derive import ThreeLevelTables
from codegen.topologies.ttype.records import INPUT, output_record
from codegen.topologies.ttype.render import render_cdef, render_three_level


def build_three_level_library(model: Model, tables: ThreeLevelTables, with_sim: bool = False) -> HostLib:
    """Render the host profile (+ the closed loop), compile strictly, load (cached)."""
    sim = simulator_of("codegen.topologies.ttype.sim") if with_sim else None
    return build_step_library(model, "_mpc_ttype", render_three_level(model, tables, "host"),
                              render_cdef(model, tables), (INPUT, output_record(tables.max_groups)), sim, tables.nf)
