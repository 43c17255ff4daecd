"""Estimated Cortex-M7 cycles per step: the executed instruction path through a pipeline model.

QEMU counts instructions, not cycles (``codegen.stages.emulate``).  This
module estimates cycles from the real firmware image:

1. **Trace.**  The ELF's loadable segments are mapped into unicorn (Cortex-M7,
   Thumb, M-profile) at their run addresses (the ``.dtcm_rodata``/``.data``
   copies Reset_Handler makes are already in place), a stack is set up at the
   top of RAM, one input record (the bench state, in the step's number format,
   laid out as ``codegen.records`` binds it) is written to RAM, and
   ``<prefix>_step(&in, &out)`` runs from its entry to its return.  Every
   executed translation block is recorded, which gives the executed
   instruction addresses in order (skipped instructions of an IT block
   included: the core issues them too).  The output record is read back and
   compared with the Python reference's, so a wrong path is an error, never a
   number.
2. **Disassemble.**  ``arm-none-eabi-objdump -d`` of the image gives each
   address's instruction; branch targets are replaced by one label, so the
   path is a straight-line block of assembly llvm-mca accepts.
3. **Pipeline model.**  ``llvm-mca -mtriple=thumbv7em-none-eabihf
   -mcpu=cortex-m7 -iterations=1`` (LLVM's Cortex-M7 scheduling model:
   dual issue, FP latencies, the non-pipelined VSQRT/VDIV) gives the block's
   ``Total Cycles``.  Each distinct path is modelled once (cached).

Not modelled: branch penalties (taken branches and mispredictions: the path is
a straight line), instruction and data caches, flash wait states, bus
contention, interrupts.  On the board the step runs from ITCM with its tables
in DTCM, where every access is single-cycle, which is what the model assumes.
The estimate is therefore a lower-leaning figure for the real board's cycles.

:func:`estimate_cycles` traces at most ``max_states`` states, evenly spaced
over the given ones (``codegen.stages.fwdata.evenly_spaced``).
"""
from __future__ import annotations

import glob
import hashlib
import re
import shutil
import struct
import subprocess
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from codegen.errors import MpcgenError
from codegen.model import Model
from codegen.numfmt.opcost import INSTRUCTION_CLASSES, OPERATIONS
from codegen.stages.fwdata import N_BENCH, evenly_spaced
from codegen.stages.progress import phase

__all__ = ["MCA_ARGS", "CycleEstimate", "CycleError", "Elf", "StepTracer", "check_bound", "estimate_cycles", "mca_cycles",
           "llvm_mca", "instruction_totals", "model_bound", "op_totals", "overlap_bound", "strategy_cycles",
           "METHOD_NOTE"]

#: llvm-mca's target: the board's core (thumbv7em, hard float, Cortex-M7 scheduling model)
MCA_ARGS = ("-mtriple=thumbv7em-none-eabihf", "-mcpu=cortex-m7", "-iterations=1")

#: one-paragraph statement of the method (bench footnote, docs/targets.md)
METHOD_NOTE = ("estimated M7 cycles: the step's executed instruction path (the real qemu-m7 image traced "
               "instruction by instruction in unicorn over the bench states) fed to llvm-mca's Cortex-M7 "
               "pipeline model (-mcpu=cortex-m7, one iteration, Total Cycles); not modelled: branch penalties, "
               "caches, flash wait states, interrupts (TCM placement makes every memory access single-cycle). "
               "bound: the algorithm's essential operations per step (sums, products, compares, square roots, "
               "divisions, loads, stores) as the instructions of the step's number format (float32: one each; "
               "fixed point: each helper's shortest integer sequence) at the model's issue limits (an FP write "
               "issues alone, 13 cycles a VSQRT/VDIV, 6 a UDIV, the rest two a cycle, one shifter operation, "
               "multiply, store or branch a cycle); overlap bound: the same with every unit overlapping perfectly.")

