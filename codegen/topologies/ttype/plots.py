"""PNG plots of a closed-loop three-level run (matplotlib, Agg canvas, no GUI).

Plot list: docs/simulation.md "Plots" (speed, torque and reference, flux
magnitude, flux locus, phase currents, spectrum of i_a, and for the
three-level inverter V_o and u_ab).  Figures use the object-oriented API
(codegen/plotting.py, codegen/simulator/figures.py).  The zooms, the locus
window and the spectrum are those of the THD the run's metric result reports
(``window["THD_ia_percent"]``).
"""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from codegen.metrics import sample_time
from codegen.model import Model
from codegen.plotting import heading, new_figure, plot_lines, save_figure, span
from codegen.simulator import figures

if TYPE_CHECKING:  # pragma: no cover
    from codegen.topologies.ttype.sim import Trace

__all__ = ["plot_three_level", "uab_steps"]

def uab_steps(trace: Trace, sl: slice) -> tuple[np.ndarray, np.ndarray]:
    """(t, u_ab) step-plot points of the applied segments of periods sl (zero-length dropped)."""
    dt = trace.dt_s
    k = np.arange(sl.start, sl.stop)
    seg = trace.seg_s[sl]
    starts = k[:, None] * dt + np.concatenate((np.zeros((seg.shape[0], 1)), np.cumsum(seg, axis=1)[:, :-1]), axis=1)
    keep = seg.ravel() > 0
    t0 = starts.ravel()[keep]
    v = trace.uab_v[sl].ravel()[keep]
    # left edges + the end of the last segment, for drawstyle="steps-post"
    t = np.append(t0, sl.stop * dt)
    v = np.append(v, v[-1] if v.size else 0.0)
    return t, v


def plot_three_level(trace: Trace, model: Model, tag: str, run: str, outdir: str | Path,
                     metrics: dict[str, Any]) -> list[Path]:
    """Write ``<tag>_{speed,torque,flux,locus,currents,spectrum,vo,uab}.png`` into outdir.

    ``tag`` names the files (strategy and run), ``run`` describes the run in
    every title; ``metrics``: the metric result the table reports for it
    (the spectrum, the locus window and the zooms use its THD window and
    fundamental: currents over two fundamental periods, u_ab over 10 control
    periods and over one fundamental period, each ending at the end of the
    THD window, or of the run when there is none).  Returns the paths written.
    """
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    title = f"{model.name}: {run}"
    t = trace.t_s
    dt = trace.dt_s
    tw = figures.thd_span(metrics)
    f1 = tw[2] if tw is not None else 0.0
    k_end = min(trace.n, int(round((tw[1] if tw is not None else trace.n * dt) / dt)))
    psi_ref = trace.psi_ref_wb.astype(np.float64)
    paths = [
        figures.plot_speed(out / f"{tag}_speed.png", title, trace),
        figures.plot_torque(out / f"{tag}_torque.png", title, trace),
        plot_lines(out / f"{tag}_flux.png", heading(title, f"stator-flux magnitude, {figures.run_span(trace)}"),
                   "stator flux |psi_s| / Wb", t, [
                       (trace.psi_wb, "plant |psi_s|", {"color": "tab:blue", "lw": 0.4}),
                       (psi_ref, "controller psi*", {"color": "k", "lw": 1.0}),
                   ]),
        figures.plot_flux_locus(out / f"{tag}_locus.png", title, trace, model, metrics, psi_ref),
        figures.plot_phase_currents(out / f"{tag}_currents.png", title, trace, figures.zoom_slice(trace, metrics, fallback_s=0.02)),
        figures.plot_spectrum(out / f"{tag}_spectrum.png", title, trace.ia_a, dt, metrics),
        plot_lines(out / f"{tag}_vo.png", heading(title, f"neutral-point voltage, {figures.run_span(trace)}"), "V_o / V", t,
                   [(trace.vo_v, "plant V_o = (u_c1 - u_c2)/2", {"color": "tab:blue", "lw": 0.5})],
                   hline=(0.0, "")),
    ]

    # line voltage: 10 control periods and one fundamental period
    half = 0.5 * trace.udc_v
    fig, axes = new_figure(2, height=7.0)
    fund = int(round((1.0 / f1) / dt)) if f1 > 0 else 400
    for ax, n_per, label in ((axes[0], 10, "10 control periods"), (axes[1], max(10, fund), "one fundamental period")):
        s = slice(max(0, k_end - n_per), k_end)
        if s.stop > s.start:
            tt, vv = uab_steps(trace, s)
            ax.plot(tt * 1e3, vv, drawstyle="steps-post", lw=0.7, color="tab:blue", label="u_ab")
        ax.set_yticks(np.arange(-4, 5) * half)
        ax.set(xlabel="time t / ms", ylabel="u_ab / V",
               title=heading(title, f"line voltage u_ab, {label} "
                             f"{span(sample_time(s.start, dt), sample_time(s.stop, dt))}"))
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right")
    paths.append(save_figure(fig, out / f"{tag}_uab.png"))
    return paths
