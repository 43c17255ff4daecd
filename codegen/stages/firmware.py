"""Firmware projects: generated controller + runtime + board port + test data.

``write_firmware_project`` writes a self-contained, buildable directory:

    Makefile                         (templates/firmware/Makefile.j2)
    gen/<prefix>_mpc.[ch], mpc_binding.h    generated controller (render.py)
    gen/mpc_values.[ch]              record flattening (templates/firmware/values.*.j2)
    gen/mpc_selftest_data.c          embedded states + expected outputs
    firmware/runtime/...             the shared hand-written runtime
    firmware/ports/<board>/...       the board port (+ ports/cortex-m7 for Arm)

A serial protocol build (``protocol=``, written by the ``hil`` package, which
renders the protocol codec: codegen never imports hil) adds the protocol's
runtime files, its generated files and ``-DMPC_HIL``: the image then serves
the HIL protocol instead of running the self-test.

``build_firmware`` runs ``make`` there and returns the image's size and stack
figures.  Sources come from ``codegen.resources`` so the installed package
works outside a checkout.
"""
from __future__ import annotations

import re
import shutil
import subprocess
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from codegen import __version__
from codegen.errors import MpcgenError
from codegen.model import Model
from codegen.records import REAL, RecordLayout
from codegen.render import environment, write_files
from codegen.resources import firmware_dir
from codegen.stages.fwdata import (
    N_BENCH,
    SELFTEST_SEED,
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
    """Octets of one embedded state with its full expected outputs."""
    return inp.dtype.itemsize + out.dtype.itemsize


def compact_record(inp: RecordLayout) -> int:
    """Octets of one embedded state with a CRC-32 of its expected outputs."""
    return inp.dtype.itemsize + 4


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
    Board(EMULATED_BOARD, "stm32h743", "arm", ("cortex-m7", EMULATED_BOARD), "qemu_m7.ld",
          3584 * 1024, (ARM_GCC, MAKE, QEMU), "QEMU mps2-an500 emulated Cortex-M7",
          " ".join(qemu_command("$(IMAGE)", "stdio", machine=_QEMU_M7)), qemu=_QEMU_M7),
    # no tightly coupled memories and no FPU: the host profile's C (no placement attributes)
    Board(NOFPU_BOARD, "host", "arm", (NOFPU_BOARD,), "qemu_m3.ld", 3584 * 1024, (ARM_GCC, MAKE, QEMU),
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

    def context(self) -> dict[str, Any]:
        """Values the template prints."""
        ctx = {"name": self.name, "doc": self.doc, "n": len(self.states), "dump": self.dump,
               "full": self.full, "states": self.inp.rows(self.states)}
        if self.full:
            ctx["expected"] = self.out.rows(self.expected)
        else:
            ctx["expected_crc"] = self.out.record_crcs(self.expected)
        return ctx


def make_test_sets(model: Model, t: Any, n_selftest: int, n_bench: int,
                   seed: int = SELFTEST_SEED) -> list[TestSet]:
    """The self-test set and (if n_bench > 0) the bench trajectory, with reference outputs."""
    topo = topology_of(model)
    inp, out = layouts(model)
    x = selftest_states(model, t, n_selftest, seed)
    sets = [TestSet("selftest", f"{len(x)} guard and random states (seed {seed})", x,
                    expected_outputs(topo, t, x), False, inp, out)]
    if n_bench > 0:
        b = in_step_format(model, t, trajectory_states(model, n_bench))
        sets.append(TestSet("bench", f"{len(b)} {topo.trajectory_doc}", b, expected_outputs(topo, t, b),
                            True, inp, out))
    return sets


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
                           seed: int = SELFTEST_SEED, protocol: ProtocolBuild | None = None) -> list[Path]:
    """Write a buildable firmware project for ``board`` into ``outdir``; return the files written.

    The controller is rendered with the board's target profile, the
    self-test states and the bench trajectory are embedded with the Python
    reference's outputs (compact per-state CRCs where the full records do not
    fit the board), and a Makefile (C2000: Makefile + build.sh) is written.
    Either topology: ``model.inverter.topology`` picks the controller, the
    records, the reference and the test states (``codegen.fwdata.Topology``);
    ``tables`` are TwoLevelTables or ThreeLevelTables to match.  ``protocol``:
    a serial protocol build (see the module docstring).
    """
    spec = board_spec(board)
    topo = topology_of(model)
    if n_selftest < 1:
        raise FirmwareError(f"n_selftest must be >= 1, got {n_selftest}")
    outdir = Path(outdir)
    sets = make_test_sets(model, tables, n_selftest, n_bench, seed)
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
    inp, out = layouts(model)
    env = environment()
    env.filters["c_value"] = lambda v, kind: inp.nf.c_value(v) if kind == REAL else f"{int(v)}u"
    ctx = {"model_name": model.name, "config_hash": model.config_hash(), "version": __version__,
           "board": spec.name, "strategy": tables.strategy, "prefix": model.prefix,
           "input_fields": inp.members, "output_fields": out.members,
           "input_values": inp.values, "output_values": out.values,
           "input_bits": inp.dtype.itemsize * 8, "output_bits": out.dtype.itemsize * 8,
           "reference": topo.reference,
           "states_doc": "; ".join(s.doc for s in sets),
           "sets": [s.context() for s in sets]}
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


def build_firmware(project: Path, board: str, *, make_vars: dict[str, str] | None = None,
                   timeout_s: float = 600) -> BuildResult:
    """Run ``make`` in ``project``; BuildError-like FirmwareError with the compiler output on failure."""
    spec = board_spec(board)
    require_tools(spec.tools + ((MAKE,) if spec.kind == "c28x" else ()))
    project = Path(project)
    cmd = ["make", "-C", str(project), *[f"{k}={v}" for k, v in (make_vars or {}).items()]]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout_s)
    log = r.stdout + r.stderr
    if r.returncode != 0:
        raise FirmwareError(f"building the {board} firmware in {project} failed:\n{log}")
    image = project / "build" / ("fw" if spec.kind == "host" else "fw.elf" if spec.kind == "arm" else "fw.out")
    res = BuildResult(project, image, log)
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