#: instructions LLVM 14's Cortex-M7 model has no scheduling data for -> an equivalent with the same timing
_SUBSTITUTES = {"vcmpe.f32": "vcmp.f32", "vcmpe.f64": "vcmp.f64", "vcmp.f32": "vcmp.f32", "vcmp.f64": "vcmp.f64"}
#: calls: llvm-mca gives a call 100 cycles of latency (an untraced callee); the traced path holds the
#: callee's instructions, so a call is the taken branch it is
_CALLS = {"bl": "b", "blx": "bx"}

_CODE_BASE, _CODE_SIZE = 0x0000_0000, 0x0040_0000
_RAM_BASE, _RAM_SIZE = 0x2000_0000, 0x0040_0000
_STACK_TOP = _RAM_BASE + _RAM_SIZE - 0x100
_IO_BASE = _RAM_BASE + _RAM_SIZE - 0x0004_0000  # records (below the stack, above any image data)
_RETURN = _CODE_BASE + _CODE_SIZE - 0x40  # mapped, never executed: the step "returns" here


class CycleError(MpcgenError):
    """The cycle estimate cannot be made (missing tool, bad image, emulated output differs)."""


# ---------------------------------------------------------------- ELF


@dataclass
class Elf:
    """The parts of a little-endian ELF32 image the tracer needs: loadable segments and symbols."""

    segments: list[tuple[int, bytes, int]]  # (run address, file bytes, memory size)
    symbols: dict[str, tuple[int, int]]  # name -> (address, size)

    @classmethod
    def read(cls, path: Path) -> Elf:
        data = Path(path).read_bytes()
        if data[:4] != b"\x7fELF" or data[4] != 1 or data[5] != 1:
            raise CycleError(f"{path}: not a little-endian ELF32 image")
        (e_phoff, e_shoff, _flags, _ehsize, e_phentsize, e_phnum, e_shentsize, e_shnum,
         _shstrndx) = struct.unpack_from("<IIIHHHHHH", data, 28)
        segments = []
        for i in range(e_phnum):
            p_type, p_offset, p_vaddr, _paddr, p_filesz, p_memsz, _fl, _al = struct.unpack_from(
                "<8I", data, e_phoff + i * e_phentsize)
            if p_type == 1:  # PT_LOAD, at its run (virtual) address
                segments.append((p_vaddr, data[p_offset:p_offset + p_filesz], p_memsz))
        sections = [struct.unpack_from("<10I", data, e_shoff + i * e_shentsize) for i in range(e_shnum)]
        symbols: dict[str, tuple[int, int]] = {}
        for sh in sections:
            if sh[1] != 2:  # SHT_SYMTAB
                continue
            strtab = sections[sh[6]]
            for off in range(sh[4], sh[4] + sh[5], 16):
                st_name, st_value, st_size, st_info, _o, _shndx = struct.unpack_from("<IIIBBH", data, off)
                if st_info & 0xF != 2:  # STT_FUNC
                    continue
                start = strtab[4] + st_name
                name = data[start:data.index(b"\0", start)].decode()
                symbols[name] = (st_value & ~1, st_size)
        return cls(segments, symbols)


# ---------------------------------------------------------------- tools


def _which(exe: str, pattern: str = "") -> str:
    found = shutil.which(exe)
    if not found and pattern:
        found = next(iter(sorted(glob.glob(pattern), reverse=True)), None)
    if not found:
        hint = {"llvm-mca": "install the Debian package llvm (apt-get install llvm)",
                "arm-none-eabi-objdump": "install the Debian package binutils-arm-none-eabi "
                                         "(comes with gcc-arm-none-eabi)"}[exe]
        raise CycleError(f"{exe} not found: {hint}")
    return found


def llvm_mca() -> str:
    """Path of llvm-mca (PATH, else the newest /usr/lib/llvm-*/bin/llvm-mca)."""
    return _which("llvm-mca", "/usr/lib/llvm-*/bin/llvm-mca")


_TOTAL = re.compile(r"^Total Cycles:\s+(\d+)", re.M)
_UNSUPPORTED = re.compile(r"note: instruction:\s*(.*)$", re.M)


