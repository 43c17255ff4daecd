"""Host build of the generated two-level step (+ its closed-loop simulator) through cffi."""
from __future__ import annotations

from codegen.hostbuild import HostLib, build_step_library
from codegen.model import Model
from codegen.simulator.api import simulator_of
from codegen.topologies.twolevel.derive import TwoLevelTables
from codegen.topologies.twolevel.records import INPUT, OUTPUT
from codegen.topologies.twolevel.render import render_cdef, render_two_level


def build_host_library(model: Model, t: TwoLevelTables, with_sim: bool = True) -> HostLib:
    """Render the host profile (+ the closed loop), compile strictly, load (cached)."""
    sim = simulator_of("codegen.topologies.twolevel.sim") if with_sim else None
    return build_step_library(model, "_mpc_twolevel", render_two_level(model, t, "host"), render_cdef(model, t),
                              (INPUT, OUTPUT), sim, t.nf)
