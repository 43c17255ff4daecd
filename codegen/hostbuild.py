"""Host build of the generated C through cffi (render -> compile -> load).

The generated controller and the hand-written runtime are compiled with the
same strictness as the target builds (``STRICT_CFLAGS``, -Werror) into object
files by a direct compiler call; cffi then links them into an extension
module (its own glue is compiled with cffi's default flags, since it is not
ours to make -Wconversion clean).  Builds are cached by a hash of every
input byte, so a rebuilt config reuses its library.
"""
from __future__ import annotations

import hashlib
import importlib.util
import os
import shutil
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

import cffi

from codegen import cache
from codegen.cache import cache_root
from codegen.errors import MpcgenError
from codegen.model import Model
from codegen.numfmt import NumberFormat
from codegen.records import Record, RecordLayout
from codegen.render import write_files

#: Flags every build of generated C uses (README "Standards", numerics.md).
STRICT_CFLAGS: tuple[str, ...] = (
    "-std=c99", "-O2", "-Wall", "-Wextra", "-Wconversion", "-Wdouble-promotion", "-Werror",
    "-ffp-contract=off", "-fno-math-errno",
)


class BuildError(MpcgenError):
    """The C compiler failed or is missing."""


@dataclass(frozen=True)
class Records:
    """The step's input and output records, bound to the step's number format."""

    input: RecordLayout
    output: RecordLayout


@dataclass(frozen=True)
class SimSources:
    """The closed-loop simulator compiled beside the step: cffi API header, C sources, other headers."""

    api: Path
    sources: tuple[Path, ...]
    headers: tuple[Path, ...]


@dataclass(frozen=True)
class HostLib:
    """A loaded host build: cffi ``ffi`` and ``lib`` plus where it was built."""

    ffi: Any
    lib: Any
    build_dir: Path
    prefix: str
    has_sim: bool
    records: Records

    def step_batch(self, states: Any) -> Any:
        """Run the compiled step over an array of input records; return output records."""
        import numpy as np

        states = np.ascontiguousarray(states, dtype=self.records.input.dtype)
        out = np.zeros(len(states), self.records.output.dtype)
        fn = getattr(self.lib, f"{self.prefix}_step_batch")
        pin = self.ffi.cast(f"{self.prefix}_input_t *", self.ffi.from_buffer(states))
        pout = self.ffi.cast(f"{self.prefix}_output_t *", self.ffi.from_buffer(out))
        fn(pin, pout, len(states))
        return out


def compiler() -> str:
    """The host C compiler (CC or gcc); a clear error if there is none."""
    cc = os.environ.get("CC", "gcc")
    if shutil.which(cc) is None:
        raise BuildError(f"host C compiler '{cc}' not found: install gcc (apt-get install gcc) or set CC")
    return cc


