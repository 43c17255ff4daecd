"""Run the qemu-m7 firmware headless in QEMU and read its self-test results.

QEMU (``mps2-an500``, Cortex-M7) runs the ELF with semihosting (the firmware
exits through SYS_EXIT_EXTENDED) and ``-icount shift=N``, under which SysTick
counts exactly ``instructions * 2**N / 40`` ticks (docs/targets.md;
every image re-checks this with its CAL line: a 1024-NOP sled must take
1024 instructions).  The UART goes to a file; QEMU runs in its own process
group, under a timeout, and is always killed by its id.

``run_and_check`` builds (or takes from the build cache, when every input of
the build is unchanged: ``firmware.build_firmware``), runs and checks one
strategy's image and returns its counts: states, mismatches, and the
instructions per step (min/median/max) over the bench set, a recorded
closed-loop trajectory (``mpcgen bench --emulated`` calls it per strategy).
"""
from __future__ import annotations

import os
import re
import signal
import subprocess
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from codegen.errors import MpcgenError
from codegen.model import Model
from codegen.stages.firmware import (
    EMULATED_BOARD,
    ICOUNT_SHIFT,
    QEMU,
    board_spec,
    build_firmware,
    make_test_sets,
    qemu_command,
    require_tools,
    write_firmware_project,
)
from codegen.stages.fwdata import N_BENCH, layouts
from codegen.stages.progress import phase

#: SysTick clock of mps2-an500 (processor clock, CLKSOURCE=1).
SYSTICK_HZ = 25_000_000


class EmulationError(MpcgenError):
    """QEMU failed, timed out, or the firmware's output is wrong or incomplete."""


@dataclass
class QemuRun:
    """One QEMU run: exit status (None if killed), UART text, QEMU's own output."""

    returncode: int | None
    uart: str
    stderr: str
    timed_out: bool
    pid: int




def kill_group(proc: subprocess.Popen[Any]) -> None:
    """Kill QEMU's process group (it was started in its own session) and reap it."""
    if proc.poll() is None:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    proc.wait()


def uart_progress(text: str) -> str:
    """How far a running image got, from its console so far: the test sets finished, the one running
    (with the states stepped, where the set prints its cycles)."""
    done: list[str] = []
    running, n, stepped = "", 0, 0
    for line in text.splitlines():
        word, _, rest = line.partition(" ")
        kv = dict(_KV.findall(rest))
        if word == "SET":
            running, n, stepped = kv.get("name", "?"), int(kv.get("n", "0")), 0
        elif word == "CYC":
            stepped += len(rest.split())
        elif word == "SUMMARY":
            done.append(kv.get("set", "?"))
            running = ""
    parts = [f"sets done: {', '.join(done)}" if done else "no set done yet"]
    if running:
        parts.append(f"running set {running}" + (f" ({stepped}/{n} states)" if stepped else ""))
    return "; ".join(parts)


def build_progress(project: Path) -> str:
    """How far ``make`` got in a firmware project: the objects built of its sources (the Makefile's
    ``SRCS``, built in order into ``build/``), the one being compiled, or the link."""
    text = (Path(project) / "Makefile").read_text()
    m = re.search(r"^SRCS = ((?:.*\\\n)*.*)$", text, re.M)
    srcs = m.group(1).replace("\\\n", " ").split() if m else []
    built = [src for src in srcs if (Path(project) / "build" / src).with_suffix(".o").exists()]
    if len(built) < len(srcs):
        pending = next(src for src in srcs if src not in built)
        return f"{len(built)}/{len(srcs)} objects built, compiling {pending}"
    return f"{len(srcs)}/{len(srcs)} objects built, linking"


def run_qemu(elf: Path, *, timeout_s: float = 120.0, icount_shift: int = ICOUNT_SHIFT,
             progress: Callable[[str], None] | None = None, poll_s: float = 1.0,
             board: str = EMULATED_BOARD) -> QemuRun:
    """Run ``elf`` of the emulated ``board`` (qemu-m7, qemu-m3) until it exits (semihosting) or
    ``timeout_s`` passes; QEMU is always ended.  ``progress``: called every ``poll_s`` seconds with
    how far the image got (:func:`uart_progress`)."""
    require_tools((QEMU,))
    machine = board_spec(board).qemu
    if machine is None:
        raise EmulationError(f"board {board} is not emulated: QEMU runs {', '.join(_emulated())}")
    elf = Path(elf)
    if not elf.is_file():
        raise EmulationError(f"firmware image {elf} does not exist: build the {board} project first")
    with tempfile.TemporaryDirectory(prefix="mpcgen-qemu-") as tmp:
        uart = Path(tmp) / "uart.log"
        proc = subprocess.Popen(qemu_command(elf, f"file:{uart}", icount_shift, machine), stdin=subprocess.DEVNULL,
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True)
        timed_out = False
        out = b""
        deadline = time.monotonic() + timeout_s
        try:
            while True:
                try:
                    out, _ = proc.communicate(timeout=max(0.0, min(poll_s, deadline - time.monotonic())))
                    break
                except subprocess.TimeoutExpired:
                    if time.monotonic() >= deadline:
                        timed_out = True
                        break
                    if progress is not None and uart.exists():
                        progress(uart_progress(uart.read_text(errors="replace")))
        finally:
            kill_group(proc)
            if proc.stdout is not None:
                proc.stdout.close()
        text = uart.read_text(errors="replace") if uart.exists() else ""
    return QemuRun(None if timed_out else proc.returncode, text.replace("\r", ""),
                   out.decode(errors="replace"), timed_out, proc.pid)