def mca_cycles(asm: list[str] | str) -> int:
    """llvm-mca's Total Cycles of one iteration of the straight-line block ``asm`` (lines of Thumb-2
    assembly, unified syntax) on the Cortex-M7 model.  An instruction the model has no data for is
    replaced by its equivalent (``vcmpe`` -> ``vcmp``; LLVM 14's model has no IT: ``it`` becomes a
    ``nop`` (one issue slot) and the instructions it makes conditional their unconditional forms, same
    resources and latencies; a call ``bl`` becomes the branch ``b``, its callee being part of the
    traced path) or, failing that, CycleError."""
    lines = asm.splitlines() if isinstance(asm, str) else list(asm)
    text = "\n".join(_without_it(_substitute(line) for line in lines)) + "\n.Lt:\n"
    r = subprocess.run([llvm_mca(), *MCA_ARGS], input=text, capture_output=True, text=True, timeout=300)
    m = _TOTAL.search(r.stdout)
    if r.returncode != 0 or not m:
        bad = _UNSUPPORTED.search(r.stderr)
        raise CycleError("llvm-mca failed" + (f" on {bad.group(1).strip()!r}" if bad else "") +
                         f": {r.stderr.strip()[:400]}")
    return int(m.group(1))


_IT = re.compile(r"^\s*it([te]{0,3})\s")
_CONDS = ("eq", "ne", "cs", "hs", "cc", "lo", "mi", "pl", "vs", "vc", "hi", "ls", "ge", "lt", "gt", "le", "al")


def _without_it(lines: Iterable[str]) -> Iterator[str]:
    """IT blocks as a ``nop`` followed by the unconditional forms of their instructions."""
    pending = 0
    for line in lines:
        m = _IT.match(line + " ")
        if m:
            pending = 1 + len(m.group(1))
            yield "\tnop"
            continue
        if pending:
            pending -= 1
            parts = line.split(None, 1)
            head, dot, tail = parts[0].partition(".")
            if head[-2:] in _CONDS:
                line = "\t" + head[:-2] + dot + tail + ("\t" + parts[1] if len(parts) > 1 else "")
        yield line


def _substitute(line: str) -> str:
    parts = line.split(None, 1)
    if parts and parts[0] in _CALLS:
        return "\t" + _CALLS[parts[0]] + ("\t" + parts[1] if len(parts) > 1 else "")
    if parts and parts[0] in _SUBSTITUTES:
        ops = parts[1] if len(parts) > 1 else ""
        reg, _, imm = ops.partition(",")
        if imm.strip().startswith("#"):  # compare with zero: the model has only the register form
            ops = f"{reg}, {reg.strip()}"
        return "\t" + _SUBSTITUTES[parts[0]] + ("\t" + ops if ops else "")
    return line


# ---------------------------------------------------------------- disassembly

_OBJ_LINE = re.compile(r"^\s*([0-9a-f]+):\t([^\t]+)(?:\t(.*))?$")
_TARGET = re.compile(r"\b[0-9a-f]+ <[^>]*>")


def disassemble(elf_path: Path) -> dict[int, str]:
    """Address -> one line of assembly llvm-mca accepts, for every instruction of the image's code:
    objdump's comments dropped, branch (and ``adr``) targets replaced by the label ``.Lt``."""
    r = subprocess.run([_which("arm-none-eabi-objdump"), "-d", "--no-show-raw-insn", str(elf_path)],
                       capture_output=True, text=True, timeout=300)
    if r.returncode != 0:
        raise CycleError(f"arm-none-eabi-objdump failed on {elf_path}: {r.stderr.strip()[:300]}")
    out: dict[int, str] = {}
    for line in r.stdout.splitlines():
        m = _OBJ_LINE.match(line)
        if not m:
            continue
        mnemonic, operands = m.group(2).strip(), (m.group(3) or "")
        if mnemonic.startswith("."):  # .word / .short literal data
            continue
        operands, _, comment = operands.partition("@")
        operands = _TARGET.sub(".Lt", operands.split(";")[0]).strip()
        if mnemonic.startswith("vmov.f") and "#" in operands and comment.split():
            # objdump prints a VFP immediate's encoding (#96) and its value in the comment (0.5)
            operands = operands.split("#")[0] + "#" + comment.split()[-1]
        if mnemonic.endswith(".w") and re.search(r"\]!$|\], ", operands):
            mnemonic = mnemonic[:-2]  # pre-/post-indexed writeback: LLVM takes no .w there
        out[int(m.group(1), 16)] = f"\t{mnemonic}\t{operands}" if operands else f"\t{mnemonic}"
    return out


