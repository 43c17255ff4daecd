"""Firmware projects: generated controller + runtime + board port + test data.

``write_firmware_project`` writes a self-contained, buildable directory:

    Makefile                         (templates/firmware/Makefile.j2)
    gen/<prefix>_mpc.[ch], mpc_binding.h    generated controller (render.py)
    gen/mpc_values.[ch]              record value tables, flattening and its inverse (templates/firmware/values.*.j2)
    gen/mpc_selftest_data.c          embedded states + expected outputs: canonical records as uint32 words
    firmware/runtime/...             the shared hand-written runtime
    firmware/ports/<board>/...       the board port (+ ports/cortex-m7 for Arm)

A serial protocol build (``protocol=``, written by the ``hil`` package, which
renders the protocol codec: codegen never imports hil) adds the protocol's
runtime files, its generated files and ``-DMPC_HIL``: the image then serves
the HIL protocol instead of running the self-test.

The embedded records are the canonical little-endian layout of
``codegen.records.RecordLayout`` in 32-bit words (``RecordLayout.words``,
printed by numpy in one pass: ``fwdata.c_words``); the runtime decodes them
with the value tables generated from the same layout (firmware/runtime/selftest.h).

``build_firmware`` runs ``make`` there and returns the image's size and stack
figures; a clean project whose every build input hashes as an earlier build's
gets that build's folder from the build cache instead (``codegen.cache``
entries under ``firmware/``).  Sources come from ``codegen.resources`` so the
installed package works outside a checkout.
"""
from __future__ import annotations

import hashlib
import os
import re
import shutil
import subprocess
import tarfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from codegen import __version__, cache
from codegen.errors import MpcgenError
from codegen.model import Model
from codegen.records import RecordLayout
from codegen.render import environment, write_files
from codegen.resources import firmware_dir
from codegen.stages.fwdata import (
    N_BENCH,
    SELFTEST_SEED,
    c_words,
    expected_outputs,
    in_step_format,
    layouts,
    selftest_states,
    trajectory_states,
)
from codegen.topology import topology_of

RUNTIME_FILES = ("main.c", "console.c", "console.h", "mpc_runtime.c", "mpc_runtime.h",
                 "selftest.c", "selftest.h", "port.h")
#: the core of the Cortex-M7 boards: FPv5 double-precision FPU, hard-float ABI
M7_CPU_FLAGS = ("-mcpu=cortex-m7", "-mthumb", "-mfpu=fpv5-d16", "-mfloat-abi=hard")
#: a core without FPU (Cortex-M3, qemu-m3): every float operation, if any, is libgcc's software float
M3_CPU_FLAGS = ("-mcpu=cortex-m3", "-mthumb", "-mfloat-abi=soft")
#: the flags every Arm board compiles with after its core's
ARM_COMMON_CFLAGS = ("-O2", "-ffp-contract=off", "-fno-math-errno", "-std=c99", "-Wall", "-Wextra", "-Wconversion",
                     "-Wdouble-promotion", "-Werror", "-fstack-usage", "-fcallgraph-info=su",
                     "-ffunction-sections", "-fdata-sections", "-g")
#: the Cortex-M7 boards' compiler flags (stm32h743, qemu-m7)
ARM_CFLAGS = M7_CPU_FLAGS + ARM_COMMON_CFLAGS
#: runtime files of the serial protocol (serial protocol builds only)
PROTOCOL_RUNTIME_FILES = ("hil_proto.c", "hil_proto.h", "hil_cobs.c", "hil_cobs.h", "hil_wire.c", "hil_wire.h",
                          "onboard.c", "onboard.h")
HOST_CFLAGS = ("-O2", "-ffp-contract=off", "-fno-math-errno", "-std=c99", "-Wall", "-Wextra",
               "-Wconversion", "-Wdouble-promotion", "-Werror", "-fstack-usage", "-g")


@dataclass(frozen=True)
class ProtocolBuild:
    """A serial protocol build: its generated files (project-relative path -> text) and C define."""

    files: dict[str, str]
    define: str = "MPC_HIL"


