"""The live progress line (stderr), the timing statistics of a run and the wire counters on the console.

Timing keys are named by what the board counts (:func:`timing_prefix`): a
board's INFO gives the unit of its RESULT timings, ``ns`` on the virtual
board (the host's CLOCK_MONOTONIC), ``instructions`` under QEMU (-icount),
``cycles`` on silicon (DWT, the C28x timer).  ``cycles_*`` keys are
therefore those of a real board only.
"""
from __future__ import annotations

import re
import sys
import time
from collections.abc import Mapping, Sequence
from typing import Any, TextIO

import numpy as np

__all__ = ["cycle_stats", "timing_prefix", "timing_label", "rename_timing_keys", "wire_note", "Progress"]

#: timing unit of a board's INFO -> prefix of the JSON keys
_PREFIX = {"ns": "host_ns", "instructions": "instructions", "cycles": "cycles"}


def timing_prefix(unit: str) -> str:
    """The JSON key prefix of timings counted in ``unit``: host_ns, instructions, cycles (others: the unit)."""
    return _PREFIX.get(unit) or re.sub(r"[^a-z0-9]+", "_", unit.lower()).strip("_") or "timing"


def timing_label(unit: str) -> str:
    """The console label of timings counted in ``unit`` ("host ns", "instructions", "cycles")."""
    return timing_prefix(unit).replace("_", " ")


def cycle_stats(cycles: np.ndarray, prefix: str = "cycles") -> dict[str, int | None]:
    """min / median / p99 / max of the answered states' timings (None when there are none),
    under ``{prefix}_min`` ... (``prefix``: :func:`timing_prefix` of the board's unit)."""
    if len(cycles) == 0:
        return {f"{prefix}_min": None, f"{prefix}_median": None, f"{prefix}_p99": None, f"{prefix}_max": None}
    c = np.asarray(cycles, np.int64)
    return {f"{prefix}_min": int(c.min()), f"{prefix}_median": int(np.percentile(c, 50, method="nearest")),
            f"{prefix}_p99": int(np.percentile(c, 99, method="nearest")), f"{prefix}_max": int(c.max())}


def rename_timing_keys(data: dict[str, Any], unit: str) -> dict[str, Any]:
    """``data`` with its ``cycles_*`` keys named by ``unit`` (:func:`timing_prefix`), order kept."""
    prefix = timing_prefix(unit)
    return {(prefix + k[len("cycles"):] if k.startswith("cycles_") else k): v for k, v in data.items()}


def wire_note(wire: Mapping[str, Any]) -> str:
    """The wire counters that are not zero, for the summary line ("" on a perfect link)."""
    parts = []
    for key, label in (("resent_states", "resent"), ("duplicates", "duplicates"), ("reordered", "reordered"),
                       ("unexpected", "unexpected"), ("resets", "resets"),
                       ("handshake_retries", "handshake retries")):
        if wire.get(key):
            parts.append(f"{label} {wire[key]}")
    for key, label in (("discarded", "discarded"), ("board_errors", "board errors")):
        by = {k: v for k, v in dict(wire.get(key) or {}).items() if v}
        if by:
            parts.append(f"{label} {sum(by.values())} ("
                         + ", ".join(f"{k} {v}" for k, v in sorted(by.items())) + ")")
    if wire.get("silent"):
        parts.append("board silent")
    return "  wire: " + ", ".join(parts) if parts else ""


class Progress:
    """A one-line status rewritten in place at most every ``every_s`` seconds."""

    def __init__(self, label: str, total: int, unit: str, stream: TextIO | None = None,
                 enabled: bool = True, every_s: float = 0.25) -> None:
        self.label, self.total, self.unit = label, total, unit
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled
        self.every_s = every_s
        self.t0 = time.perf_counter()
        self._last = 0.0
        self._shown = False

    def update(self, done: int, mismatches: int, cycles: Sequence[int] | np.ndarray, force: bool = False) -> None:
        """Rewrite the line (``cycles``: the timings answered so far, in the board's unit)."""
        now = time.perf_counter()
        if not self.enabled or (not force and now - self._last < self.every_s):
            return
        self._last = now
        rate = done / max(now - self.t0, 1e-9)
        s = cycle_stats(np.asarray(cycles, np.int64), "t")
        cyc = ("" if s["t_min"] is None else
               f"  {timing_label(self.unit)} min/med/p99/max {s['t_min']}/{s['t_median']}/{s['t_p99']}/{s['t_max']}")
        self.stream.write(f"\r{self.label}: {done}/{self.total} states  {rate:,.0f} states/s  "
                          f"mismatches {mismatches}{cyc}   ")
        self.stream.flush()
        self._shown = True

    def close(self) -> None:
        """End the line."""
        if self.enabled and self._shown:
            self.stream.write("\n")
            self.stream.flush()
