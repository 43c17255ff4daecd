"""Test data embedded in a firmware image: states, expected outputs, digests.

The self-test set is the topology's deterministic mix of guard cases and
random/adversarial states (:meth:`~codegen.topology.Topology.selftest_states`);
the bench set is its recorded closed-loop trajectory, evenly sampled.
Expected outputs always come from the Python reference.  Digests: CRC-32
(zlib) of every value in record order, in the canonical little-endian layout
of :class:`codegen.records.RecordLayout` (the firmware's ``mpc_values_crc``).

The image embeds the records in that same canonical layout, as 32-bit words
(:meth:`RecordLayout.words`), printed by :func:`c_words` in one numpy pass: no
Python loop over values, and a C initializer of plain integer constants that
compiles in a fraction of the time per-value float literals took.
"""
from __future__ import annotations

import fcntl
from typing import Any

import numpy as np

from codegen.hostbuild import cache_root
from codegen.model import Model
from codegen.numfmt import FLOAT_CONTROLLER, number_format
from codegen.records import RecordLayout
from codegen.teststates import in_format
from codegen.topology import Reference, topology_of

__all__ = ["SELFTEST_SEED", "WORDS_PER_LINE", "layouts", "in_step_format", "selftest_states", "trajectory_states",
           "expected_outputs", "evenly_spaced", "c_words"]

#: Seed of the self-test states (the set is a pure function of config and n).
SELFTEST_SEED = 20240604


def layouts(model: Model) -> tuple[RecordLayout, RecordLayout]:
    """The step's input and output records in the model's number format."""
    topo = topology_of(model)
    nf = number_format(model.controller.number_format)
    return topo.input_record.bind(nf), topo.output_record(model).bind(nf)


def in_step_format(model: Model, tables: Any, x: np.ndarray) -> np.ndarray:
    """Input records ``x`` (float32 SI values, or already in the step's format) in the format of
    ``tables`` (``tables.nf``: the derived step's format, bound to its scaling)."""
    return in_format(x, topology_of(model).input_record.bind(tables.nf))


def selftest_states(model: Model, tables: Any, n: int, seed: int = SELFTEST_SEED) -> np.ndarray:
    """``n`` deterministic self-test states of the model's topology (guard cases first), in the
    step's format."""
    return in_step_format(model, tables, topology_of(model).selftest_states(model, tables, n, seed))


#: states of the bench trajectory a firmware image embeds (timed on the board, traced by the cycle estimate)
N_BENCH = 2000


def evenly_spaced(x: np.ndarray, n: int) -> np.ndarray:
    """``n`` records (at most ``len(x)``) evenly spaced over ``x``, first and last included."""
    idx = np.linspace(0, len(x) - 1, num=min(n, len(x))).round().astype(np.intp)
    return x[idx]


def trajectory_states(model: Model, n: int) -> np.ndarray:
    """``n`` states evenly spaced over the topology's recorded benchmark trajectory, float32 SI
    values: the float32 controller's run, whatever the model's number format, so that every format's
    image replays the same states (``in_step_format`` converts them).

    The host build is taken under a file lock: parallel test workers share
    the build cache.
    """
    topo = topology_of(model)
    cache_root().mkdir(parents=True, exist_ok=True)
    with open(cache_root() / f"{model.prefix}.trajectory.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        traj = topo.trajectory(model.with_controller(number_format=FLOAT_CONTROLLER))
    return evenly_spaced(traj.states, n)


def expected_outputs(topo: Reference[Any], tables: Any, states: np.ndarray) -> np.ndarray:
    """The reference's outputs; every real output must be finite (an input-guard bug otherwise)."""
    out = topo.step_batch(tables, states)
    for name in out.dtype.names or ():
        if out.dtype[name].base.kind == "f" and not np.all(np.isfinite(out[name])):
            raise ValueError(f"reference output {name} is not finite for some state (input guard bug)")
    return out


#: 32-bit words per line of an embedded data array
WORDS_PER_LINE = 12


def c_words(words: np.ndarray, per_line: int = WORDS_PER_LINE, indent: str = "    ", suffix: str = "u") -> str:
    """The body of a C initializer of ``words`` (uint32): each word a hexadecimal constant without
    leading zeros, with ``suffix`` (``0x3f800000u,``, ``0x3u,``, zero as ``0u,``; ``suffix``: that of
    the target's uint32_t, ``u`` or ``ul``, so the compiler converts nothing), ``per_line`` a line,
    every line indented and ended by a newline.  Built as one character array by numpy (hexadecimal
    digits from the words' big-endian bytes, then a mask dropping leading zeros and the padding of
    the last line), with no Python loop over the values."""
    w = np.ascontiguousarray(words, dtype=np.uint32).ravel()
    if w.size == 0:
        return ""
    n_lines = -(-w.size // per_line)
    padded = np.zeros(n_lines * per_line, np.uint32)
    padded[:w.size] = w
    digits = np.frombuffer(padded.astype(">u4").tobytes().hex().encode("ascii"), np.uint8).reshape(-1, 8)
    significant = digits != ord("0")
    first = np.where(significant.any(axis=1), significant.argmax(axis=1), 8)  # first digit kept (8: none)
    tail = np.frombuffer((suffix + ",").encode("ascii"), np.uint8)
    cell = 10 + len(tail)  # "0x", 8 digits, suffix, ","
    cells = np.empty((padded.size, cell), np.uint8)
    cells[:, 0:2] = np.frombuffer(b"0x", np.uint8)
    cells[:, 2:10] = digits
    cells[:, 10:] = tail
    keep = np.ones((padded.size, cell), bool)
    keep[:, 1] = padded != 0  # zero is "0u,"
    keep[:, 2:10] = np.arange(8) >= first[:, None]
    keep[w.size:] = False  # the last line's padding
    lead = np.frombuffer(indent.encode("ascii"), np.uint8)
    width = len(lead) + per_line * cell + 1
    lines = np.empty((n_lines, width), np.uint8)
    lines[:, :len(lead)] = lead
    lines[:, len(lead):-1] = cells.reshape(n_lines, per_line * cell)
    lines[:, -1] = ord("\n")
    mask = np.ones((n_lines, width), bool)
    mask[:, len(lead):-1] = keep.reshape(n_lines, per_line * cell)
    return lines[mask].tobytes().decode("ascii")