# ---------------------------------------------------------------- tracing


class StepTracer:
    """The image loaded into unicorn once; :meth:`run` traces one call of ``symbol(&in, &out)``."""

    def __init__(self, elf_path: Path, symbol: str) -> None:
        try:
            import unicorn
            from unicorn import arm_const
        except ImportError:  # pragma: no cover - a declared dependency
            raise CycleError("the Python package unicorn is not installed (pip install unicorn)") from None
        self._uc_mod, self._arm = unicorn, arm_const
        elf = Elf.read(elf_path)
        if symbol not in elf.symbols:
            raise CycleError(f"{elf_path}: no function {symbol}")
        self.entry = elf.symbols[symbol][0]
        uc = unicorn.Uc(unicorn.UC_ARCH_ARM, unicorn.UC_MODE_THUMB | unicorn.UC_MODE_MCLASS)
        uc.ctl_set_cpu_model(arm_const.UC_CPU_ARM_CORTEX_M7)
        uc.mem_map(_CODE_BASE, _CODE_SIZE)
        uc.mem_map(_RAM_BASE, _RAM_SIZE)
        for addr, data, memsz in elf.segments:
            if not (_CODE_BASE <= addr < _CODE_BASE + _CODE_SIZE or _RAM_BASE <= addr < _IO_BASE):
                raise CycleError(f"{elf_path}: segment at {addr:#x} outside the qemu-m7 memory map")
            uc.mem_write(addr, data + bytes(memsz - len(data)))
        self._ram = bytes(uc.mem_read(_RAM_BASE, _IO_BASE - _RAM_BASE))
        self._blocks: list[tuple[int, int]] = []
        uc.hook_add(unicorn.UC_HOOK_BLOCK, lambda _uc, addr, size, _u: self._blocks.append((addr, size)))
        self.uc = uc

    def run(self, record: bytes, out_size: int, max_instructions: int = 1_000_000) -> tuple[list[tuple[int, int]],
                                                                                             bytes]:
        """Executed blocks (address, octets) of one call and the output record's bytes."""
        uc, a = self.uc, self._arm
        uc.mem_write(_RAM_BASE, self._ram)  # the step is pure; restore anyway (static scratch)
        out_addr = _IO_BASE + ((len(record) + 63) & ~63)
        uc.mem_write(_IO_BASE, bytes(record))
        uc.mem_write(out_addr, bytes(out_size))
        uc.reg_write(a.UC_ARM_REG_SP, _STACK_TOP)
        uc.reg_write(a.UC_ARM_REG_R0, _IO_BASE)
        uc.reg_write(a.UC_ARM_REG_R1, out_addr)
        uc.reg_write(a.UC_ARM_REG_LR, _RETURN | 1)
        self._blocks = []
        try:
            uc.emu_start(self.entry | 1, _RETURN, count=max_instructions)
        except self._uc_mod.UcError as e:
            raise CycleError(f"unicorn stopped at pc={uc.reg_read(a.UC_ARM_REG_PC):#x}: {e}") from None
        if uc.reg_read(a.UC_ARM_REG_PC) != _RETURN:
            raise CycleError(f"the step did not return within {max_instructions} instructions")
        return self._blocks, bytes(uc.mem_read(out_addr, out_size))


# ---------------------------------------------------------------- estimate


@dataclass
class CycleEstimate:
    """Estimated cycles per step over the traced states (and what the estimate saw)."""

    states: int
    paths: int
    cycles: np.ndarray  # per traced state
    instructions: np.ndarray  # per traced state (executed instructions of the path)

    @property
    def summary(self) -> dict[str, float]:
        c = self.cycles
        return {"min": float(c.min()), "median": float(np.median(c)), "max": float(c.max()),
                "mean": round(float(c.mean()), 1), "instructions_median": float(np.median(self.instructions)),
                "states": self.states, "paths": self.paths}