def full_record(inp: RecordLayout, out: RecordLayout) -> int:
    """Octets of one embedded state with its full expected outputs (canonical records in 32-bit words)."""
    return 4 * (inp.word_count + out.word_count)


def compact_record(inp: RecordLayout) -> int:
    """Octets of one embedded state with a CRC-32 of its expected outputs."""
    return 4 * inp.word_count + 4


class FirmwareError(MpcgenError):
    """A firmware project cannot be written or built."""


class ToolchainError(FirmwareError):
    """A tool the build or emulation needs is not installed."""


@dataclass(frozen=True)
class Tool:
    """An executable and what to install to get it."""

    exe: str
    install: str  # one-line hint naming the package


#: Default -icount shift of the emulated board: 25.6 SysTick ticks per instruction.
ICOUNT_SHIFT = 10


def qemu_command(elf: str | Path, serial: str, icount_shift: int = ICOUNT_SHIFT,
                 machine: tuple[str, str] = ("mps2-an500", "cortex-m7")) -> list[str]:
    """An emulated board's QEMU command line: ``machine`` (QEMU machine, CPU; default the qemu-m7
    board's mps2-an500 Cortex-M7), headless, semihosting exit, -icount (instructions counted by
    SysTick), UART0 to ``serial`` (``stdio``, ``file:PATH``, ...)."""
    return ["qemu-system-arm", "-M", machine[0], "-cpu", machine[1], "-m", "16M",
            "-display", "none", "-monitor", "none",
            "-semihosting-config", "enable=on,target=native",
            "-icount", f"shift={icount_shift}", "-kernel", str(elf), "-serial", serial]


@dataclass(frozen=True)
class Board:
    """What differs between boards in a project."""

    name: str
    profile: str  # render.PROFILES key of the generated controller
    kind: str  # "arm" | "host" | "c28x"
    port_dirs: tuple[str, ...]
    linker_script: str
    data_budget: int | None  # octets available to the embedded test data
    tools: tuple[Tool, ...]
    doc: str
    run: str = ""  # `make run` command line (empty: the board has no run target)
    cpu_flags: tuple[str, ...] = M7_CPU_FLAGS  # Arm: the core's compiler and linker flags
    qemu: tuple[str, str] | None = None  # an emulated board's QEMU (machine, cpu)
    #: Arm: the port folder holding stackdepth.sh, and the function the stack depth is counted from
    stack_dir: str = "cortex-m7"
    stack_root: str = "Reset_Handler"
    #: files of other port folders the project needs (``folder/name``: a shared script)
    extra_files: tuple[str, ...] = ()


ARM_GCC = Tool("arm-none-eabi-gcc", "install the Debian packages gcc-arm-none-eabi and libnewlib-arm-none-eabi "
               "(apt-get install gcc-arm-none-eabi libnewlib-arm-none-eabi)")
MAKE = Tool("make", "install the Debian package make (apt-get install make)")
QEMU = Tool("qemu-system-arm", "install the Debian package qemu-system-arm (apt-get install qemu-system-arm)")
HOST_GCC = Tool("gcc", "install the Debian package gcc (apt-get install gcc)")
CL2000 = Tool("cl2000", "TI's C2000 code generation tools are not packaged by Debian: install Code Composer "
              "Studio or the C2000 CGT and put cl2000 on PATH (or set C2000_CGT_ROOT)")

#: the emulated Cortex-M7 (QEMU mps2-an500): the board of ``bench --emulated`` and of ``hil --board``
EMULATED_BOARD = "qemu-m7"
#: the emulated core without FPU (QEMU mps2-an385, Cortex-M3, -mfloat-abi=soft): fixed point's board
NOFPU_BOARD = "qemu-m3"
_QEMU_M7 = ("mps2-an500", "cortex-m7")
_QEMU_M3 = ("mps2-an385", "cortex-m3")

