"""PNG plots of a closed-loop two-level run (matplotlib, Agg canvas, no GUI).

Figures are built with the object-oriented API (``matplotlib.figure.Figure``
rendered by the Agg canvas), so no pyplot state and no display are involved.
Plot list: docs/simulation.md, last paragraph (speed, torque and
reference, flux magnitude, phase currents, spectrum of i_a).
"""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from codegen.metrics import amplitude_spectrum, fundamental_hz, thd, thd_window, window_slice
from codegen.model import Model
from codegen.plotting import new_figure, plot_lines, plot_phase_currents, plot_torque, save_figure
from codegen.topologies.twolevel.metrics import flux_reference_of

if TYPE_CHECKING:  # pragma: no cover
    from codegen.topologies.twolevel.sim import Trace

__all__ = ["plot_two_level"]

def plot_two_level(trace: Trace, model: Model, strategy: str, outdir: str | Path) -> list[Path]:
    """Write ``<strategy>_{speed,torque,flux,currents,spectrum}.png`` into outdir.

    Returns the paths written.  The spectrum uses the THD window of
    :func:`codegen.metrics.thd_window` (last steady window with nonzero speed);
    when there is none, the spectrum figure says so instead of plotting.
    """
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    t = trace.t_s
    title = f"{model.name}: {strategy}"
    paths: list[Path] = []

    paths.append(plot_lines(out / f"{strategy}_speed.png", f"{title}: rotor speed", "speed n / (r/min)", t, [
        (trace.speed_ref_rpm, "reference n*", {"color": "k", "lw": 1.0, "ls": "--"}),
        (trace.speed_rpm, "actual n", {"color": "tab:blue", "lw": 0.8}),
    ]))
    paths.append(plot_torque(out / f"{strategy}_torque.png", title, trace))
    psi_ref = flux_reference_of(trace, model)
    flux_lines = [(trace.psi_wb, "plant |psi_s|", {"color": "tab:blue", "lw": 0.4})]
    if np.ndim(psi_ref):
        flux_lines.append((psi_ref, "reference psi* (MTPA of T*)", {"color": "k", "lw": 1.0, "ls": "--"}))
    paths.append(plot_lines(out / f"{strategy}_flux.png", f"{title}: stator-flux magnitude",
                            "stator flux |psi_s| / Wb", t, flux_lines,
                            hline=None if np.ndim(psi_ref) else (float(psi_ref), "reference psi*")))

    # phase currents: whole run + zoom on two fundamental periods of the THD window
    tw = thd_window(trace, model)
    if tw is not None:
        f1 = fundamental_hz(trace, model, *tw)
        span = 2.0 / f1 if f1 > 0 else tw[1] - tw[0]
        zoom = window_slice(trace.dt_s, max(tw[0], tw[1] - span), tw[1], trace.n)
    else:
        zoom = slice(max(0, trace.n - int(round(0.05 / trace.dt_s))), trace.n)
    paths.append(plot_phase_currents(out / f"{strategy}_currents.png", title, trace, zoom))

    # spectrum of i_a over the THD window
    fig, (ax,) = new_figure()
    drawn = False
    if tw is not None:
        f1 = fundamental_hz(trace, model, *tw)
        try:
            freqs, amp, info = amplitude_spectrum(trace.ia_a, trace.dt_s, tw[0], tw[1], f1)
            thd_pct, tinfo = thd(trace.ia_a, trace.dt_s, tw[0], tw[1], f1)
        except ValueError:
            pass
        else:
            i1 = tinfo["i1_peak"]
            keep = freqs <= tinfo["f_limit_hz"]
            rel = 100.0 * amp[keep] / i1 if i1 > 0 else amp[keep]
            ax.vlines(freqs[keep], 0.0, rel, lw=0.8)
            ax.set_yscale("symlog", linthresh=0.1)
            ax.set(
                xlabel="frequency f / Hz",
                ylabel="amplitude / % of fundamental",
                title=(
                    f"{title}: spectrum of i_a, [{info['t0_s']:.4g}, {info['t1_s']:.4g}) s, "
                    f"{info['n_periods']} periods of {info['f1_used_hz']:.4g} Hz, "
                    f"THD = {thd_pct:.2f} % (h = 2..{tinfo['harmonics'][1]})"
                ),
            )
            ax.title.set_fontsize(9)
            ax.grid(True, alpha=0.3)
            drawn = True
    if not drawn:
        ax.text(0.5, 0.5, "no steady window with nonzero speed: no spectrum",
                ha="center", va="center", transform=ax.transAxes)
        ax.set(xlabel="frequency f / Hz", ylabel="amplitude / % of fundamental",
               title=f"{title}: spectrum of i_a")
    paths.append(save_figure(fig, out / f"{strategy}_spectrum.png"))
    return paths
