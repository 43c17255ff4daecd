"""PNG plots of a closed-loop two-level run (matplotlib, Agg canvas, no GUI).

Figures are built with the object-oriented API (codegen/plotting.py, codegen/simulator/figures.py).
Plot list: docs/simulation.md "Plots" (speed, torque and reference, flux
magnitude, flux locus, phase currents, spectrum of i_a).  The zoom, the
locus window and the spectrum are those of the THD the run's metric result
reports (``window["THD_ia_percent"]``), never a window of their own.
"""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from codegen.model import Model
from codegen.plotting import heading, plot_lines
from codegen.simulator.figures import (
    plot_flux_locus,
    plot_phase_currents,
    plot_spectrum,
    plot_speed,
    plot_torque,
    run_span,
    scenario_label,
    zoom_slice,
)
from codegen.topologies.twolevel.metrics import flux_reference_of

if TYPE_CHECKING:  # pragma: no cover
    from codegen.topologies.twolevel.sim import Trace

__all__ = ["plot_two_level"]


def plot_two_level(trace: Trace, model: Model, strategy: str, outdir: str | Path,
                   metrics: dict[str, Any]) -> list[Path]:
    """Write ``<strategy>_{speed,torque,flux,locus,currents,spectrum}.png`` into outdir.

    ``metrics``: the run's metric result (``two_level_metrics``); the
    spectrum, the locus window and the current zoom use its THD window and
    fundamental.  Returns the paths written.
    """
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    title = f"{model.name}: {strategy}, config scenario ({scenario_label(model)})"
    psi_ref = flux_reference_of(trace, model)
    flux_lines = [(trace.psi_wb, "plant |psi_s|", {"color": "tab:blue", "lw": 0.4})]
    if np.ndim(psi_ref):
        flux_lines.append((psi_ref, "reference psi* (MTPA of T*)", {"color": "k", "lw": 1.0, "ls": "--"}))
    return [
        plot_speed(out / f"{strategy}_speed.png", title, trace),
        plot_torque(out / f"{strategy}_torque.png", title, trace),
        plot_lines(out / f"{strategy}_flux.png", heading(title, f"stator-flux magnitude, {run_span(trace)}"),
                   "stator flux |psi_s| / Wb", trace.t_s, flux_lines,
                   hline=None if np.ndim(psi_ref) else (float(psi_ref), "reference psi*")),
        plot_flux_locus(out / f"{strategy}_locus.png", title, trace, model, metrics, psi_ref),
        plot_phase_currents(out / f"{strategy}_currents.png", title, trace, zoom_slice(trace, metrics)),
        plot_spectrum(out / f"{strategy}_spectrum.png", title, trace.ia_a, trace.dt_s, metrics),
    ]