#: every board a firmware project is written for, by name (its port folder under firmware/ports/)
BOARDS: dict[str, Board] = {b.name: b for b in (
    Board("stm32h743", "stm32h743", "arm", ("cortex-m7", "stm32h743"), "stm32h743.ld",
          1792 * 1024, (ARM_GCC, MAKE), "NUCLEO-H743ZI2, 400 MHz, step in ITCM, tables in DTCM"),
    Board(EMULATED_BOARD, "stm32h743", "arm", ("cortex-m7", "qemu-mps2", EMULATED_BOARD), "qemu_m7.ld",
          3584 * 1024, (ARM_GCC, MAKE, QEMU), "QEMU mps2-an500 emulated Cortex-M7",
          " ".join(qemu_command("$(IMAGE)", "stdio", machine=_QEMU_M7)), qemu=_QEMU_M7),
    # no tightly coupled memories and no FPU: the host profile's C (no placement attributes)
    Board(NOFPU_BOARD, "host", "arm", ("qemu-mps2", NOFPU_BOARD), "qemu_m3.ld", 3584 * 1024, (ARM_GCC, MAKE, QEMU),
          "QEMU mps2-an385 emulated Cortex-M3, no FPU (-mfloat-abi=soft)",
          " ".join(qemu_command("$(IMAGE)", "stdio", machine=_QEMU_M3)), M3_CPU_FLAGS, _QEMU_M3,
          NOFPU_BOARD, "m3_reset", ("cortex-m7/stackdepth.sh",)),
    Board("tms320f28377", "tms320f28377", "c28x", ("tms320f28377",), "f28377s.cmd",
          448 * 1024, (CL2000,), "LAUNCHXL-F28377S, C28x + FPU32 at 200 MHz"),
    Board("host", "host", "host", ("host",), "", None, (HOST_GCC, MAKE),
          "host program (sanitizer builds)", "./$(IMAGE)"),
)}


def board_spec(board: str) -> Board:
    """The Board named ``board``; MpcgenError (one line) for any other name."""
    try:
        return BOARDS[board]
    except (KeyError, TypeError):
        raise FirmwareError(f"unknown board {board!r}: choose one of {', '.join(BOARDS)}") from None


def require_tools(tools: tuple[Tool, ...]) -> None:
    """Raise ToolchainError (one line, naming the package) for the first missing tool."""
    for tool in tools:
        if shutil.which(tool.exe) is None:
            raise ToolchainError(f"{tool.exe} not found: {tool.install}")
        if tool is ARM_GCC:
            r = subprocess.run([tool.exe, "-print-file-name=libc_nano.a"], capture_output=True, text=True)
            if "/" not in r.stdout:
                raise ToolchainError(f"newlib for {tool.exe} not found: {tool.install}")


@dataclass
class TestSet:
    """One embedded set of states with its expected outputs (template context)."""

    name: str
    doc: str
    states: np.ndarray
    expected: np.ndarray
    dump: bool
    inp: RecordLayout
    out: RecordLayout
    full: bool = True

    def context(self, suffix: str = "u") -> dict[str, Any]:
        """Values the template prints: the records' canonical words as initializer text (one numpy
        pass each, :func:`~codegen.stages.fwdata.c_words`; ``suffix``: of the board's uint32_t)."""
        ctx: dict[str, Any] = {"name": self.name, "doc": self.doc, "n": len(self.states), "dump": self.dump,
                               "full": self.full, "states_words": c_words(self.inp.words(self.states), suffix=suffix)}
        if self.full:
            ctx["expected_words"] = c_words(self.out.words(self.expected), suffix=suffix)
        else:
            ctx["expected_crc_words"] = c_words(np.array(self.out.record_crcs(self.expected), np.uint32),
                                                suffix=suffix)
        return ctx


