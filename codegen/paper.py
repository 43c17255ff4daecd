"""Published figures next to ours (``mpcgen simulate --paper``): cells, ratios, the "none" answer.

Each topology's ``paper`` module lays out its seed's tables; this module
holds what they share.  A compared figure is a dict ``{"published", "ours",
"ours_over_published"}`` (JSON-ready; None where a side is missing), a ratio
the paper draws is ``{"name", "published", "ours"}`` in percent.
"""
from __future__ import annotations

import math
from typing import Any, NamedTuple

__all__ = ["SeedMotor", "side", "percent", "pair_cell", "pct_cell", "no_figures", "pair_head"]



class SeedMotor(NamedTuple):
    """A seed paper's motor, as published (rated values where the paper gives them): a config runs
    the paper's case, and the published figures apply, only with these parameters."""

    rs_ohm: float
    ld_h: float
    lq_h: float
    psi_f_wb: float
    pole_pairs: int
    rated_speed_rpm: float | None = None
    rated_torque_nm: float | None = None


def _num(v: Any) -> float | None:
    return float(v) if isinstance(v, (int, float)) and math.isfinite(float(v)) else None


def side(published: Any, ours: Any) -> dict[str, float | None]:
    """One compared figure: both values and ours / published (None when either is missing or 0)."""
    p, o = _num(published), _num(ours)
    return {"published": p, "ours": o, "ours_over_published": o / p if p and o is not None else None}


def percent(a: Any, b: Any) -> float | None:
    """100 * a / b, or None."""
    x, y = _num(a), _num(b)
    return 100.0 * x / y if x is not None and y else None


def _width(spec: str) -> int:
    """Width of a cell formatted with ``spec`` (float or integer spec)."""
    return len(format(0, spec)) if spec.endswith("d") else len(format(0.0, spec))


def _fmt(v: float | None, spec: str) -> str:
    width = _width(spec)
    return f"{'n/a':>{width}}" if v is None else format(v, spec)


def pair_head(title: str, spec: str) -> str:
    """The heading of a :func:`pair_cell` column, as wide as the cell."""
    w = 2 * _width(spec) + 1
    return f"{title:>{w}s}"


def pair_cell(c: Any, spec: str, scale: float = 1.0) -> str:
    """``published ours`` of a compared figure (``scale`` applied to both, e.g. 1e-3 for kHz)."""
    p, o = c["published"], c["ours"]
    return (f"{_fmt(None if p is None else p * scale, spec)} "
            f"{_fmt(None if o is None else o * scale, spec)}")


def pct_cell(v: Any, width: int = 7) -> str:
    """A percentage cell ("n/a" when missing)."""
    return f"{'n/a':>{width}}" if v is None else f"{v:{width}.2f}"


def no_figures(reason: str) -> dict[str, Any]:
    """The answer of a topology with no published figures for this config or scenario: one line."""
    return {"available": False, "reason": reason, "_table": f"paper: no published figures: {reason}"}
