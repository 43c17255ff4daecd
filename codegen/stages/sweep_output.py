"""A sweep's results: one JSON document, a CSV (one row per run, strategy and scenario), a table, a plot.

JSON: the header (config, hash, versions, strategies, axes, spreads, seed),
``runs`` (per run: its parameters, config hash, simulate's metrics per
strategy, warnings) and ``timing`` (runner, wall times, workers): everything
but ``timing`` is the same bit for bit whichever runner computed it.

Plot (PNG): for a grid, the metrics against the first axis, one line per
strategy (and scenario run, and value of the other axes); for a Monte
Carlo study, the distribution of each metric per strategy (box plots with
the runs as points).
"""
from __future__ import annotations

import json
import math
import statistics
from pathlib import Path
from typing import Any

from codegen import __version__
from codegen.model import Model
from codegen.outputs import write_atomic
from codegen.plotting import save_figure
from codegen.results import clean_json, metric_sets, versions, write_csv_rows

__all__ = ["assemble", "flat_rows", "write_json", "write_csv", "table", "plot", "colours", "PLOT_METRICS"]

#: metrics plotted (those a run reports), with their axis labels and scale
PLOT_METRICS = (
    ("T_rip_RMSE_nm", "torque ripple RMSE / N*m", 1.0),
    ("psi_rip_RMSE_wb", "flux ripple RMSE / Wb", 1.0),
    ("f_ave_hz", "average switching frequency / kHz", 1e-3),
    ("Cal_ave", "evaluations per period", 1.0),
    ("THD_ia_percent", "THD of i_a / %", 1.0),
)
#: metrics in the printed table: (key, header, format, scale)
_TABLE = (("T_rip_RMSE_nm", "T_rip/N*m", "10.4f", 1.0), ("psi_rip_RMSE_wb", "psi_rip/Wb", "10.5f", 1.0),
          ("THD_ia_percent", "THD/%", "7.2f", 1.0), ("Cal_ave", "Cal_ave", "7.2f", 1.0),
          ("f_ave_hz", "f_ave/kHz", "9.2f", 1e-3), ("faults", "faults", "6d", 1))


def assemble(plan: Any, model: Model, outs: list[dict[str, Any]], timing: dict[str, Any]) -> dict[str, Any]:
    """The JSON document of a sweep."""
    runs = []
    for run, m, out in zip(plan.runs, plan.models, outs):
        assert out["index"] == run["index"]
        runs.append({**run, "config_hash": m.config_hash(), **out["result"], "warnings": out["warnings"]})
    return clean_json({
        "config": model.name, "config_file": str(plan.config), "config_hash": model.config_hash(),
        "mpcgen": __version__, "versions": versions(), "kind": plan.kind, "strategies": list(plan.strategies),
        "overrides": dict(plan.base),
        "axes": [{"field": a.field, "values": list(a.values)} for a in plan.axes],
        "monte_carlo": ({"runs": plan.monte_carlo, "seed": plan.seed, "distribution": "uniform",
                         "spreads": [{"field": s.field, "percent": s.percent, "nominal": s.nominal}
                                     for s in plan.spreads]} if plan.monte_carlo else None),
        "runs": runs,
        "timing": timing,
    })


def _scalar(v: Any) -> bool:
    return isinstance(v, (int, float, str, bool)) or v is None


def flat_rows(data: dict[str, Any]) -> list[dict[str, Any]]:
    """One row per run, strategy and scenario run: the run's parameters and every scalar metric."""
    rows: list[dict[str, Any]] = []
    for run in data["runs"]:
        head: dict[str, Any] = {"run": run["index"], "grid_point": run["grid_point"], "draw": run["draw"]}
        head.update(run["params"])
        for s, scen, m in metric_sets(run):
            row = dict(head, strategy=s)
            if scen is not None:
                row["scenario"] = scen
            row.update({k: v for k, v in m.items() if _scalar(v)})
            rows.append(row)
    return rows


def write_json(path: Path, data: dict[str, Any]) -> None:
    write_atomic(path, (json.dumps(data, indent=2, sort_keys=True) + "\n").encode())