def make_test_sets(model: Model, t: Any, n_selftest: int, n_bench: int,
                   seed: int = SELFTEST_SEED, dump_selftest: bool = False) -> list[TestSet]:
    """The self-test set and (if n_bench > 0) the bench trajectory, with reference outputs
    (``dump_selftest``: the image prints the self-test set's per-state cycles too, as the bench set's)."""
    topo = topology_of(model)
    inp, out = layouts(model)
    x = selftest_states(model, t, n_selftest, seed)
    sets = [TestSet("selftest", f"{len(x)} guard and random states (seed {seed})", x,
                    expected_outputs(topo, t, x), dump_selftest, inp, out)]
    if n_bench > 0:
        b = in_step_format(model, t, trajectory_states(model, n_bench))
        sets.append(TestSet("bench", f"{len(b)} {topo.trajectory_doc}", b, expected_outputs(topo, t, b),
                            True, inp, out))
    return sets


#: suffix of a constant of the board's uint32_t, by board kind (the embedded words are constants of
#: exactly that type, so the compiler converts none of them: arm-none-eabi-gcc's and cl2000's uint32_t
#: is unsigned long, the host's unsigned int)
UINT32_SUFFIX = {"arm": "ul", "c28x": "ul", "host": "u"}

#: the runtime function building a record member from its 32-bit value, by value kind (firmware/runtime/mpc_runtime.h)
VALUE_WRITERS = {"MPC_VALUE_F32": "mpc_f32_from_bits", "MPC_VALUE_I32": "mpc_i32_from_value",
                 "MPC_VALUE_U16": "mpc_u16_from_value"}


@dataclass(frozen=True)
class ValueEntry:
    """One row of a record's value table (templates/firmware/values.c.j2): member, kind, the runtime's
    reader (member -> 32 bits) and writer (32 bits -> member), octet offset in the canonical layout."""

    name: str
    kind: str
    reader: str
    writer: str
    offset: int


def value_table(layout: RecordLayout) -> list[ValueEntry]:
    """The value table of ``layout``, derived from its fields (``values``, ``value_offsets``); a value
    the runtime cannot hold (not 2 or 4 octets, e.g. float64) is a FirmwareError."""
    rows = []
    for v, off in zip(layout.values, layout.value_offsets):
        if v.kind not in VALUE_WRITERS:
            raise FirmwareError(f"{layout.record.name}.{v.name}: a {v.kind} value has no firmware representation "
                                f"(the firmware runtime holds float32, int32 and uint16 values)")
        rows.append(ValueEntry(v.name, v.kind, v.reader, VALUE_WRITERS[v.kind], off))
    return rows


def _fit_budget(board: Board, sets: list[TestSet]) -> None:
    if not sets:
        return
    n = sum(len(s.states) for s in sets)
    inp, out = sets[0].inp, sets[0].out
    if board.data_budget is None or n * full_record(inp, out) <= board.data_budget:
        return
    if n * compact_record(inp) > board.data_budget:
        raise FirmwareError(f"{board.name}: {n} test states need {n * compact_record(inp)} octets even with "
                            f"compact expected outputs, the board has {board.data_budget}: lower n_selftest")
    for s in sets:
        s.full = False


def _sources(board: Board, outdir: Path, prefix: str, protocol: ProtocolBuild | None = None) -> list[str]:
    srcs = [f"gen/{prefix}_mpc.c", "gen/mpc_values.c", "gen/mpc_selftest_data.c"]
    srcs += [f"firmware/runtime/{f}" for f in RUNTIME_FILES if f.endswith(".c")]
    if protocol is not None:
        srcs += sorted(f for f in protocol.files if f.endswith(".c"))
        srcs += [f"firmware/runtime/{f}" for f in PROTOCOL_RUNTIME_FILES if f.endswith(".c")]
    for d in board.port_dirs:
        srcs += sorted(str(p.relative_to(outdir)) for p in (outdir / "firmware/ports" / d).glob("*.c"))
    return srcs


