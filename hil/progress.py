"""The live progress line (stderr) and the cycle statistics of a run."""
from __future__ import annotations

import sys
import time
from collections.abc import Sequence
from typing import TextIO

import numpy as np

__all__ = ["cycle_stats", "Progress"]


def cycle_stats(cycles: np.ndarray) -> dict[str, int | None]:
    """min / median / p99 / max of the answered states' cycles (None when there are none)."""
    if len(cycles) == 0:
        return {"cycles_min": None, "cycles_median": None, "cycles_p99": None, "cycles_max": None}
    c = np.asarray(cycles, np.int64)
    return {"cycles_min": int(c.min()), "cycles_median": int(np.percentile(c, 50, method="nearest")),
            "cycles_p99": int(np.percentile(c, 99, method="nearest")), "cycles_max": int(c.max())}


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
        """Rewrite the line (``cycles``: the cycles answered so far)."""
        now = time.perf_counter()
        if not self.enabled or (not force and now - self._last < self.every_s):
            return
        self._last = now
        rate = done / max(now - self.t0, 1e-9)
        s = cycle_stats(np.asarray(cycles, np.int64))
        cyc = ("" if s["cycles_min"] is None else
               f"  {self.unit} min/med/p99/max {s['cycles_min']}/{s['cycles_median']}/{s['cycles_p99']}/{s['cycles_max']}")
        self.stream.write(f"\r{self.label}: {done}/{self.total} states  {rate:,.0f} states/s  "
                          f"mismatches {mismatches}{cyc}   ")
        self.stream.flush()
        self._shown = True

    def close(self) -> None:
        """End the line."""
        if self.enabled and self._shown:
            self.stream.write("\n")
            self.stream.flush()
