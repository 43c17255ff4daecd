"""Figure helpers every topology's plots share (matplotlib object API, Agg canvas, no GUI).

Figures are built with ``matplotlib.figure.Figure`` rendered by the Agg
canvas, so no pyplot state and no display are involved.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

__all__ = ["new_figure", "save_figure", "plot_lines", "plot_torque", "plot_phase_currents"]

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


def plot_torque(path: Path, title: str, trace: Any) -> Path:
    """Plant torque Te and the reference T* of a closed-loop run."""
    return plot_lines(path, f"{title}: electromagnetic torque", "torque / (N*m)", trace.t_s, [
        (trace.te_nm, "plant torque Te", {"color": "tab:blue", "lw": 0.4}),
        (trace.torque_ref_nm, "reference T*", {"color": "k", "lw": 1.0}),
    ])


def plot_phase_currents(path: Path, title: str, trace: Any, zoom: slice) -> Path:
    """Phase currents i_a, i_b, i_c over the whole run (top) and over ``zoom`` (bottom)."""
    fig, axes = new_figure(2, height=7.0)
    for ax, sl, label in ((axes[0], slice(0, trace.n), "whole run"), (axes[1], zoom, "zoom")):
        for name in ("ia_a", "ib_a", "ic_a"):
            ax.plot(trace.t_s[sl], getattr(trace, name)[sl], lw=0.5, label=f"i_{name[1]}")
        ax.set(xlabel="time t / s", ylabel="phase current / A", title=f"{title}: phase currents ({label})")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right")
    return save_figure(fig, path)