def write_firmware_project(model: Model, tables: Any, board: str, outdir: Path,
                           n_selftest: int = 10000, *, n_bench: int = N_BENCH,
                           seed: int = SELFTEST_SEED, protocol: ProtocolBuild | None = None,
                           dump_selftest: bool = False) -> list[Path]:
    """Write a buildable firmware project for ``board`` into ``outdir``; return the files written.

    The controller is rendered with the board's target profile, the
    self-test states and the bench trajectory are embedded with the Python
    reference's outputs (compact per-state CRCs where the full records do not
    fit the board), and a Makefile (C2000: Makefile + build.sh) is written.
    Either topology: ``model.inverter.topology`` picks the controller, the
    records, the reference and the test states (``codegen.fwdata.Topology``);
    ``tables`` are TwoLevelTables or ThreeLevelTables to match.  ``protocol``:
    a serial protocol build (see the module docstring).  ``dump_selftest``: the image prints every
    self-test state's cycles (CYC lines), as it does the bench set's.
    """
    spec = board_spec(board)
    topo = topology_of(model)
    if n_selftest < 1:
        raise FirmwareError(f"n_selftest must be >= 1, got {n_selftest}")
    outdir = Path(outdir)
    inp, out = layouts(model)
    input_values, output_values = value_table(inp), value_table(out)  # refused before any work
    sets = make_test_sets(model, tables, n_selftest, n_bench, seed, dump_selftest)
    _fit_budget(spec, sets)
    fw = firmware_dir()
    files: dict[str, str] = {f"gen/{k}": v for k, v in topo.render(model, tables, spec.profile).items()}
    for f in RUNTIME_FILES + (PROTOCOL_RUNTIME_FILES if protocol is not None else ()):
        files[f"firmware/runtime/{f}"] = (fw / "runtime" / f).read_text()
    if protocol is not None:
        files.update(protocol.files)
    for d in spec.port_dirs:
        for p in sorted((fw / "ports" / d).iterdir()):
            if p.is_file():
                files[f"firmware/ports/{d}/{p.name}"] = p.read_text()
    for f in spec.extra_files:
        files[f"firmware/ports/{spec.stack_dir}/{Path(f).name}"] = (fw / "ports" / f).read_text()
    env = environment()
    ctx = {"model_name": model.name, "config_hash": model.config_hash(), "version": __version__,
           "board": spec.name, "strategy": tables.strategy, "prefix": model.prefix,
           "input_values": input_values, "output_values": output_values,
           "input_words": inp.word_count, "output_words": out.word_count,
           "input_octets": inp.packed_dtype.itemsize, "output_octets": out.packed_dtype.itemsize,
           "input_bits": inp.dtype.itemsize * 8, "output_bits": out.dtype.itemsize * 8,
           "reference": topo.reference,
           "states_doc": "; ".join(s.doc for s in sets),
           "sets": [s.context(UINT32_SUFFIX[spec.kind]) for s in sets]}
    files["gen/mpc_values.h"] = env.get_template("firmware/values.h.j2").render(ctx)
    files["gen/mpc_values.c"] = env.get_template("firmware/values.c.j2").render(ctx)
    files["gen/mpc_selftest_data.c"] = env.get_template("firmware/selftest_data.c.j2").render(ctx)
    written = write_files(files, outdir)
    mk = {"board": spec, "sources": _sources(spec, outdir, model.prefix, protocol), "arm_cflags": spec.cpu_flags + ARM_COMMON_CFLAGS,
          "defines": [protocol.define] if protocol is not None else [],
          "host_cflags": HOST_CFLAGS, "includes": ["gen", "firmware/runtime",
                                                   *[f"firmware/ports/{d}" for d in spec.port_dirs]],
          "model_name": model.name, "config_hash": model.config_hash(), "version": __version__}
    written += write_files({"Makefile": env.get_template("firmware/Makefile.j2").render(mk)}, outdir)
    return written


@dataclass
class BuildResult:
    """A built image and its figures (Arm boards: from arm-none-eabi-size and the .su/.ci files)."""

    project: Path
    image: Path
    log: str
    text: int = 0
    data: int = 0
    bss: int = 0
    max_frame: int = 0
    max_frame_function: str = ""
    stack_path: list[str] = field(default_factory=list)
    stack_depth: int = 0
    #: the build cache entry the build folder was restored from (None: built by make here)
    reused: Path | None = None