def _path_lines(blocks: list[tuple[int, int]], addresses: np.ndarray, asm: dict[int, str]) -> list[str]:
    lines: list[str] = []
    for start, size in blocks:
        lo, hi = np.searchsorted(addresses, [start, start + size])
        if lo == hi or addresses[lo] != start:
            raise CycleError(f"executed block at {start:#x} does not start at a disassembled instruction")
        lines.extend(asm[int(x)] for x in addresses[lo:hi])
    return lines


def _same_fields(raw: bytes, want: Any) -> bool:
    """The output record ``raw`` (the traced step's bytes) equals ``want`` (one record of the expected
    outputs) field by field, bit for bit: padding between and after the fields is not data (neither side
    defines it); an array without fields is compared whole."""
    want = np.asarray(want)
    if not want.dtype.names:
        return raw == np.ascontiguousarray(want).tobytes()
    got = np.frombuffer(raw, dtype=want.dtype)[0]
    return all(np.asarray(got[f]).tobytes() == np.asarray(want[f]).tobytes() for f in want.dtype.names)


def estimate_cycles(elf_path: Path, symbol: str, states: np.ndarray, expected: np.ndarray, *,
                    max_states: int = 256, jobs: int = 4, log: Callable[[str], None] | None = None) -> CycleEstimate:
    """Estimated Cortex-M7 cycles of ``symbol(&in, &out)`` for each of at most ``max_states`` of
    ``states`` (input records in the step's format, evenly spaced), with ``expected`` the reference's
    output records (same order) to compare the traced outputs with (a mismatch is a CycleError).
    ``log``: progress lines of the trace and the pipeline model, a heartbeat every few seconds
    (:func:`codegen.stages.progress.phase`)."""
    idx = evenly_spaced(np.arange(len(states)), max_states)
    keys: list[str] = []
    paths: dict[str, list[str]] = {}
    n_instr = []
    mismatches = 0
    with phase(log, f"{symbol}: tracing {len(idx)} bench states in unicorn") as p:
        tracer = StepTracer(elf_path, symbol)
        asm = disassemble(elf_path)
        addresses = np.array(sorted(asm), dtype=np.int64)
        out_size = expected.dtype.itemsize
        for done, i in enumerate(idx, 1):
            blocks, out = tracer.run(np.ascontiguousarray(states[i:i + 1]).tobytes(), out_size)
            if not _same_fields(out, expected[i]):
                mismatches += 1
            key = hashlib.sha1(repr(blocks).encode()).hexdigest()
            if key not in paths:
                paths[key] = _path_lines(blocks, addresses, asm)
            keys.append(key)
            n_instr.append(len(paths[key]))
            p.note(f"{done}/{len(idx)} states, {len(paths)} distinct paths")
    if mismatches:
        raise CycleError(f"{symbol}: the traced step's outputs differ from the reference for {mismatches} of "
                         f"{len(idx)} states")
    with phase(log, f"{symbol}: llvm-mca (Cortex-M7 model) on {len(paths)} distinct paths") as p, \
            ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
        cycles = []
        for c in pool.map(mca_cycles, paths.values()):
            cycles.append(c)
            p.note(f"{len(cycles)}/{len(paths)} paths")
        cyc = dict(zip(paths, cycles))
    return CycleEstimate(len(idx), len(paths), np.array([cyc[k] for k in keys], dtype=np.float64),
                         np.array(n_instr, dtype=np.float64))


# ---------------------------------------------------------------- lower bounds

#: Issue limits with perfect overlap (the overlap bound): one FP instruction per cycle, VSQRT.F32 /
#: VDIV.F32 not pipelined (14 / 16 cycles each in the divide/square-root unit, the rest going on), one
#: load or store per cycle, at most two instructions per cycle (dual issue).
SQRT_CYCLES, DIV_CYCLES, ISSUE_WIDTH = 14, 16, 2