def _emulated() -> list[str]:
    from codegen.stages.firmware import BOARDS

    return [b.name for b in BOARDS.values() if b.qemu is not None]


# ---------------------------------------------------------------- parsing

_KV = re.compile(r"(\w+)=(\S+)")


@dataclass
class SetResult:
    """A SUMMARY line with the set's CYC values and detail lines."""

    name: str
    n: int
    mismatches: int
    crc_in: int
    crc_out: int
    cyc_min: int
    cyc_max: int
    cyc_mean: int
    overhead: int
    unit: str
    cycles: list[int] = field(default_factory=list)
    details: list[str] = field(default_factory=list)


@dataclass
class ConsoleReport:
    """Everything the firmware printed, parsed."""

    hello: dict[str, str]
    cal: dict[str, int]
    sets: dict[str, SetResult]
    result: str | None
    exit_code: int | None
    errors: list[str]


def parse_console(text: str) -> ConsoleReport:
    """Parse the runtime's console lines (firmware/runtime/selftest.h documents them)."""
    hello: dict[str, str] = {}
    cal: dict[str, int] = {}
    sets: dict[str, SetResult] = {}
    cycles: dict[str, list[int]] = {}
    details: dict[str, list[str]] = {}
    current = ""
    result = None
    exit_code = None
    errors: list[str] = []
    for line in text.splitlines():
        word, _, rest = line.partition(" ")
        kv = dict(_KV.findall(rest))
        if word == "HELLO":
            hello = kv
        elif word == "CAL":
            cal = {k: int(v) for k, v in kv.items()}
        elif word == "SET":
            current = kv.get("name", "")
            cycles[current], details[current] = [], []
        elif word == "CYC":
            cycles.setdefault(current, []).extend(int(v) for v in rest.split())
        elif word in ("MISMATCH", "STATE", "OUT"):
            details.setdefault(kv.get("set", current), []).append(line)
        elif word == "SUMMARY":
            name = kv["set"]
            sets[name] = SetResult(name, int(kv["n"]), int(kv["mismatches"]), int(kv["crc_in"], 16),
                                   int(kv["crc_out"], 16), int(kv["cyc_min"]), int(kv["cyc_max"]),
                                   int(kv["cyc_mean"]), int(kv["overhead"]), kv["unit"],
                                   cycles.get(name, []), details.get(name, []))
        elif word == "RESULT":
            result = rest.split()[0] if rest else ""
        elif word == "EXIT":
            exit_code = int(kv.get("code", "-1"))
        elif word in ("ERROR", "FAULT"):
            errors.append(line)
    return ConsoleReport(hello, cal, sets, result, exit_code, errors)


def ticks_to_instructions(ticks: np.ndarray | list[int] | int, icount_shift: int = ICOUNT_SHIFT) -> np.ndarray:
    """SysTick ticks under -icount shift=N -> instructions (ticks * 40 / 2**N)."""
    return np.asarray(ticks, dtype=np.float64) * (1e9 / SYSTICK_HZ) / float(2 ** icount_shift)


def check_calibration(report: ConsoleReport, icount_shift: int = ICOUNT_SHIFT) -> float:
    """Instructions measured for the CAL NOP sled; EmulationError if not the sled's length (+-0.5)."""
    if "nops" not in report.cal or "ticks" not in report.cal:
        raise EmulationError("the firmware printed no CAL line (SysTick calibration)")
    measured = float(ticks_to_instructions(report.cal["ticks"], icount_shift))
    if abs(measured - report.cal["nops"]) > 0.5:
        raise EmulationError(f"SysTick scaling check failed: {report.cal['nops']} NOPs measured as "
                             f"{measured:.2f} instructions at -icount shift={icount_shift}")
    return measured


# ---------------------------------------------------------------- per strategy