def write_csv(path: Path, data: dict[str, Any]) -> None:
    write_csv_rows(path, flat_rows(data))


def _cell(v: Any, spec: str, scale: float) -> str:
    width = int("".join(c for c in spec.split(".")[0] if c.isdigit()) or 8)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or (isinstance(v, float) and not math.isfinite(v)):
        return "n/a".rjust(width)
    return format(v * scale if scale != 1 else v, spec)


def _label(s: str, scen: str | None) -> str:
    return s if scen is None else f"{s} {scen}"


def table(data: dict[str, Any]) -> str:
    """Grid: one line per run and strategy; Monte Carlo: statistics per strategy (mean, std, min, max)."""
    rows = flat_rows(data)
    fields = [a["field"] for a in data["axes"]]
    lines = [f"{data['config']}: {data['kind']} sweep, {len(data['runs'])} runs x {len(data['strategies'])} strategies"
             f" ({data['timing']['wall_s']:.1f} s on {data['timing']['runner']})"]
    if data["monte_carlo"] is None:
        heads = [f.rpartition(".")[2] for f in fields]
        widths = [max(10, len(h)) for h in heads]
        lines.append("  ".join(f"{h:>{w}s}" for h, w in zip(heads, widths)) + f"  {'strategy':<24s}"
                     + " ".join(f"{h:>{len(_cell(0, spec, 1))}s}" for _, h, spec, _ in _TABLE))
        for r in rows:
            vals = "  ".join(f"{r[f]:>{w}.6g}" if isinstance(r[f], float) else f"{r[f]!s:>{w}s}"
                             for f, w in zip(fields, widths))
            lines.append(f"{vals}  {_label(str(r['strategy']), r.get('scenario')):<24s}"
                         + " ".join(_cell(r.get(k), spec, scale) for k, _, spec, scale in _TABLE))
        return "\n".join(lines)
    mc = data["monte_carlo"]
    lines.append("  spreads: " + ", ".join(f"{s['field']} {s['nominal']:.6g} +-{s['percent']:g}%" for s in mc["spreads"])
                 + f" (uniform, seed {mc['seed']})")
    groups: dict[str, list[dict[str, Any]]] = {}
    for r in rows:
        point = ", ".join(f"{f.rpartition('.')[2]}={r[f]:.6g}" if isinstance(r[f], float) else f"{f.rpartition('.')[2]}={r[f]}"
                          for f in fields)
        key = (point + "  " if point else "") + _label(str(r["strategy"]), r.get("scenario"))
        groups.setdefault(key, []).append(r)
    width = max(len(k) for k in groups)
    lines.append(f"{'strategy':<{width}s}  {'metric':<16s} {'mean':>10s} {'std':>10s} {'min':>10s} {'max':>10s}   runs")
    for key, rs in groups.items():
        for k, _h, _spec, _scale in _TABLE[:3]:
            xs: list[float] = [float(r[k]) for r in rs if isinstance(r.get(k), (int, float)) and math.isfinite(float(r[k]))]
            if not xs:
                continue
            sd = statistics.stdev(xs) if len(xs) > 1 else 0.0
            lines.append(f"{key:<{width}s}  {k:<16s} {statistics.fmean(xs):10.5f} {sd:10.5f} "
                         f"{min(xs):10.5f} {max(xs):10.5f}   {len(xs)}")
        faults = sum(int(r.get("faults") or 0) for r in rs)
        lines.append(f"{key:<{width}s}  {'faults (total)':<16s} {faults:10d}")
    return "\n".join(lines)


