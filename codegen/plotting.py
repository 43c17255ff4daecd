"""Figure helpers every figure of mpcgen shares (matplotlib object API, Agg canvas, no GUI).

Figures are built with ``matplotlib.figure.Figure`` rendered by the Agg
canvas, so no pyplot state and no display are involved.  Each PNG carries its
axes' titles in its ``Title`` text chunk and, where the figure says what it
shows (``save_figure(..., described=...)``), that in ``Description`` (JSON),
so that a test (or a reader) can check a figure against the figures it
claims to show.  The plots of a closed-loop run are in
``codegen.simulator.figures``.
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

__all__ = ["new_figure", "save_figure", "heading", "span", "plot_lines"]

DPI = 120
SIZE_IN = (9.0, 4.5)


def new_figure(nrows: int = 1, height: float = SIZE_IN[1]) -> tuple[Figure, Any]:
    """A figure with ``nrows`` stacked axes (returned as a 1-d array)."""
    fig = Figure(figsize=(SIZE_IN[0], height), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, 1, squeeze=False)[:, 0]
    return fig, axes


def save_figure(fig: Figure, path: Path, described: dict[str, Any] | None = None) -> Path:
    """Write ``fig`` as PNG to ``path``; return the path.  A two-line title (:func:`heading`) is set in
    10 pt, so that it fits the width.  The PNG's ``Title`` chunk holds the axes' titles (`` | `` between
    axes), ``Description`` the JSON of ``described`` (what the figure shows)."""
    titles = " | ".join(ax.get_title() for ax in fig.get_axes() if ax.get_title())
    for ax in fig.get_axes():
        if "\n" in ax.get_title():
            ax.title.set_fontsize(10)
    meta = {"Title": titles}
    if described is not None:
        meta["Description"] = json.dumps(described, sort_keys=True)
    fig.savefig(path, format="png", metadata=meta)
    return path


def heading(title: str, what: str) -> str:
    """A two-line axes title: the run (``title``), then what the plot shows and over which span."""
    return f"{title}\n{what}"


def span(t0_s: float, t1_s: float) -> str:
    """A time span as the tables print it: ``[t0, t1) s``, 4 significant digits."""
    return f"[{t0_s:.4g}, {t1_s:.4g}) s"


def plot_lines(path: Path, title: str, ylabel: str, t: Any,
               lines: list[tuple[Any, str, dict[str, Any]]], hline: tuple[float, str] | None = None) -> Path:
    """One time plot: ``lines`` = (values, label, matplotlib style), an optional
    horizontal reference (value, label); written as PNG to ``path``."""
    fig, (ax,) = new_figure()
    for y, label, style in lines:
        ax.plot(t, y, label=label, **style)
    if hline is not None:
        ax.axhline(hline[0], color="k", lw=1.0 if hline[1] else 0.8, label=hline[1] or None)
    ax.set(xlabel="time t / s", ylabel=ylabel, title=title)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best")
    return save_figure(fig, path)
