"""``mpcgen verify``: the compiled C step against the Python reference, bit for bit.

Per strategy: build the host library of that variant, assemble the test
states ((a) the variant's own closed-loop run, (b) random states over the
operating range, (c) adversarial states), run both implementations over the
whole batch and compare every output field's bits.  On a mismatch the first
offending state is printed with every intermediate value from both sides.
Before anything runs, :func:`check_verify_memory` estimates the memory the
run takes (:class:`VerifyMemory`) and refuses one that does not fit the
machine or the process's address-space limit.  Each result names the C it is about by C hash (``codegen.manifest``): the
host C compiled and compared, and the C ``generate`` writes for the config's
target (the same arithmetic: target profiles differ only in placement
attributes and comments).  Topology-agnostic: everything topology-specific
comes from the plugin.

A quantised (fixed-point) step's reference also counts, per saturating
operation (``codegen.numfmt.fixed.count_saturations``: the C helper and the
reference line calling it), how many of the states that pass the input
guard saturate it (``StrategyResult.saturations``; numerics.md "Saturation
inside the guard's limits").
"""
from __future__ import annotations

import contextlib
import functools
import multiprocessing
import os
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np

from codegen.compare import describe_mismatch, mismatch_mask
from codegen.errors import UsageError
from codegen.manifest import c_hash_of, sources
from codegen.model import Model
from codegen.numfmt import number_format
from codegen.numfmt.fixed import count_saturations
from codegen.stages.fwdata import evenly_spaced
from codegen.topology import topology_of

CHUNK = 250_000
#: the target whose C verification compiles (``Topology.host_library``)
COMPILED_TARGET = "host"
#: fewer states than this are compared in this process (a pool costs more than it saves)
PARALLEL_MIN_STATES = 50_000
#: seed of the random states
RANDOM_SEED = 11