def compile_object(src: Path, obj: Path, include_dirs: list[Path], extra: tuple[str, ...] = ()) -> None:
    """Compile one C file with STRICT_CFLAGS (+ -fPIC); raise BuildError with the diagnostics."""
    cmd = [compiler(), *STRICT_CFLAGS, "-fPIC", *extra, *[f"-I{d}" for d in include_dirs], "-c", str(src), "-o", str(obj)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise BuildError(f"compiling {src.name} failed:\n{' '.join(cmd)}\n{r.stderr}")


def build_library(prefix: str, tag: str, files: dict[str, str], cdef: str, records: Records,
                  sim: SimSources | None = None) -> HostLib:
    """Compile the rendered step (+ the optional closed-loop simulator), link with cffi, load.

    Cached by a hash of every input byte.
    """
    api = sim.api.read_text() if sim else ""
    key_src = [cache.LAYOUT, cdef, api, " ".join(STRICT_CFLAGS), cffi.__version__, sys.version]
    key_src += [files[k] for k in sorted(files)]
    if sim:
        key_src += [p.read_text() for p in (*sim.sources, *sim.headers)]
    key = hashlib.sha256("\0".join(key_src).encode()).hexdigest()[:16]
    modname = f"{tag}_{prefix}_{key}"
    bdir = cache_root() / modname
    so = _find_module(bdir, modname)
    damaged = cache.sealed_ok(bdir, so) if so is not None and modname not in sys.modules else None
    if damaged is not None:  # a truncated or edited library would crash the process when loaded
        cache.warn(f"cache entry {bdir} is damaged ({damaged}); rebuilding it")
        cache.discard(bdir)
        so = None
    if so is None:
        # build in a private directory, then rename: parallel test workers may race
        tmp = bdir.with_name(f"{modname}.tmp{os.getpid()}")
        shutil.rmtree(tmp, ignore_errors=True)
        tmp.mkdir(parents=True)
        write_files(files, tmp)
        sources = [tmp / f"{prefix}_mpc.c"] + (list(sim.sources) if sim else [])
        incdirs = [tmp] + (sorted({p.parent for p in (*sim.sources, *sim.headers)}) if sim else [])
        objs = []
        for src in sources:
            obj = tmp / (src.stem + ".o")
            compile_object(src, obj, incdirs)
            objs.append(str(obj))
        ffi = cffi.FFI()
        ffi.cdef(cdef + "\n" + api)
        includes = '#include "mpc_binding.h"\n' + (f'#include "{sim.api.name}"\n' if sim else "")
        ffi.set_source(modname, includes, include_dirs=[str(d) for d in incdirs],
                       extra_objects=objs, libraries=["m"])
        try:
            ffi.compile(tmpdir=str(tmp), verbose=False)
        except Exception as exc:  # cffi raises distutils/setuptools errors
            raise BuildError(f"linking the cffi module {modname} failed: {exc}") from exc
        built = _find_module(tmp, modname)
        if built is None:
            raise BuildError(f"cffi produced no module in {tmp}")
        cache.seal(tmp, built)
        try:
            os.replace(tmp, bdir)
        except OSError:  # another process finished first: use its build
            shutil.rmtree(tmp, ignore_errors=True)
        so = _find_module(bdir, modname)
        if so is None:
            raise BuildError(f"cffi produced no module in {bdir}")
    mod = _load(modname, so)
    lib = HostLib(mod.ffi, mod.lib, bdir, prefix, sim is not None, records)
    _check_layout(lib)
    return lib


def _find_module(bdir: Path, modname: str) -> Path | None:
    if not bdir.is_dir():
        return None
    hits = sorted(bdir.glob(f"{modname}*.so")) + sorted(bdir.glob(f"{modname}*.pyd"))
    return hits[0] if hits else None


def _load(modname: str, path: Path) -> ModuleType:
    if modname in sys.modules:
        return sys.modules[modname]
    spec = importlib.util.spec_from_file_location(modname, path)
    assert spec and spec.loader
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    sys.modules[modname] = mod
    return mod


def _check_layout(lib: HostLib) -> None:
    """The numpy records must match the C structs byte for byte."""
    ffi, p, r = lib.ffi, lib.prefix, lib.records
    for ctype, layout in ((f"{p}_input_t", r.input), (f"{p}_output_t", r.output)):
        dtype = layout.dtype
        assert dtype.fields is not None
        if ffi.sizeof(ctype) != dtype.itemsize:
            raise BuildError(f"{ctype}: C size {ffi.sizeof(ctype)} != numpy {dtype.itemsize}")
        for f in layout.fields:
            if ffi.offsetof(ctype, f.name) != dtype.fields[f.name][1]:
                raise BuildError(f"{ctype}.{f.name}: C offset differs from numpy")


def build_step_library(model: Model, tag: str, files: dict[str, str], cdef: str, records: tuple[Record, Record],
                       sim: Callable[[], SimSources] | None, nf: NumberFormat) -> HostLib:
    """A topology's host build: its rendered step (host profile) and cffi ``cdef``, its (input,
    output) records bound to the step's number format ``nf`` (the derived tables', with its scaling),
    + the closed-loop simulator ``sim()`` gives."""
    return build_library(model.prefix, tag, files, cdef, Records(records[0].bind(nf), records[1].bind(nf)),
                         sim() if sim is not None else None)
