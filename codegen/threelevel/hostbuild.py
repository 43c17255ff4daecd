"""Host build of the generated three-level C through cffi (render -> compile -> load).

Same scheme as ``codegen.hostbuild`` (whose helpers it reuses): the
generated step is compiled with ``STRICT_CFLAGS`` (-Werror) into an object by
a direct compiler call, cffi links it into an extension module, builds are
cached by a hash of every input byte.  No plant simulator is linked here.
"""
from __future__ import annotations

import hashlib
import os
import shutil
import sys

import cffi

from ..hostbuild import STRICT_CFLAGS, BuildError, HostLib, _find_module, _load, cache_root, compile_object
from ..model import Model
from ..render import write_files
from .derive import ThreeLevelTables
from .interface import INPUT_DTYPE, INPUT_FIELDS, OUTPUT_DTYPE, OUTPUT_FIELDS
from .render import render_cdef, render_three_level


class ThreeLevelHostLib(HostLib):
    """HostLib whose batch call uses the three-level records."""

    def step_batch(self, states):  # type: ignore[override]
        import numpy as np

        states = np.ascontiguousarray(states, dtype=INPUT_DTYPE)
        out = np.zeros(len(states), OUTPUT_DTYPE)
        fn = getattr(self.lib, f"{self.prefix}_step_batch")
        pin = self.ffi.cast(f"{self.prefix}_input_t *", self.ffi.from_buffer(states))
        pout = self.ffi.cast(f"{self.prefix}_output_t *", self.ffi.from_buffer(out))
        fn(pin, pout, len(states))
        return out


def build_three_level_library(model: Model, tables: ThreeLevelTables) -> HostLib:
    """Render the host profile, compile strictly, link with cffi, load (cached)."""
    files = render_three_level(model, tables, "host")
    cdef = render_cdef(model, tables)
    key_src = [cdef, " ".join(STRICT_CFLAGS), cffi.__version__, sys.version]
    key_src += [files[k] for k in sorted(files)]
    key = hashlib.sha256("\0".join(key_src).encode()).hexdigest()[:16]
    modname = f"_mpc3l_{model.prefix}_{key}"
    bdir = cache_root() / modname
    so = _find_module(bdir, modname)
    if so is None:
        tmp = bdir.with_name(f"{modname}.tmp{os.getpid()}")
        shutil.rmtree(tmp, ignore_errors=True)
        tmp.mkdir(parents=True)
        write_files(files, tmp)
        obj = tmp / f"{model.prefix}_mpc.o"
        compile_object(tmp / f"{model.prefix}_mpc.c", obj, [tmp])
        ffi = cffi.FFI()
        ffi.cdef(cdef)
        ffi.set_source(modname, '#include "mpc_binding.h"\n', include_dirs=[str(tmp)],
                       extra_objects=[str(obj)], libraries=["m"])
        try:
            ffi.compile(tmpdir=str(tmp), verbose=False)
        except Exception as exc:  # cffi raises distutils/setuptools errors
            raise BuildError(f"linking the cffi module {modname} failed: {exc}") from exc
        try:
            os.replace(tmp, bdir)
        except OSError:  # another process finished first: use its build
            shutil.rmtree(tmp, ignore_errors=True)
        so = _find_module(bdir, modname)
        if so is None:
            raise BuildError(f"cffi produced no module in {bdir}")
    mod = _load(modname, so)
    lib = ThreeLevelHostLib(mod.ffi, mod.lib, bdir, model.prefix, False)
    _check_layout(lib)
    return lib


def _check_layout(lib: HostLib) -> None:
    """The numpy records must match the C structs byte for byte."""
    ffi, p = lib.ffi, lib.prefix
    for ctype, dtype, fields in ((f"{p}_input_t", INPUT_DTYPE, INPUT_FIELDS), (f"{p}_output_t", OUTPUT_DTYPE, OUTPUT_FIELDS)):
        if ffi.sizeof(ctype) != dtype.itemsize:
            raise BuildError(f"{ctype}: C size {ffi.sizeof(ctype)} != numpy {dtype.itemsize}")
        for f in fields:
            if ffi.offsetof(ctype, f.name) != dtype.fields[f.name][1]:
                raise BuildError(f"{ctype}.{f.name}: C offset differs from numpy")