def plot(path: Path, data: dict[str, Any]) -> Path:
    """The sweep's PNG: metrics against the first grid axis, or their Monte Carlo distributions."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    rows = flat_rows(data)
    metrics = [m for m in PLOT_METRICS if any(isinstance(r.get(m[0]), (int, float)) for r in rows)][:4] or [PLOT_METRICS[0]]
    ncols = 2 if len(metrics) > 1 else 1
    nrows = (len(metrics) + ncols - 1) // ncols
    fig = Figure(figsize=(6.0 * ncols, 3.8 * nrows), dpi=110, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
    for ax in axes[len(metrics):]:
        ax.set_visible(False)
    fields = [a["field"] for a in data["axes"]]
    if data["monte_carlo"] is None:
        _plot_grid(axes, metrics, rows, fields)
        title = f"{data['config']}: sweep of {', '.join(f.rpartition('.')[2] for f in fields)}"
    else:
        _plot_distributions(axes, metrics, rows, fields)
        mc = data["monte_carlo"]
        title = (f"{data['config']}: Monte Carlo, {mc['runs']} runs, "
                 + ", ".join(f"{s['field'].rpartition('.')[2]} +-{s['percent']:g}%" for s in mc["spreads"]))
    fig.suptitle(title)
    return save_figure(fig, path)


def _series_key(r: dict[str, Any], others: list[str]) -> str:
    parts = [_label(str(r["strategy"]), r.get("scenario"))]
    parts += [f"{f.rpartition('.')[2]}={r[f]}" for f in others]
    return ", ".join(parts)


def _plot_grid(axes: Any, metrics: Any, rows: list[dict[str, Any]], fields: list[str]) -> None:
    x_field, others = fields[0], fields[1:]
    numeric = all(isinstance(r[x_field], (int, float)) and not isinstance(r[x_field], bool) for r in rows)
    series: dict[str, list[dict[str, Any]]] = {}
    for r in rows:
        series.setdefault(_series_key(r, others), []).append(r)
    ticks = list(dict.fromkeys(str(r[x_field]) for r in rows))
    strategies = list(dict.fromkeys(str(r["strategy"]) for r in rows))
    palette = colours(len(series))
    for ax, (key, label, scale) in zip(axes, metrics):
        for n, (name, rs) in enumerate(series.items()):
            pts = [(r[x_field] if numeric else ticks.index(str(r[x_field])), r.get(key)) for r in rs]
            pts = [(x, float(y) * scale) for x, y in pts if isinstance(y, (int, float))]
            style = _LINESTYLES[strategies.index(str(rs[0]["strategy"])) % len(_LINESTYLES)]
            if pts:
                ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", ms=3, ls=style,
                        color=palette[n], label=name)
        if not numeric:
            ax.set_xticks(range(len(ticks)), ticks)
        ax.set(xlabel=x_field, ylabel=label)
        ax.grid(True, alpha=0.3)
    if len(series) > 6:
        axes[0].figure.legend(*axes[0].get_legend_handles_labels(), loc="outside right upper", fontsize="small")
    else:
        axes[0].legend(loc="best", fontsize="small")


_LINESTYLES = ("-", "--", ":", "-.")


def colours(n: int) -> list[Any]:
    """``n`` distinct colours (tab10 up to 10 series, then a continuous map)."""
    from matplotlib import colormaps

    if n <= 10:
        return [colormaps["tab10"](i) for i in range(n)]
    cmap = colormaps["turbo"]
    return [cmap(0.05 + 0.9 * i / (n - 1)) for i in range(n)]


def _plot_distributions(axes: Any, metrics: Any, rows: list[dict[str, Any]], fields: list[str]) -> None:
    groups: dict[str, list[dict[str, Any]]] = {}
    for r in rows:
        groups.setdefault(_series_key(r, fields), []).append(r)
    names = list(groups)
    for ax, (key, label, scale) in zip(axes, metrics):
        data = [[float(r[key]) * scale for r in groups[n] if isinstance(r.get(key), (int, float))
                 and math.isfinite(float(r[key]))] for n in names]
        pos = [i + 1 for i, d in enumerate(data) if d]
        ax.boxplot([d for d in data if d], positions=pos, widths=0.5, showfliers=False)
        for p, d in zip(pos, [d for d in data if d]):
            jitter = [p + 0.18 * (((j * 0.618034) % 1.0) - 0.5) for j in range(len(d))]
            ax.plot(jitter, d, ".", ms=3, alpha=0.5)
        ax.set_xticks(range(1, len(names) + 1), names, rotation=30 if len(names) > 4 else 0, fontsize="small")
        ax.set(ylabel=label)
        ax.grid(True, axis="y", alpha=0.3)