#: the build cache's folder of built firmware (one sealed entry per inputs hash, codegen.cache)
IMAGE_CACHE = "firmware"
#: the entry's archive of the project's build/ folder (its seal's payload) and its make log
_ARCHIVE, _LOG = "build.tar.gz", "build.json"
#: environment variables that change what the compiler or make read
_BUILD_ENV = ("CPATH", "C_INCLUDE_PATH", "LIBRARY_PATH", "GCC_EXEC_PREFIX", "COMPILER_PATH", "MAKEFLAGS")


def compiler_identity(compiler: str) -> str:
    """The compiler's resolved path and its ``--version`` text (the package's version and revision)."""
    path = shutil.which(compiler) or compiler
    r = subprocess.run([path, "--version"], capture_output=True, text=True)
    return f"{path}\n{r.stdout}{r.stderr}"


def build_inputs_hash(project: Path, board: str, make_vars: dict[str, str] | None = None) -> str:
    """SHA-256 (hex, 32 characters) of everything a build of ``project`` for ``board`` depends on: every
    file of the project outside ``build/`` (sources, headers, Makefile with the compiler flags, linker
    script, scripts: path and content), the ``make`` variables, the compiler's identity
    (:func:`compiler_identity`; ``CC`` of ``make_vars`` if given) and the environment variables that
    change what the compiler reads."""
    spec = board_spec(board)
    project = Path(project)
    make_vars = dict(make_vars or {})
    cc = make_vars.get("CC") or ("arm-none-eabi-gcc" if spec.kind == "arm" else "gcc")
    h = hashlib.sha256()
    for part in (cache.LAYOUT, IMAGE_CACHE, board, repr(sorted(make_vars.items())), compiler_identity(cc),
                 repr([(k, os.environ.get(k)) for k in _BUILD_ENV])):
        h.update(part.encode() + b"\0")
    files = sorted(p for p in project.rglob("*") if p.is_file()
                   and not re.fullmatch(r"build(\.tmp\d+)?", p.relative_to(project).parts[0]))
    for p in files:
        h.update(p.relative_to(project).as_posix().encode() + b"\0")
        h.update(hashlib.sha256(p.read_bytes()).digest())
    return h.hexdigest()[:32]


def _entry(board: str, key: str) -> Path:
    return cache.cache_root() / IMAGE_CACHE / f"{board}-{key}"


def _restore(entry: Path, project: Path) -> str | None:
    """Unpack the entry's build folder into ``project``; its make log, or None (a damaged entry is
    reported in one warning line and removed)."""
    damaged = cache.sealed_ok(entry, entry / _ARCHIVE)
    meta = cache.read_json(entry / _LOG) if damaged is None else None
    if damaged is None and (not isinstance(meta, dict) or not isinstance(meta.get("log"), str)):
        damaged = "no build log"
    if damaged is not None:
        cache.warn(f"cache entry {entry} is damaged ({damaged}); rebuilding it")
        cache.discard(entry)
        return None
    assert isinstance(meta, dict)
    tmp = project / f"build.tmp{os.getpid()}"
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir()
    try:
        with tarfile.open(entry / _ARCHIVE, "r:gz") as tar:
            members = tar.getmembers()
            if any(m.name.startswith(("/", "..")) or ".." in Path(m.name).parts or not (m.isfile() or m.isdir())
                   for m in members):
                raise tarfile.TarError("a member outside the build folder")
            if hasattr(tarfile, "data_filter"):  # Python 3.11.4+: refuse anything outside the folder too
                tar.extractall(tmp, members, filter="data")
            else:  # pragma: no cover - older Python 3.11
                tar.extractall(tmp, members)
        # every file as new as the sources just written: make takes the restored build as up to date
        now = time.time()
        for p in tmp.rglob("*"):
            os.utime(p, (now, now))
        os.replace(tmp / "build", project / "build")
    except (tarfile.TarError, OSError, EOFError) as exc:
        cache.warn(f"cache entry {entry} is damaged ({exc}); rebuilding it")
        cache.discard(entry)
        shutil.rmtree(project / "build", ignore_errors=True)
        return None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return str(meta["log"])


