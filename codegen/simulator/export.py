"""``mpcgen simulate --traces FILE``: the time series of every run, one column per signal.

Columns are the trace struct's fields (:func:`codegen.simulator.driver.trace_fields`,
names with their unit: ``t_s``, ``ia_a``, ``te_nm``) and ``load_nm``; a
field with w > 1 values per period (the T-type's per-segment ``uab_v``,
``seg_s``, ``seg_states``) gives the columns ``name[0]`` .. ``name[w-1]``.

* ``FILE.npz``: one array per run and column, key ``<strategy>/<run>/<column>``
  (``numpy.load``); each run is written as it finishes, so no two runs are
  held in memory at once.
* ``FILE.csv``: one header line ``strategy,run,<columns>`` and one line per
  period of every run (values as ``%.17g``: float64 exactly, float32 and
  integers as their float64 value); every run of one file has the same columns.
"""
from __future__ import annotations

import contextlib
import io
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any, TextIO

import numpy as np

__all__ = ["TraceWriter", "trace_columns"]


def trace_columns(trace: Any, fields: list[str]) -> dict[str, np.ndarray]:
    """The columns of one run: ``fields`` of ``trace`` (2-D ones split per value), in order."""
    out: dict[str, np.ndarray] = {}
    for name in fields:
        arr = np.asarray(getattr(trace, name))
        if arr.ndim == 1:
            out[name] = arr
        else:
            for j in range(arr.shape[1]):
                out[f"{name}[{j}]"] = arr[:, j]
    return out


class TraceWriter:
    """Writes the runs of one ``simulate`` into ``path`` (npz, or CSV when the name ends in .csv)."""

    def __init__(self, path: Path, fields: list[str]) -> None:
        self.path = Path(path)
        self.fields = [*fields, "load_nm"]
        self.csv = self.path.suffix.lower() == ".csv"
        self._zip: zipfile.ZipFile | None = None
        self._text: TextIO | None = None
        self._header: list[str] | None = None

    def add(self, strategy: str, run: str, trace: Any) -> None:
        """Append one run."""
        cols = trace_columns(trace, self.fields)
        if self.csv:
            self._add_csv(strategy, run, cols)
        else:
            if self._zip is None:
                self._zip = zipfile.ZipFile(self.path, "w", compression=zipfile.ZIP_DEFLATED, allowZip64=True)
            for name, arr in cols.items():
                with self._zip.open(f"{strategy}/{run}/{name}.npy", "w", force_zip64=True) as f:
                    np.lib.format.write_array(f, np.ascontiguousarray(arr), allow_pickle=False)

    def _add_csv(self, strategy: str, run: str, cols: dict[str, np.ndarray]) -> None:
        if self._text is None:
            self._text = open(self.path, "w", newline="")
            self._header = list(cols)
            self._text.write(",".join(["strategy", "run", *self._header]) + "\n")
        assert self._header is not None
        if list(cols) != self._header:
            raise ValueError(f"run {strategy}/{run} has other columns than the first run of {self.path}")
        table = np.column_stack([np.asarray(c, dtype=np.float64) for c in cols.values()])
        buf = io.StringIO()
        np.savetxt(buf, table, fmt="%.17g", delimiter=",")
        prefix = f"{strategy},{run},"
        self._text.writelines(prefix + line + "\n" for line in buf.getvalue().splitlines())

    def close(self) -> None:
        """Finish the file."""
        if self._zip is not None:
            self._zip.close()
        if self._text is not None:
            self._text.close()

    def __enter__(self) -> TraceWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


@contextlib.contextmanager
def trace_writer(path: Path | None, trace: Any) -> Iterator[TraceWriter | None]:
    """A :class:`TraceWriter` of the trace struct ``trace``'s fields to ``path`` (None: no writer),
    closed when the block ends."""
    from codegen.simulator.driver import trace_fields

    writer = TraceWriter(path, list(trace_fields(trace))) if path is not None else None
    try:
        yield writer
    finally:
        if writer is not None:
            writer.close()