@dataclass
class StrategyResult:
    """What verification found for one strategy."""

    strategy: str
    states: int
    mismatches: int
    sources: dict[str, int]
    faulted_states: int
    mismatches_per_field: dict[str, int] = field(default_factory=dict)
    first_mismatch: str = ""
    wall_s: float = 0.0
    states_per_s: float = 0.0
    #: the target whose generated C ``c_hash`` names: the config's ``target.name``
    c_hash_target: str = ""
    #: C hash (``codegen.manifest``) of the C ``generate`` writes for ``c_hash_target``: what ships
    c_hash: str = ""
    #: the target of the C this run compiled and compared: always the host
    compiled_target: str = ""
    #: C hash of that host C: what was compiled (``c_hash`` too when ``c_hash_target`` is the host)
    compiled_c_hash: str = ""
    #: fixed point: per saturating operation (``q_div at ttype/reference.py:236``), the states passing
    #: the input guard on which it saturated (empty: none did, or a float format)
    saturations: dict[str, int] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def verify_strategy(
    model: Model,
    n_states: int,
    log: Callable[[str], None] = print,
    closed_loop: bool = True,
) -> StrategyResult:
    """Verify one variant (``model.controller.strategy``) over exactly ``n_states`` states.

    The mix: the variant's closed-loop states (at most 8 %, evenly sampled if
    the run is longer), adversarial states (20 %, at most 200 000), random
    states for the rest.
    """
    t0 = time.perf_counter()
    workers()  # a bad MPCGEN_JOBS is an error before anything is built
    topo = topology_of(model)
    tables = topo.derive(model)
    lib = topo.host_library(model, tables, with_sim=closed_loop)
    parts: dict[str, np.ndarray] = {}
    if closed_loop:
        parts["closed_loop"] = evenly_spaced(topo.closed_loop_states(model, lib), n_states * 8 // 100)
    n_adv = min(200_000, n_states // 5)
    parts["adversarial"] = topo.adversarial_states(model, tables, max(n_adv, 1000))[:n_adv]
    n_random = max(n_states - sum(len(p) for p in parts.values()), 0)
    parts["random"] = topo.random_states(model, tables, n_random, RANDOM_SEED)
    ref_step: Callable[[np.ndarray], Any] = functools.partial(topo.step_batch, tables)
    if number_format(model.controller.number_format).quantised:
        ref_step = functools.partial(counting_saturations, ref_step)
    result = compare_batches(model.controller.strategy, parts, ref_step, lib.step_batch, log, t0)
    if result.saturations:
        passing = result.states - result.faulted_states
        for site, k in result.saturations.items():
            log(f"  {result.strategy:12s} saturates {site}: {k} of {passing} states passing the guard")
    return named_c(result, model, tables)


def counting_saturations(ref_step: Callable[[np.ndarray], np.ndarray],
                         x: np.ndarray) -> tuple[np.ndarray, dict[str, int]]:
    """``ref_step(x)`` and, per saturating operation, the states of ``x`` passing the input guard that
    saturate it (module doc); picklable as a partial for the process pool."""
    with count_saturations(len(x)) as rec:
        out = ref_step(x)
    return out, rec.counts(out["fault"] == 0)


def named_c(result: StrategyResult, model: Model, tables: Any) -> StrategyResult:
    """``result`` of verifying ``model`` (derived ``tables``) with the C it is about, by C hash
    (``codegen.manifest``): ``compiled_c_hash``, the host C it compiled (``compiled_target``), and
    ``c_hash``, the C ``generate`` writes for the config's target (``c_hash_target``), the same
    arithmetic in the target's placement."""
    compiled = c_hash_of(sources(model, COMPILED_TARGET, tables))
    shipped = compiled if model.target == COMPILED_TARGET else c_hash_of(sources(model, model.target, tables))
    return replace(result, c_hash_target=model.target, c_hash=shipped, compiled_target=COMPILED_TARGET,
                   compiled_c_hash=compiled)


def workers() -> int:
    """Processes the reference runs in: every core (``MPCGEN_JOBS`` overrides); UsageError for a
    value that is not a positive integer."""
    text = os.environ.get("MPCGEN_JOBS")
    if not text:
        return os.cpu_count() or 1
    if not text.strip().isdigit() or int(text) < 1:
        raise UsageError(f"MPCGEN_JOBS = {text!r}: must be a positive integer (the processes verify uses)")
    return int(text)


def chunking(total: int) -> tuple[int, int]:
    """(processes, states per chunk) :func:`compare_batches` uses for ``total`` states."""
    n_jobs = workers() if total >= PARALLEL_MIN_STATES else 1
    return n_jobs, CHUNK if n_jobs == 1 else min(CHUNK, max(10_000, -(-total // (4 * n_jobs))))


# ---------------------------------------------------------------- memory, estimated before anything runs

#: float64 temporaries per state while the random states are drawn (a few columns at a time)
DRAW_BYTES_PER_STATE = 24
#: working set of one chunk in the process that runs the reference on it, per state, in units of
#: (input + output record): the candidates' intermediate columns (measured: 3-8; 10 kept as margin)
CHUNK_WORK_RECORDS = 10
#: what the main process maps beyond its arrays once it runs (the host libraries, the pool's threads
#: and their malloc arenas), on top of what it maps when the estimate is made
RUNTIME_BYTES = 512 * 1024**2
#: closed-loop phase, per simulated period, in units of the shared trace record (the topology's own
#: trace fields, the recorded inputs of every run it makes)
CLOSED_LOOP_TRACE_RECORDS = 4


@dataclass(frozen=True)
class VerifyMemory:
    """Estimated memory of verifying one strategy over ``states`` states (every figure in bytes).

    The main process holds the states twice (the parts, then their concatenation:
    ``2 * in_bytes``), the float64 columns of the random draw, and with a process pool every chunk's
    reference outputs until they are compared (``out_bytes``, the worst case); each process working on
    a chunk holds ``chunk_bytes``; the closed-loop run before them holds its trace.
    """

    strategy: str
    states: int
    jobs: int
    chunk: int
    in_bytes: int
    out_bytes: int
    closed_loop_bytes: int

    @property
    def per_state(self) -> int:
        """Bytes the main process holds per state."""
        return 2 * self.in_bytes + DRAW_BYTES_PER_STATE + (self.out_bytes if self.jobs > 1 else 0)

    @property
    def chunk_bytes(self) -> int:
        """Working set of one chunk (reference outputs and intermediates, C outputs, the comparison)."""
        return self.chunk * CHUNK_WORK_RECORDS * (self.in_bytes + self.out_bytes)

    @property
    def main_bytes(self) -> int:
        """Peak of the main process (its address space)."""
        return self.states * self.per_state + self.chunk_bytes + self.closed_loop_bytes + RUNTIME_BYTES

    @property
    def total_bytes(self) -> int:
        """Peak of every process together (the machine's memory): the workers' chunks added."""
        return self.main_bytes + (self.jobs * self.chunk_bytes if self.jobs > 1 else 0)

    def describe(self) -> str:
        pool = f", {self.jobs} processes" if self.jobs > 1 else ""
        outs = f" + its {self.out_bytes}-byte output held for the pool" if self.jobs > 1 else ""
        return (f"{self.states} states x {self.per_state} bytes (the {self.in_bytes}-byte input record twice"
                f"{outs}) + chunks of {self.chunk} states{pool}")


def verify_memory(model: Model, n_states: int, closed_loop: bool = True) -> VerifyMemory:
    """The memory estimate of ``verify_strategy(model, n_states, closed_loop=...)`` (its strategy's
    record sizes in its number format, its chunking)."""
    from codegen.simulator.driver import n_periods
    from codegen.simulator.memory import bytes_per_period
    from codegen.simulator.records import SIM_TRACE
    from codegen.stages.fwdata import layouts

    inp, out = layouts(model)
    jobs, chunk = chunking(n_states)
    loop = n_periods(model) * CLOSED_LOOP_TRACE_RECORDS * (bytes_per_period(SIM_TRACE) + inp.dtype.itemsize) \
        if closed_loop else 0
    return VerifyMemory(model.controller.strategy, n_states, jobs, chunk, inp.dtype.itemsize, out.dtype.itemsize,
                        loop)


def check_verify_memory(model: Model, strategies: list[str], n_states: int, closed_loop: bool = True,
                        option: str = "--states") -> list[VerifyMemory]:
    """Refuse (UsageError, exit 2) a verification whose estimated memory (:func:`verify_memory`, the
    largest of its strategies: they run one after the other) exceeds what this process may still
    allocate (:func:`codegen.simulator.memory.memory_room`: the address-space limit for the main
    process, the available memory for every process together).  Returns the estimates."""
    from codegen.simulator.memory import gb, memory_room

    estimates = [verify_memory(model.with_controller(strategy=s), n_states, closed_loop) for s in strategies]
    worst = max(estimates, key=lambda e: e.total_bytes)
    for what, room, own in memory_room():
        need = worst.main_bytes if own else worst.total_bytes
        if need > room:
            fixed = need - n_states * worst.per_state
            fits = max(0, (room - fixed) // worst.per_state)
            raise UsageError(
                f"{option} = {n_states}: verifying {worst.strategy} would take about {gb(need)} "
                f"({worst.describe()}), more than {what} leaves ({gb(room)}): at most about {fits} states fit")
    return estimates


def compare_batches(strategy: str, parts: dict[str, np.ndarray], ref_step: Callable[[np.ndarray], Any],
                    c_step: Callable[[np.ndarray], np.ndarray], log: Callable[[str], None], t0: float) -> StrategyResult:
    """Run both implementations over every state (in chunks of :func:`chunking`) and compare bits.
    ``ref_step`` returns the reference outputs, or (outputs, saturation counts) (:func:`counting_saturations`).

    The Python reference, the slow side, runs in a process pool on every core
    (``ref_step`` must be picklable: a module function, or a partial of one);
    the compiled C and the comparison run here, chunk by chunk, in order.
    """
    states = np.concatenate(list(parts.values()))
    total = len(states)
    n_jobs, size = chunking(total)
    bounds = [(lo, min(lo + size, total)) for lo in range(0, total, size)]
    mismatches = 0
    per_field: dict[str, int] = {}
    first = ""
    faulted = 0
    saturations: dict[str, int] = {}
    with contextlib.ExitStack() as stack:
        if n_jobs > 1:
            pool = stack.enter_context(ProcessPoolExecutor(n_jobs, mp_context=multiprocessing.get_context("fork")))
            refs: Iterator[Any] = (f.result() for f in [pool.submit(ref_step, states[a:b]) for a, b in bounds])
        else:
            refs = (ref_step(states[a:b]) for a, b in bounds)
        for (lo, hi), ref in zip(bounds, refs):
            if isinstance(ref, tuple):
                ref, sat = ref
                for k, v in sat.items():
                    saturations[k] = saturations.get(k, 0) + v
            x = states[lo:hi]
            got = c_step(x)
            bad, pf = mismatch_mask(ref, got)
            faulted += int((ref["fault"] != 0).sum())
            for k, v in pf.items():
                per_field[k] = per_field.get(k, 0) + v
            nb = int(bad.sum())
            if nb and not first:
                i = int(np.flatnonzero(bad)[0])
                first = f"state #{lo + i}:\n" + describe_mismatch(x[i], ref[i], got[i])
            mismatches += nb
            log(f"  {strategy:12s} {hi:>9d}/{total} states, {mismatches} mismatches")
    wall = time.perf_counter() - t0
    return StrategyResult(
        strategy=strategy,
        states=total,
        mismatches=mismatches,
        sources={k: len(v) for k, v in parts.items()},
        faulted_states=faulted,
        mismatches_per_field=per_field,
        first_mismatch=first,
        wall_s=wall,
        states_per_s=total / wall if wall > 0 else 0.0,
        saturations=dict(sorted(saturations.items())),
    )
