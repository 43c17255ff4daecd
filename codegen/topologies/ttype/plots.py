"""PNG plots of a closed-loop three-level run (matplotlib, Agg canvas, no GUI).

Plot list: docs/simulation.md, last paragraph (torque and
reference, flux magnitude, phase currents, and for three-level V_o and u_ab).
Figures use the object-oriented API (codegen/plotting.py).
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from codegen.metrics import thd_window, window_slice
from codegen.model import Model
from codegen.plotting import new_figure, plot_lines, plot_phase_currents, plot_torque, save_figure

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


def plot_three_level(trace: Trace, model: Model, strategy: str, speed_rpm: float,
                     outdir: str | Path) -> list[Path]:
    """Write ``<strategy>_<speed>rpm_{torque,flux,currents,vo,uab}.png`` into outdir.

    The zooms (currents over two fundamental periods; u_ab over 10 control
    periods and over one fundamental period) are taken at the end of the
    THD window (:func:`codegen.metrics.thd_window`), or the end of the run.
    Returns the paths written.
    """
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    tag = f"{strategy}_{int(round(speed_rpm))}rpm"
    title = f"{model.name}: {strategy}, {speed_rpm:g} r/min"
    t = trace.t_s
    dt = trace.dt_s
    paths: list[Path] = []

    tw = thd_window(trace, model)  # type: ignore[arg-type]
    f1 = 0.0
    if tw is not None:
        sl = window_slice(dt, tw[0], tw[1], trace.n)
        f1 = model.motor.pole_pairs * float(np.mean(np.abs(trace.omega_m_rad_s[sl]))) / (2.0 * math.pi)
        t_end = tw[1]
    else:
        t_end = trace.n * dt
    k_end = min(trace.n, int(round(t_end / dt)))

    paths.append(plot_torque(out / f"{tag}_torque.png", title, trace))
    paths.append(plot_lines(out / f"{tag}_flux.png", f"{title}: stator-flux magnitude", "stator flux |psi_s| / Wb", t, [
        (trace.psi_wb, "plant |psi_s|", {"color": "tab:blue", "lw": 0.4}),
        (trace.psi_ref_wb, "controller psi*", {"color": "k", "lw": 1.0}),
    ]))

    # currents: whole run + two fundamental periods
    span = 2.0 / f1 if f1 > 0 else 0.02
    zoom = slice(max(0, k_end - int(round(span / dt))), k_end)
    paths.append(plot_phase_currents(out / f"{tag}_currents.png", title, trace, zoom))

    paths.append(plot_lines(out / f"{tag}_vo.png", f"{title}: neutral-point voltage", "V_o / V", t,
                            [(trace.vo_v, "plant V_o = (u_c1 - u_c2)/2", {"color": "tab:blue", "lw": 0.5})],
                            hline=(0.0, "")))

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
        ax.set(xlabel="time t / ms", ylabel="u_ab / V", title=f"{title}: line voltage u_ab ({label})")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right")
    paths.append(save_figure(fig, out / f"{tag}_uab.png"))
    return paths
