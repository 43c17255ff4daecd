"""The plots of one closed-loop run every topology draws (``simulate --plots``; docs/simulation.md "Plots").

Every title names what its plot covers: the whole run with its time span, a
zoom with its span, the THD window with its fundamental.  The spectrum of a
signal is never computed over a window of its own: it is drawn from the
topology's metric result (the window entry of the THD the table reports) and
refused, with an error, when the FFT would not cover exactly that window or
give that THD (:func:`plot_spectrum`).  The zooms and the flux locus take the
same window (:func:`thd_span`).  Generic figure helpers: ``codegen.plotting``.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from codegen.metrics import amplitude_spectrum, sample_time, window_slice
from codegen.model import Model
from codegen.plotting import SIZE_IN, heading, new_figure, plot_lines, save_figure, span

__all__ = ["scenario_label", "run_span", "thd_span", "zoom_slice", "plot_speed", "plot_torque", "plot_phase_currents",
           "plot_spectrum", "flux_alpha_beta", "plot_flux_locus"]


def scenario_label(model: Model) -> str:
    """The scenario's speed and load profiles, e.g. ``n* = 1000/-1000 r/min, T_L = 15/-15 N*m``."""
    sc = model.scenario

    def steps(profile: tuple[tuple[float, float], ...]) -> str:
        return "/".join(f"{v:g}" for _t, v in sorted(profile))

    return f"n* = {steps(sc.speed_ref_rpm)} r/min, T_L = {steps(sc.load_nm)} N*m"


def run_span(trace: Any) -> str:
    """``whole run [0, T) s`` of a trace."""
    return f"whole run {span(0.0, sample_time(trace.n, trace.dt_s))}"


def thd_span(metrics: dict[str, Any], key: str = "THD_ia_percent") -> tuple[float, float, float] | None:
    """(t0_s, t1_s, f1_hz) of the THD the metric result reports under ``key`` (the FFT's window, the
    measured fundamental), or None when it was not computed."""
    info = metrics["window"][key]
    if "not_computed_reason" in info or "n_periods" not in info:
        return None
    return float(info["t0_s"]), float(info["t1_s"]), float(info["f1_hz"])


def zoom_slice(trace: Any, metrics: dict[str, Any], fundamental_periods: float = 2.0,
               fallback_s: float = 0.05) -> slice:
    """Periods of the last ``fundamental_periods`` fundamental periods of the THD window the metric
    result reports, or the last ``fallback_s`` of the run when there is none."""
    tw = thd_span(metrics)
    if tw is None:
        return slice(max(0, trace.n - int(round(fallback_s / trace.dt_s))), trace.n)
    t0, t1, f1 = tw
    width = fundamental_periods / f1 if f1 > 0 else t1 - t0
    return window_slice(trace.dt_s, max(t0, t1 - width), t1, trace.n)


def plot_speed(path: Path, title: str, trace: Any) -> Path:
    """Rotor speed and its reference over the whole run, r/min."""
    return plot_lines(path, heading(title, f"rotor speed, {run_span(trace)}"), "speed n / (r/min)", trace.t_s, [
        (trace.speed_ref_rpm, "reference n*", {"color": "k", "lw": 1.0, "ls": "--"}),
        (trace.speed_rpm, "actual n", {"color": "tab:blue", "lw": 0.8}),
    ])


def plot_torque(path: Path, title: str, trace: Any) -> Path:
    """Plant torque Te and the reference T* of a closed-loop run."""
    return plot_lines(path, heading(title, f"electromagnetic torque, {run_span(trace)}"), "torque / (N*m)", trace.t_s, [
        (trace.te_nm, "plant torque Te", {"color": "tab:blue", "lw": 0.4}),
        (trace.torque_ref_nm, "reference T*", {"color": "k", "lw": 1.0}),
    ])


def plot_phase_currents(path: Path, title: str, trace: Any, zoom: slice) -> Path:
    """Phase currents i_a, i_b, i_c over the whole run (top) and over ``zoom`` (bottom)."""
    fig, axes = new_figure(2, height=7.0)
    dt = trace.dt_s
    zoom_label = f"zoom {span(sample_time(zoom.start, dt), sample_time(zoom.stop, dt))}"
    for ax, sl, label in ((axes[0], slice(0, trace.n), run_span(trace)), (axes[1], zoom, zoom_label)):
        for name in ("ia_a", "ib_a", "ic_a"):
            ax.plot(trace.t_s[sl], getattr(trace, name)[sl], lw=0.5, label=f"i_{name[1]}")
        ax.set(xlabel="time t / s", ylabel="phase current / A", title=heading(title, f"phase currents, {label}"))
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right")
    return save_figure(fig, path)


def _no_figure(ax: Any, text: str) -> None:
    ax.text(0.5, 0.5, text, ha="center", va="center", transform=ax.transAxes, wrap=True)


