"""The generated simulator API header of every topology (codegen/simulator/api.py)."""
from __future__ import annotations

import cffi
import numpy as np
import pytest

from codegen.simulator.api import render_header
from codegen.simulator.driver import trace_fields
from codegen.topologies.ttype.sim import SIM as TTYPE
from codegen.topologies.ttype.sim import Trace as TtypeTrace
from codegen.topologies.twolevel.sim import SIM as TWOLEVEL
from codegen.topologies.twolevel.sim import Trace as TwolevelTrace

CASES = [(TWOLEVEL, TwolevelTrace), (TTYPE, TtypeTrace)]


@pytest.mark.parametrize("api,trace", CASES, ids=["twolevel", "ttype"])
def test_header_is_plain_cdef_matching_the_field_lists(api, trace):
    """sim_api.h goes to ffi.cdef as is; its structs have the field lists' members, in order."""
    text = render_header(api)
    assert not any(line.lstrip().startswith("#") for line in text.splitlines())
    ffi = cffi.FFI()
    ffi.cdef(text)
    for struct in (api.params, api.state, api.trace):
        members = [name for name, _ in ffi.typeof(struct.ctype).fields]
        assert members == [m.name for m in struct.members]
        base = struct.base
        assert [name for name, _ in ffi.typeof(base.ctype).fields] == [m.name for m in base.members]
    # numpy side: the Trace class has every trace member, with the C type's width
    fields = trace_fields(api.trace)
    names = set(trace.__dataclass_fields__)
    assert set(fields) <= names and {"dt_s", "load_nm"} <= names
    for name, (dtype, _) in fields.items():
        holder = api.trace.owner(name).ctype
        ctype = dict(ffi.typeof(holder).fields)[name].type
        assert ffi.sizeof(ctype.item) == np.dtype(dtype).itemsize, name