def _store(entry: Path, project: Path, log: str) -> None:
    """The project's build folder and make log as a sealed cache entry (written aside, renamed into place)."""
    tmp = entry.with_name(f"{entry.name}.tmp{os.getpid()}")
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir(parents=True)
    try:
        with tarfile.open(tmp / _ARCHIVE, "w:gz", compresslevel=1) as tar:
            tar.add(project / "build", arcname="build")
        cache.write_json(tmp / _LOG, {"log": log})
        cache.seal(tmp, tmp / _ARCHIVE)
        os.replace(tmp, entry)
    except OSError:  # another process stored the same inputs first (or the cache is full): keep going
        pass
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _figures(res: BuildResult) -> BuildResult:
    log = res.log
    m = re.search(r"^\s*(\d+)\s+(\d+)\s+(\d+)\s+\d+\s+[0-9a-f]+\s+\S*fw", log, re.M)
    if m:
        res.text, res.data, res.bss = (int(g) for g in m.groups())
    m = re.search(r"largest frame (\d+) bytes in (\S+)", log)
    if m:
        res.max_frame, res.max_frame_function = int(m.group(1)), m.group(2)
    m = re.search(r"worst depth (\d+) bytes from \S+: (.*)$", log, re.M)
    if m:
        res.stack_depth, res.stack_path = int(m.group(1)), m.group(2).split(" > ")
    return res


def build_firmware(project: Path, board: str, *, make_vars: dict[str, str] | None = None,
                   timeout_s: float = 600, reuse: bool = True,
                   log: Callable[[str], None] | None = None) -> BuildResult:
    """Run ``make`` in ``project``; FirmwareError with the compiler output on failure.

    Built images are cached by content hash (``reuse``, Arm and host boards): a project without a
    ``build/`` folder whose inputs hash (:func:`build_inputs_hash`: every source, the Makefile and its
    flags, the make variables, the compiler's version) names a cache entry gets that entry's
    ``build/`` folder (image, objects, stack files, map; as new as the sources, so a later ``make``
    has nothing to do) and make log instead of a build, with a line to ``log`` and
    ``BuildResult.reused`` set; otherwise make builds, and a build from a clean folder is stored.  A
    project that already has a ``build/`` folder is always left to make (an incremental build: the
    folder may hold objects compiled otherwise)."""
    spec = board_spec(board)
    require_tools(spec.tools + ((MAKE,) if spec.kind == "c28x" else ()))
    project = Path(project)
    image = project / "build" / ("fw" if spec.kind == "host" else "fw.elf" if spec.kind == "arm" else "fw.out")
    entry = None
    if reuse and spec.kind in ("arm", "host") and not (project / "build").exists():
        key = build_inputs_hash(project, board, make_vars)
        entry = _entry(board, key)
        if entry.is_dir():
            old = _restore(entry, project)
            if old is not None and image.is_file():
                line = (f"reused the {board} image built from identical inputs (sources, Makefile, flags, "
                        f"compiler; inputs hash {key[:12]}): cache entry {entry}")
                if log is not None:
                    log(f"    {line}")
                return _figures(BuildResult(project, image, f"mpcgen: {line}\n{old}", reused=entry))
            shutil.rmtree(project / "build", ignore_errors=True)
    cmd = ["make", "-C", str(project), *[f"{k}={v}" for k, v in (make_vars or {}).items()]]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout_s)
    out = r.stdout + r.stderr
    if r.returncode != 0:
        raise FirmwareError(f"building the {board} firmware in {project} failed:\n{out}")
    if entry is not None and image.is_file():
        _store(entry, project, out)
    return _figures(BuildResult(project, image, out))
