"""PNG plots of a closed-loop two-level run (matplotlib, Agg canvas, no GUI).

Figures are built with the object-oriented API (``matplotlib.figure.Figure``
rendered by the Agg canvas), so no pyplot state and no display are involved.
Plot list: shared/spec/plant-and-metrics.md, last paragraph (speed, torque and
reference, flux magnitude, phase currents, spectrum of i_a).
"""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from codegen.metrics import amplitude_spectrum, fundamental_hz, thd, thd_window, window_slice
from codegen.model import Model
from codegen.plotting import new_figure, save_figure

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

    # speed
    fig, (ax,) = new_figure()
    ax.plot(t, trace.speed_ref_rpm, color="k", lw=1.0, ls="--", label="reference n*")
    ax.plot(t, trace.speed_rpm, color="tab:blue", lw=0.8, label="actual n")
    ax.set(xlabel="time t / s", ylabel="speed n / (r/min)", title=f"{title}: rotor speed")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best")
    paths.append(save_figure(fig, out / f"{strategy}_speed.png"))

    # torque
    fig, (ax,) = new_figure()
    ax.plot(t, trace.te_nm, color="tab:blue", lw=0.4, label="plant torque Te")
    ax.plot(t, trace.torque_ref_nm, color="k", lw=1.0, label="reference T*")
    ax.set(xlabel="time t / s", ylabel="torque / (N*m)", title=f"{title}: electromagnetic torque")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best")
    paths.append(save_figure(fig, out / f"{strategy}_torque.png"))

    # flux magnitude
    fig, (ax,) = new_figure()
    ax.plot(t, trace.psi_wb, color="tab:blue", lw=0.4, label="plant |psi_s|")
    ax.axhline(model.controller.psi_ref_wb, color="k", lw=1.0, label="reference psi*")
    ax.set(xlabel="time t / s", ylabel="stator flux |psi_s| / Wb", title=f"{title}: stator-flux magnitude")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best")
    paths.append(save_figure(fig, out / f"{strategy}_flux.png"))

    # phase currents: whole run + zoom on two fundamental periods of the THD window
    tw = thd_window(trace, model)
    fig, axes = new_figure(2, height=7.0)
    if tw is not None:
        f1 = fundamental_hz(trace, model, *tw)
        span = 2.0 / f1 if f1 > 0 else tw[1] - tw[0]
        zoom = window_slice(trace.dt_s, max(tw[0], tw[1] - span), tw[1], trace.n)
    else:
        zoom = slice(max(0, trace.n - int(round(0.05 / trace.dt_s))), trace.n)
    for ax, sl, label in ((axes[0], slice(0, trace.n), "whole run"), (axes[1], zoom, "zoom")):
        lo, hi = sl.start, sl.stop
        ax.plot(t[lo:hi], trace.ia_a[lo:hi], lw=0.5, label="i_a")
        ax.plot(t[lo:hi], trace.ib_a[lo:hi], lw=0.5, label="i_b")
        ax.plot(t[lo:hi], trace.ic_a[lo:hi], lw=0.5, label="i_c")
        ax.set(xlabel="time t / s", ylabel="phase current / A", title=f"{title}: phase currents ({label})")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right")
    paths.append(save_figure(fig, out / f"{strategy}_currents.png"))

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
