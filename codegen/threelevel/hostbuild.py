"""Host build of the generated three-level C (codegen.hostbuild.build_library)."""
from __future__ import annotations

from ..hostbuild import HostLib, Records, build_library
from ..model import Model
from .derive import ThreeLevelTables
from .interface import INPUT_DTYPE, INPUT_FIELDS, OUTPUT_DTYPE, OUTPUT_FIELDS
from .render import render_cdef, render_three_level

THREE_LEVEL_RECORDS = Records(INPUT_FIELDS, OUTPUT_FIELDS, INPUT_DTYPE, OUTPUT_DTYPE)
SIM3L = ("runtime/sim3l_api.h",
         ("runtime/pmsm_dq.c", "runtime/speed_pi.c", "runtime/plant3l.c", "runtime/sim3l.c"),
         ("runtime/plant3l.h", "runtime/pmsm_dq.h", "runtime/speed_pi.h"))


def build_three_level_library(model: Model, tables: ThreeLevelTables, with_sim: bool = False) -> HostLib:
    """Render the host profile (+ the three-level closed loop), compile strictly, load (cached)."""
    files = render_three_level(model, tables, "host")
    return build_library(model.prefix, "_mpc3l", files, render_cdef(model, tables), THREE_LEVEL_RECORDS,
                         SIM3L if with_sim else None)
