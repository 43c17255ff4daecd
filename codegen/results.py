"""JSON-ready results every stage and topology writes: cleaning, versions, table cells."""
from __future__ import annotations

import math
import platform
from pathlib import Path
from typing import Any

import numpy as np

from codegen import __version__

__all__ = ["clean_json", "metric_sets", "versions", "fmt_cell", "flagged_cell", "footnotes", "fault_warning", "WINDOW_HEAD", "window_cells"]


def clean_json(v: Any) -> Any:
    """JSON-safe: NaN/inf -> None, numpy scalars -> Python, recursively."""
    if isinstance(v, dict):
        return {k: clean_json(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [clean_json(x) for x in v]
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v


def versions() -> dict[str, str]:
    """Versions that determine the results."""
    import cffi
    import scipy

    return {"mpcgen": __version__, "python": platform.python_version(), "numpy": np.__version__,
            "scipy": scipy.__version__, "cffi": cffi.__version__}


def fmt_cell(v: Any, spec: str) -> str:
    """A table cell: ``format(v, spec)``, or ``n/a`` for a missing or non-finite value."""
    return "   n/a" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(v, spec)


def flagged_cell(m: dict[str, Any], key: str, spec: str, scale: float = 1.0) -> str:
    """A metric's table cell: ``n/a`` when not computed, the value with ``*`` when its window is not
    steady (``m["not_steady"]``), else the value (``m[key] * scale`` formatted with ``spec``)."""
    v = m.get(key)
    if key in m.get("not_computed", {}) or v is None or (isinstance(v, float) and not math.isfinite(v)):
        return f"{'n/a':>{len(format(0.0, spec))}} "
    mark = "*" if key in m.get("not_steady", {}) else " "
    return format(v * scale, spec) + mark


def footnotes(rows: dict[str, dict[str, Any]], shown: tuple[str, ...]) -> list[str]:
    """Footnote lines of a metric table: each ``shown`` metric of each row flagged ``*`` (window not
    steady) or ``n/a`` (not computed), with its reason."""
    out: list[str] = []
    for label, m in rows.items():
        for key in shown:
            if key in m.get("not_computed", {}):
                out.append(f"  n/a {label} {key}: not computed: {m['not_computed'][key]}")
            elif key in m.get("not_steady", {}):
                out.append(f"  * {label} {key}: window not steady: {m['not_steady'][key]}")
    return out


def fault_warning(label: str, periods: int, m: dict[str, Any]) -> str | None:
    """One stderr line for a run whose guard tripped (None when it never did)."""
    if not m.get("faults"):
        return None
    kinds = ", ".join(f"{k} {n}" for k, n in m.get("fault_counts", {}).items() if n)
    return (f"{label}: {m['faults']} of {periods} periods returned the safe decision "
            f"(guard faults: {kinds}); its figures describe a tripped drive")


#: heading of the cells :func:`window_cells` prints
WINDOW_HEAD = f"{'THD window/s':>17s} {'f1/Hz':>8s} {'periods':>7s}"


def window_cells(info: dict[str, Any]) -> str:
    """The THD window of a table row: [t0, t1) in s, fundamental f1 in Hz and whole periods in it."""
    if "n_periods" not in info or "not_computed_reason" in info:
        return f"{'n/a':>17s} {'n/a':>8s} {'n/a':>7s}"
    span = f"[{info['t0_s']:.4g}, {info['t1_s']:.4g})"
    return f"{span:>17s} {info['f1_hz']:8.4g} {info['n_periods']:7d}"


def emit(text: str, out_dir: Path | None, write_all: Any, data: dict[str, Any]) -> None:
    """A study's result: its markdown ``text`` on stdout when ``out_dir`` is None, else the files
    ``write_all(out_dir, data, text)`` writes (their paths printed, one a line)."""
    if out_dir is None:
        print(text, end="")
        return
    for p in write_all(out_dir, data, text):
        print(p)


def write_csv_rows(path: Path, rows: list[dict[str, object]]) -> None:
    """Rows with possibly different keys as one CSV: the union of the keys, in first-seen order."""
    import csv

    columns: dict[str, None] = {}
    for r in rows:
        columns.update(dict.fromkeys(r))
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(columns))
        w.writeheader()
        w.writerows(rows)


def metric_sets(result: dict[str, Any]) -> list[tuple[str, str | None, dict[str, Any]]]:
    """(strategy, scenario run or None, metrics) of one run's simulate result."""
    out: list[tuple[str, str | None, dict[str, Any]]] = []
    for s, m in result.get("strategies", {}).items():
        if not isinstance(m, dict):
            continue
        if "faults" in m or "T_rip_RMSE_nm" in m:
            out.append((s, None, m))
        else:  # a scenario set: one metrics dict per scenario run
            out.extend((s, name, mm) for name, mm in m.items() if isinstance(mm, dict))
    return out
