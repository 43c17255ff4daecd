"""Figure helpers every topology's plots share (matplotlib object API, Agg canvas, no GUI).

Figures are built with ``matplotlib.figure.Figure`` rendered by the Agg
canvas, so no pyplot state and no display are involved.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

__all__ = ["new_figure", "save_figure"]

DPI = 120
SIZE_IN = (9.0, 4.5)


def new_figure(nrows: int = 1, height: float = SIZE_IN[1]) -> tuple[Figure, Any]:
    """A figure with ``nrows`` stacked axes (returned as a 1-d array)."""
    fig = Figure(figsize=(SIZE_IN[0], height), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, 1, squeeze=False)[:, 0]
    return fig, axes


def save_figure(fig: Figure, path: Path) -> Path:
    """Write ``fig`` as PNG to ``path``; return the path."""
    fig.savefig(path, format="png")
    return path