#: Issue limits of the pipeline model the estimate uses (LLVM 14's Cortex-M7 model, each counted by hand
#: in tests/stages/test_cycles.py): an FP instruction that writes a register issues alone (results are
#: written back in order, and no other instruction pairs with one); a VSQRT.F32 or VDIV.F32 holds issue
#: for 13 cycles, back to back too; compares, branches, loads and stores issue two per cycle, stores
#: one per cycle.
MODEL_DIVIDER_CYCLES = 13
#: The model's integer rules (same tests): a UDIV holds issue for 6 cycles, alone; plain ALU operations
#: dual-issue; an instruction using the shifter (a shift, an operand shifted by an immediate), a
#: multiply (the one MAC unit: MUL, MLS, SMULL, SMLAL, UMULL), a store and a branch one a cycle each
#: (each pairs with another kind).  The overlap bound counts a UDIV's 6 cycles in the divider only.
MODEL_UDIV_CYCLES = 6


def op_totals(ops: dict[str, dict[str, int]], mult: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Per state, each count of ``Topology.essential_ops`` for the whole step: per step + for every
    other unit its counts x its multiplicity (``mult``, ``Topology.op_multiplicities``: at least
    ``per_candidate``, the evaluated candidates); with a ``first_candidate`` entry the first
    evaluated candidate counts that instead (e.g. a candidate whose prediction is the estimate
    itself).  A unit without a multiplicity, or a multiplicity without a unit, is an error; so is a
    count of no essential operation (:data:`OPERATIONS`)."""
    units = set(ops) - {"per_step", "first_candidate"}
    if units != set(mult) or "per_candidate" not in units:
        raise CycleError(f"essential operations {sorted(units)} and their multiplicities {sorted(mult)} differ")
    unknown = sorted({key for counts in ops.values() for key in counts} - set(OPERATIONS))
    if unknown:
        raise CycleError(f"essential operations count {unknown}: not among {', '.join(OPERATIONS)}")
    n = {u: np.asarray(m, dtype=np.float64) for u, m in mult.items()}
    n_first = np.minimum(n["per_candidate"], 1.0)
    n["per_candidate"] = n["per_candidate"] - n_first
    first = ops.get("first_candidate", ops["per_candidate"])
    return {key: (ops["per_step"].get(key, 0) + n_first * first.get(key, 0)
                  + sum(n[u] * ops[u].get(key, 0) for u in sorted(units)))
            for key in OPERATIONS}


def instruction_totals(t: dict[str, np.ndarray], costs: dict[str, dict[str, int]]) -> dict[str, np.ndarray]:
    """The essential operations ``t`` (:func:`op_totals`) as instructions, per class of
    :data:`INSTRUCTION_CLASSES`: each operation's count times the instructions the step's number format
    needs for it (``NumberFormat.op_costs``).  An operation without a cost, or a class the model has
    no issue rule for, is an error."""
    missing = sorted(set(t) - set(costs))
    unknown = sorted({c for cost in costs.values() for c in cost} - set(INSTRUCTION_CLASSES))
    if missing or unknown:
        raise CycleError(f"number format costs: no cost for {missing}" if missing else
                         f"number format costs: no issue rule for the instruction classes {unknown}")
    shape = np.shape(next(iter(t.values()))) if t else ()
    out = {c: np.zeros(shape) for c in INSTRUCTION_CLASSES}
    for op, n in t.items():
        for c, k in costs[op].items():
            out[c] = out[c] + k * np.asarray(n, dtype=np.float64)
    return out


def _counts(c: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Every class of :data:`INSTRUCTION_CLASSES` (zero where ``c`` has none)."""
    zero = np.zeros(np.shape(next(iter(c.values())))) if c else np.zeros(1)
    return {k: np.asarray(c[k], dtype=np.float64) if k in c else zero for k in INSTRUCTION_CLASSES}


def overlap_bound(c: dict[str, np.ndarray]) -> np.ndarray:
    """The essential instructions ``c`` (:func:`instruction_totals`) at the core's issue limits, every
    unit overlapping perfectly: max(FP issue, divider busy, memory, shifter, multiplier, branches, all
    instructions / 2).  Holds for any in-order dual-issue core with these unit limits, whatever its
    write-back rules."""
    c = _counts(c)
    fp_issue = c["fp"] + c["cmp"] + c["sqrt"] + c["div"]
    mem = c["load"] + c["store"]
    integer = c["alu"] + c["shift"] + c["mac"] + c["udiv"] + c["branch"]
    return np.maximum.reduce([fp_issue, SQRT_CYCLES * c["sqrt"] + DIV_CYCLES * c["div"] + MODEL_UDIV_CYCLES * c["udiv"],
                              mem, c["shift"], c["mac"], c["branch"],
                              np.ceil((fp_issue + mem + integer) / ISSUE_WIDTH)])


def model_bound(c: dict[str, np.ndarray]) -> np.ndarray:
    """The essential instructions ``c`` (:func:`instruction_totals`) at the issue limits of the
    estimate's pipeline model (:data:`MODEL_DIVIDER_CYCLES`, :data:`MODEL_UDIV_CYCLES`): FP instructions
    that write a register one a cycle, alone; every square root and division 13 cycles, every UDIV 6,
    alone; everything else in the remaining cycles, two a cycle, but one store, one compare of the
    float step, one shifter operation, one multiply and one branch a cycle."""
    c = _counts(c)
    rest = c["cmp"] + c["load"] + c["store"] + c["alu"] + c["shift"] + c["mac"] + c["branch"]
    paired = np.maximum.reduce([np.ceil(rest / ISSUE_WIDTH), c["store"], c["cmp"], c["shift"], c["mac"], c["branch"]])
    return c["fp"] + MODEL_DIVIDER_CYCLES * (c["sqrt"] + c["div"]) + MODEL_UDIV_CYCLES * c["udiv"] + paired


def check_bound(symbol: str, est_cycles: np.ndarray, bound: np.ndarray) -> None:
    """Raise if any state's estimate is below its model bound: the essential operations would be
    miscounted (a bound that is not a bound is an error, never a figure)."""
    below = int(np.sum(np.asarray(est_cycles) < np.asarray(bound)))
    if below:
        raise CycleError(f"{symbol}: the estimate is below the model's lower bound for {below} of "
                         f"{len(bound)} states: the essential operations are miscounted")


def strategy_cycles(model: Model, tables: Any, elf_path: Path, *, n_bench: int = N_BENCH,
                    max_states: int | None = None, log: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Estimate and bound of one strategy's image (``model`` the strategy's variant): the bench
    states the image embeds (the topology's trajectory, ``n_bench`` evenly spaced, in the step's
    format), every one traced (the set its instruction counts are taken over), or at most
    ``max_states`` of them, evenly spaced.  JSON-ready figures; ``log``: progress lines."""
    max_states = n_bench if max_states is None else max_states
    from codegen.stages.fwdata import expected_outputs, in_step_format, trajectory_states
    from codegen.topology import topology_of

    topo = topology_of(model)
    states = in_step_format(model, tables, trajectory_states(model, n_bench))
    expected = expected_outputs(topo, tables, states)
    est = estimate_cycles(elf_path, f"{model.prefix}_step", states, expected, max_states=max_states, log=log)
    idx = evenly_spaced(np.arange(len(states)), max_states)
    totals = instruction_totals(op_totals(topo.essential_ops(model, tables),
                                          topo.op_multiplicities(model, tables, states[idx], expected[idx])),
                                tables.nf.op_costs)
    bound = model_bound(totals)
    overlap = overlap_bound(totals)
    check_bound(f"{model.prefix}_step", est.cycles, bound)
    s = est.summary
    return {"min": s["min"], "median": s["median"], "max": s["max"], "mean": s["mean"],
            "path_instructions_median": s["instructions_median"], "states": s["states"], "paths": s["paths"],
            "bound_median": float(np.median(bound)), "bound_min": float(bound.min()),
            "bound_max": float(bound.max()), "est_over_bound": s["median"] / float(np.median(bound)),
            "bound_overlap_median": float(np.median(overlap)), "bound_overlap_min": float(overlap.min()),
            "bound_overlap_max": float(overlap.max()),
            "est_over_bound_overlap": s["median"] / float(np.median(overlap))}