@dataclass
class StrategyCounts:
    """Result of one strategy's image in QEMU."""

    strategy: str
    states: int  # states checked on target (all sets)
    mismatches: int
    bench_states: int
    instr_min: float
    instr_median: float
    instr_max: float
    instr_mean: float
    digests_match: bool
    uart: str = ""
    #: the self-test set's instructions per step: its state count and min/median/max/mean (median
    #: None unless the image printed every state's count: ``run_and_check(dump_selftest=True)``)
    selftest_states: int = 0
    selftest_min: float = 0.0
    selftest_median: float | None = None
    selftest_max: float = 0.0
    selftest_mean: float = 0.0


def run_and_check(model: Model, tables: Any, workdir: Path, *, n_selftest: int = 10000,
                  n_bench: int = N_BENCH, icount_shift: int = ICOUNT_SHIFT, timeout_s: float = 300.0,
                  log: Callable[[str], None] | None = None, board: str = EMULATED_BOARD,
                  dump_selftest: bool = False) -> StrategyCounts:
    """Write, build and run one image of the emulated ``board`` (qemu-m7; qemu-m3: no FPU); check it
    against the reference; count instructions.

    The firmware compares every output with its embedded expected outputs;
    independently, the host recomputes the CRC-32 of all inputs and outputs
    from the Python reference and compares it with the firmware's digests.
    Either topology (``tables``: TwoLevelTables or ThreeLevelTables to match
    ``model.inverter.topology``); the bench set is the topology's recorded
    trajectory (three-level: the 27-MPDTC run at rated speed).  ``log``: progress lines of each
    phase (writing, building, the QEMU run, the digest check), with a heartbeat every few seconds
    (:func:`codegen.stages.progress.phase`).  ``dump_selftest``: the image also prints every self-test
    state's count, which gives the self-test set's median (its min/max/mean come from its SUMMARY either way).
    """
    inp, out = layouts(model)
    workdir = Path(workdir)
    label = f"{tables.strategy} ({model.controller.number_format})"
    with phase(log, f"{label}: writing the firmware project (reference outputs of {n_selftest} self-test "
                    f"and {n_bench} bench states)"):
        write_firmware_project(model, tables, board, workdir, n_selftest, n_bench=n_bench,
                               dump_selftest=dump_selftest)
    # a clean project whose every build input is unchanged gets the cached build (a "reused" line)
    with phase(log, f"{label}: compiling and linking the image (make)", probe=lambda: build_progress(workdir)):
        build = build_firmware(workdir, board, log=log)
    with phase(log, f"{label}: running the image in QEMU") as p:
        run = run_qemu(build.image, timeout_s=timeout_s, icount_shift=icount_shift, progress=p.note, board=board)
    if run.timed_out:
        raise EmulationError(f"QEMU did not finish within {timeout_s} s (killed); last output: {run.uart[-300:]!r}")
    rep = parse_console(run.uart)
    check_calibration(rep, icount_shift)
    if rep.hello.get("config") != model.config_hash():
        raise EmulationError(f"image reports config {rep.hello.get('config')}, expected {model.config_hash()}")
    ok = True
    with phase(log, f"{label}: checking the image's digests against the reference"):
        for ts in make_test_sets(model, tables, n_selftest, n_bench):
            got = rep.sets.get(ts.name)
            if got is None:
                raise EmulationError(f"no SUMMARY for set {ts.name}; output ends {run.uart[-300:]!r}")
            ok &= (got.n == len(ts.states) and got.crc_in == inp.crc(ts.states)
                   and got.crc_out == out.crc(ts.expected))
    bench = rep.sets.get("bench")
    instr = ticks_to_instructions(bench.cycles if bench else [0], icount_shift)
    st = rep.sets["selftest"]
    st_min, st_max, st_mean = (round(float(ticks_to_instructions(v, icount_shift)), 1)
                               for v in (st.cyc_min, st.cyc_max, st.cyc_mean))
    st_median = None
    if dump_selftest:
        if len(st.cycles) != st.n:
            raise EmulationError(f"the image printed {len(st.cycles)} self-test counts for {st.n} states")
        per_state = ticks_to_instructions(st.cycles, icount_shift)
        st_median = round(float(np.median(per_state)), 1)
        # the mean of the printed counts (the SUMMARY's mean is an integer number of ticks)
        st_mean = round(float(per_state.mean()), 1)
    return StrategyCounts(tables.strategy, sum(s.n for s in rep.sets.values()),
                          sum(s.mismatches for s in rep.sets.values()), len(instr),
                          round(float(instr.min()), 1), round(float(np.median(instr)), 1),
                          round(float(instr.max()), 1), round(float(instr.mean()), 1),
                          ok and run.returncode == 0, run.uart, st.n, st_min, st_median, st_max, st_mean)