def plot_spectrum(path: Path, title: str, signal: Any, dt_s: float, metrics: dict[str, Any],
                  key: str = "THD_ia_percent", name: str = "i_a") -> Path:
    """Amplitude spectrum of ``signal`` over exactly the window, fundamental and harmonic range of the
    THD the metric result reports under ``key`` (its ``window[key]`` entry), titled with that window,
    fundamental and THD as the table prints them.  The FFT is taken with the entry's window and
    fundamental; a spectrum whose window, period count or THD would differ from the entry's is an
    error (RuntimeError), never a figure.  Without a THD the figure states the reason."""
    info = metrics["window"][key]
    fig, (ax,) = new_figure()
    described: dict[str, Any] = {"metric": key, "signal": name}
    value = metrics[key]
    computed = "not_computed_reason" not in info and "n_periods" in info and value is not None \
        and math.isfinite(float(value))
    if not computed:
        reason = info.get("not_computed_reason", "no THD")
        _no_figure(ax, f"no spectrum: {reason}")
        ax.set(xlabel="frequency f / Hz", ylabel="amplitude / % of fundamental",
               title=heading(title, f"spectrum of {name}, not computed ({reason})"))
        described["computed"] = False
        return save_figure(fig, path, described)
    t0, t1, f1 = float(info["t0_s"]), float(info["t1_s"]), float(info["f1_hz"])
    n_per, m = int(info["n_periods"]), int(info["n_samples"])
    sl = window_slice(dt_s, t0, t1, len(signal))
    # exactly the entry's samples: n_per whole periods of the FFT's own fundamental f1_used
    freqs, amp, got = amplitude_spectrum(np.asarray(signal)[sl], dt_s, 0.0, m * dt_s, float(info["f1_used_hz"]))
    if sl.stop - sl.start != m or (got["n_periods"], got["n_samples"]) != (n_per, m):
        raise RuntimeError(f"{path.name}: the spectrum would cover {sl.stop - sl.start} samples, "
                           f"{got['n_periods']} periods, not the THD window {span(t0, t1)} ({m} samples, "
                           f"{n_per} periods)")
    h_lo, h_hi = (int(h) for h in info["harmonics"])
    i1 = float(amp[n_per])
    harm = amp[n_per * np.arange(h_lo, h_hi + 1)]
    thd_pct = 100.0 * float(np.sqrt(np.sum(harm * harm))) / i1
    if not math.isclose(thd_pct, float(value), rel_tol=1e-9):
        raise RuntimeError(f"{path.name}: the plotted spectrum gives THD {thd_pct!r} %, the metric {value!r} %")
    keep = freqs <= float(info["f_limit_hz"])
    ax.vlines(freqs[keep], 0.0, 100.0 * amp[keep] / i1, lw=0.8)
    ax.set_yscale("symlog", linthresh=0.1)
    ax.set(xlabel="frequency f / Hz", ylabel="amplitude / % of fundamental",
           title=heading(title, f"spectrum of {name}, THD window {span(t0, t1)}, {n_per} periods of "
                                f"f1 = {f1:.4g} Hz, THD = {float(value):.2f} % (h = {h_lo}..{h_hi})"))
    ax.grid(True, alpha=0.3)
    described.update({"computed": True, "t0_s": t0, "t1_s": t1, "f1_hz": f1, "n_periods": n_per,
                      "thd_percent": float(value), "harmonics": [h_lo, h_hi]})
    return save_figure(fig, path, described)


def flux_alpha_beta(trace: Any, model: Model) -> tuple[np.ndarray, np.ndarray]:
    """The plant's stator flux (psi_alpha, psi_beta) in Wb at the sample instants, from its phase
    currents and electrical angle with the plant's Ld, Lq and psi_f (``[plant]`` overrides included):
    psi_d = Ld i_d + psi_f, psi_q = Lq i_q, rotated by theta_e (amplitude-invariant transforms)."""
    pl = model.plant
    ld, lq, psi_f = pl.value("ld_h", model), pl.value("lq_h", model), pl.value("psi_f_wb", model)
    ia, ib = np.asarray(trace.ia_a, np.float64), np.asarray(trace.ib_a, np.float64)
    th = np.asarray(trace.theta_e_rad, np.float64)
    i_alpha, i_beta = ia, (ia + 2.0 * ib) / math.sqrt(3.0)
    c, s = np.cos(th), np.sin(th)
    psi_d = ld * (i_alpha * c + i_beta * s) + psi_f
    psi_q = lq * (-i_alpha * s + i_beta * c)
    return psi_d * c - psi_q * s, psi_d * s + psi_q * c


def plot_flux_locus(path: Path, title: str, trace: Any, model: Model, metrics: dict[str, Any],
                    psi_ref_wb: Any) -> Path:
    """The stator-flux locus psi_beta over psi_alpha: the whole run (grey) and the THD window the
    metric result reports (blue; without one, the last ``scenario.window_s`` of the run), with a
    circle of the mean flux reference ``psi_ref_wb`` (scalar or per period) over that window."""
    psi_a, psi_b = flux_alpha_beta(trace, model)
    tw = thd_span(metrics)
    dt = trace.dt_s
    if tw is not None:
        t0, t1, label = tw[0], tw[1], f"THD window {span(tw[0], tw[1])}"
    else:
        t1 = trace.n * dt
        t0 = max(0.0, t1 - model.scenario.window_s)
        label = f"last {model.scenario.window_s:g} s {span(t0, t1)}"
    sl = window_slice(dt, t0, t1, trace.n)
    fig, (ax,) = new_figure(height=SIZE_IN[0] * 0.8)
    ax.plot(psi_a, psi_b, lw=0.3, color="0.7", label=run_span(trace))
    ax.plot(psi_a[sl], psi_b[sl], lw=0.6, color="tab:blue", label=label)
    ref = np.asarray(psi_ref_wb, np.float64)
    r = float(np.mean(ref[sl])) if ref.ndim else float(ref)
    phi = np.linspace(0.0, 2.0 * math.pi, 361)
    ax.plot(r * np.cos(phi), r * np.sin(phi), "k--", lw=0.8, label=f"psi* = {r:.4g} Wb (mean over the window)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set(xlabel="psi_alpha / Wb", ylabel="psi_beta / Wb",
           title=heading(title, f"stator-flux locus, {label} (grey: {run_span(trace)})"))
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper right", fontsize=8)
    return save_figure(fig, path, {"t0_s": t0, "t1_s": t1, "psi_ref_wb": r})
