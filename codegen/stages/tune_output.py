"""A tune's results: ``tune.json``, ``tune.csv``, ``tune.md`` (the tables) and ``front_<a>_<b>.png``.

JSON: the header (config, its hash, versions, overrides, sensor noise,
scenario, tuned fields, objectives, figures, the rules of the search, the
admissibility and the recommendation), per strategy every evaluated point
(parameters, round, figures, verdict, admissible and why not, the metrics of
each scenario run), the front, the admissible front and the recommendation
(parameters, figures, the ``--set`` line, the config hash and the C hash of
the chosen point); and ``timing`` (runner, workers, wall times per round and
run).  Everything but ``timing`` is the same bit for bit whichever runner
computed it.

CSV: one row per strategy and evaluated point.  Plots: one PNG per pair of
objectives, every strategy's points (misbehaving ones as crosses), its
admissible front filled and its recommended point as a star.
"""
from __future__ import annotations

import itertools
import json
import math
import shlex
from pathlib import Path
from typing import Any

from codegen import __version__
from codegen.model import Model
from codegen.outputs import write_atomic
from codegen.plotting import heading, save_figure
from codegen.results import clean_json, versions, write_csv_rows

__all__ = ["assemble", "markdown", "summary", "write_all", "rows", "plot_front", "RULES"]

Log = Any

#: the rules the search, the admissibility and the recommendation follow, as tune.json and tune.md state them
RULES = {
    "search": "round 0: a grid of N values per tuned field, evenly spaced on its scale (log for a weight, linear "
              "for a threshold), and their cartesian product; rounds 1..K: the spacing halves and the M points of "
              "the strategy's admissible front nearest the ideal point (as the recommendation ranks them; M = 0: "
              "every point of the admissible front; the whole front when none is admissible) get their neighbours "
              "at +- the new spacing along each field that are not evaluated yet (one field: bisection between "
              "those front points and their neighbours); values rounded to 6 significant digits",
    "figures": "per point and strategy, over the scenario runs (a run's steady entry where the scenario set has "
               "one): the mean over the runs whose window for that figure is steady (all runs when none is); the "
               "peak current the largest of the runs",
    "admissible": "no period tripped the guard, every run's tracking verdict is ok, and no run has an anomaly "
                  "(peak phase current above 2 x rated, or |psi_s| below 0.6 x its mean, in a steady window); "
                  "the others are marked and never recommended",
    "front": "the points of a strategy that no other of its points dominates in the objectives (all minimised); "
             "a point with an objective not computed is on no front",
    "recommendation": "among the strategy's admissible front, the point nearest (Euclidean) to the ideal point "
                      "after scaling each objective to [0, 1] over that front (0 its best value there, 1 its "
                      "worst); ties go to the lowest field values",
}


def _value_text(v: object) -> str:
    """A value as ``--set`` reads it back (TOML: numbers, booleans, quoted strings, arrays)."""
    return json.dumps(v)


def _recommended(search: Any, s: str, i: int, scaled: dict[str, float], log: Log) -> dict[str, Any]:
    from codegen.manifest import C_HASH_DEFINITION, c_hash
    from codegen.stages.training import with_trained_tables

    p = search.points[s][i]
    vals = tuple(p["params"].values())
    variant = search.model(vals).with_controller(strategy=s)
    try:
        ch: str | None = c_hash(with_trained_tables(variant, [s], log))
        why = None
    except Exception as exc:  # the hash is a convenience: a failure to render is stated, not fatal
        ch, why = None, f"{type(exc).__name__}: {' '.join(str(exc).split())[:200]}"
    sets = " ".join(f"--set {shlex.quote(f'{k}={_value_text(v)}')}" for k, v in p["params"].items())
    base = " ".join(f"--set {shlex.quote(f'{k}={_value_text(v)}')}" for k, v in search.base.items())
    return {
        "index": i, "params": dict(p["params"]), "figures": dict(p["figures"]), "scaled": scaled,
        "set_line": sets,
        "command": " ".join(x for x in ("mpcgen simulate", shlex.quote(str(search.config)), f"--strategy {s}",
                                        base, sets) if x),
        "config_hash": variant.config_hash(), "c_hash": ch, "c_hash_target": variant.target,
        "c_hash_definition": C_HASH_DEFINITION, **({"c_hash_error": why} if why else {}),
    }


def assemble(search: Any, model: Model, timing: dict[str, Any], log: Log) -> dict[str, Any]:
    """The JSON document of a tune."""
    from codegen.stages.tune import FIGURES, recommend

    strategies: dict[str, Any] = {}
    for s in search.strategies:
        whole, adm = search.fronts(s)
        best, scaled = recommend(search.points[s], adm, search.objectives)
        strategies[s] = {
            "points": search.points[s], "front": whole, "admissible_front": adm,
            "recommended": None if best is None else _recommended(search, s, best, scaled, log),
        }
    sc = model.scenario
    return clean_json({
        "config": model.name, "config_file": str(search.config), "config_hash": model.config_hash(),
        "mpcgen": __version__, "versions": versions(), "topology": model.inverter.topology,
        "overrides": dict(search.base),
        "sensor_noise": {"plant.noise_a": model.plant.noise_a, "plant.noise_seed": model.plant.noise_seed},
        "scenario": {"set": getattr(sc, "set", "config"), "duration_s": sc.duration_s, "speed_mode": sc.speed_mode,
                     "speed_ref_rpm": sc.speed_ref_rpm, "load_nm": sc.load_nm, "window_s": sc.window_s},
        "fields": [{"field": a.field, "role": a.role, "scale": "log" if a.log else "linear", "lo": a.lo, "hi": a.hi,
                    "config_value": a.nominal} for a in search.axes],
        "objectives": [f.key for f in search.objectives],
        "figures": [{"key": f.key, "short": f.short, "label": f.label, "combine": f.combine} for f in FIGURES],
        "grid": search.grid, "rounds": search.rounds, "focus": search.focus, "rules": RULES,
        "strategies": strategies,
        "timing": timing,
    })


# ---------------------------------------------------------------- tables
def _num(v: Any, spec: str = ".4g") -> str:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or (isinstance(v, float) and not math.isfinite(v)):
        return "n/a"
    return format(v, spec)


def _present(data: dict[str, Any]) -> list[dict[str, Any]]:
    """The figures some point reports (a topology without a neutral point has no ``Vo_std_v``)."""
    keys = {k for d in data["strategies"].values() for p in d["points"] for k, v in p["figures"].items()
            if v is not None}
    return [f for f in data["figures"] if f["key"] in keys]


def _short(name: str) -> str:
    return name.rpartition(".")[2]


def _status(p: dict[str, Any]) -> str:
    if p["admissible"]:
        return "ok"
    first = p["reasons"][0]
    more = f" (+{len(p['reasons']) - 1})" if len(p["reasons"]) > 1 else ""
    return "misbehaves: " + (first if len(first) <= 70 else first[:67] + "...") + more


def _table(data: dict[str, Any], s: str, which: list[int], marks: bool = True) -> list[str]:
    d = data["strategies"][s]
    figs = _present(data)
    fields = [f["field"] for f in data["fields"]]
    head = ["", *(_short(f) for f in fields), *(f"{f['short']}" for f in figs), "tracking", "locked", "round",
            "status"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    rec = d["recommended"]["index"] if d["recommended"] else None
    front, adm = set(d["front"]), set(d["admissible_front"])
    for i in which:
        p = d["points"][i]
        mark = "**<=**" if i == rec else ("A" if i in adm else ("F" if i in front else "")) if marks else ""
        cells = [mark, *(_num(p["params"][f], ".6g") for f in fields), *(_num(p["figures"].get(f["key"]))
                                                                        for f in figs),
                 p["tracking"], ", ".join(p["locked_cycle_runs"]) or "-", str(p["round"]), _status(p)]
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def _order(points: list[dict[str, Any]], which: list[int]) -> list[int]:
    return sorted(which, key=lambda i: tuple(points[i]["params"].values()))


def markdown(data: dict[str, Any]) -> str:
    """``tune.md``: what was tuned and how, then per strategy the recommendation, the front and every point."""
    fields = ", ".join(f"`{f['field']}` {f['lo']:.6g}..{f['hi']:.6g} ({f['scale']} scale"
                       + (f", config value {f['config_value']:.6g})" if f["config_value"] is not None else ")")
                       for f in data["fields"])
    sc = data["scenario"]
    n = sum(len(d["points"]) for d in data["strategies"].values())
    t = data["timing"]
    labels = {f["key"]: f for f in data["figures"]}
    out = [f"# Tuning {data['config']}: {', '.join(_short(f['field']) for f in data['fields'])}", "",
           f"- config `{data['config_file']}`, config hash `{data['config_hash']}`, mpcgen {data['mpcgen']}",
           "- overrides: " + (", ".join(f"`{k}={_value_text(v)}`" for k, v in data["overrides"].items()) or "none"),
           f"- sensor noise: plant.noise_a = {data['sensor_noise']['plant.noise_a']:g} A "
           f"(seed {data['sensor_noise']['plant.noise_seed']})",
           f"- scenario: scenario.set = {sc['set']}, duration {sc['duration_s']:g} s, speed {sc['speed_mode']}",
           f"- tuned: {fields}",
           "- objectives (minimised): " + ", ".join(f"{labels[k]['short']} ({labels[k]['label']})"
                                                   for k in data["objectives"]),
           f"- search: grid of {data['grid']} values per field, {data['rounds']} refinement round(s) around "
           f"{data['focus'] or 'every'} admissible-front point(s) nearest the ideal point; {n} runs in "
           f"{t['wall_s']:.1f} s on {t['runner']}" + (f" ({t['workers']} workers)" if t["runner"] == "local" else ""),
           "", "Rules:", ""]
    out += [f"- **{k}**: {v}" for k, v in data["rules"].items()]
    out += ["", "Columns: " + "; ".join(f"{f['short']} = {f['label']} ({f['combine']} over the scenario runs)"
                                        for f in _present(data))
            + "; locked = scenario runs whose decisions repeat exactly over the THD window; "
              "marks: **<=** recommended, A admissible front, F front but misbehaving.", ""]
    for s, d in data["strategies"].items():
        out += [f"## {s}", ""]
        rec = d["recommended"]
        if rec is None:
            out += ["**No admissible point**: every evaluated value misbehaves; nothing is recommended.", ""]
        else:
            vals = ", ".join(f"`{k} = {v:.6g}`" for k, v in rec["params"].items())
            figs = ", ".join(f"{labels[k]['short']} {_num(v)}" for k, v in rec["figures"].items() if v is not None)
            out += [f"**Recommended: {vals}** -- `{rec['set_line']}`", "",
                    f"{figs}; config hash `{rec['config_hash']}`, C hash `{rec['c_hash']}` ({rec['c_hash_target']})",
                    "", f"    {rec['command']}", ""]
        pts = d["points"]
        front = _order(pts, sorted(set(d["front"]) | set(d["admissible_front"])))
        out += [f"### Front ({len(d['admissible_front'])} admissible, {len(d['front'])} of all points)", "",
                *_table(data, s, front), "", f"### Every evaluated point ({len(pts)})", "",
                *_table(data, s, _order(pts, list(range(len(pts))))), ""]
    return "\n".join(out)


def summary(data: dict[str, Any]) -> str:
    """One line per strategy: the recommended values, their --set line and figures."""
    labels = {f["key"]: f for f in data["figures"]}
    lines = []
    for s, d in data["strategies"].items():
        rec = d["recommended"]
        if rec is None:
            lines.append(f"{s}: no admissible point")
            continue
        vals = ", ".join(f"{k} = {v:.6g}" for k, v in rec["params"].items())
        figs = ", ".join(f"{labels[k]['short']} {_num(v)}" for k, v in rec["figures"].items() if v is not None)
        lines.append(f"{s}: recommended {vals} ({rec['set_line']}): {figs}")
    return "\n".join(lines) + "\n"


def rows(data: dict[str, Any]) -> list[dict[str, Any]]:
    """One CSV row per strategy and evaluated point."""
    out = []
    for s, d in data["strategies"].items():
        rec = d["recommended"]["index"] if d["recommended"] else None
        front, adm = set(d["front"]), set(d["admissible_front"])
        for i, p in enumerate(d["points"]):
            out.append({"strategy": s, "point": i, "round": p["round"], **p["params"], **p["figures"],
                        "faults": p["faults"], "tracking": p["tracking"], "admissible": p["admissible"],
                        "on_front": i in front, "on_admissible_front": i in adm, "recommended": i == rec,
                        "locked_cycle_runs": ";".join(p["locked_cycle_runs"]), "reasons": "; ".join(p["reasons"]),
                        "config_hash": p["config_hash"]})
    return out


# ---------------------------------------------------------------- plots
def _xy(p: dict[str, Any], a: dict[str, Any], b: dict[str, Any]) -> tuple[Any, Any]:
    return p["figures"].get(a["key"]), p["figures"].get(b["key"])


def plot_front(path: Path, data: dict[str, Any], a: dict[str, Any], b: dict[str, Any]) -> Path:
    """Objective ``b`` over objective ``a``: every strategy's points, its admissible front and its
    recommended point (star), misbehaving points as crosses."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from codegen.stages.sweep_output import colours

    fig = Figure(figsize=(7.5, 5.5), dpi=120, layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    palette = colours(len(data["strategies"]))
    described: dict[str, Any] = {"x": a["key"], "y": b["key"], "recommended": {}}
    xs_all, ys_all = [], []
    for c, (s, d) in zip(palette, data["strategies"].items()):
        pts = d["points"]
        adm = set(d["admissible_front"])

        groups: dict[str, list[tuple[float, float]]] = {"ok": [], "front": [], "bad": []}
        for i in range(len(pts)):
            x, y = _xy(pts[i], a, b)
            if x is None or y is None:
                continue
            xs_all.append(x)
            ys_all.append(y)
            groups["front" if i in adm else ("ok" if pts[i]["admissible"] else "bad")].append((x, y))
        if groups["ok"]:
            ax.plot(*zip(*groups["ok"]), "o", mfc="none", color=c, alpha=0.6, ms=5, label=f"{s}: admissible")
        if groups["front"]:
            ax.plot(*zip(*sorted(groups["front"])), "o", color=c, ms=6, label=f"{s}: admissible front")
        if groups["bad"]:
            ax.plot(*zip(*groups["bad"]), "x", color=c, ms=7, label=f"{s}: misbehaves (not recommended)")
        rec = d["recommended"]
        if rec is not None:
            x, y = _xy(pts[rec["index"]], a, b)
            if x is not None and y is not None:
                text = ", ".join(f"{_short(k)}={v:.4g}" for k, v in rec["params"].items())
                ax.plot([x], [y], "*", color=c, ms=18, mec="k", label=f"{s}: recommended {text}")
                ax.annotate(text, (x, y), textcoords="offset points", xytext=(8, 8), fontsize="small")
                described["recommended"][s] = {"params": rec["params"], a["key"]: x, b["key"]: y}
    for vals, setter in ((xs_all, ax.set_xscale), (ys_all, ax.set_yscale)):
        pos = [v for v in vals if v > 0]
        if pos and len(pos) == len(vals) and max(pos) / min(pos) > 10:
            setter("log")
    fields = ", ".join(_short(f["field"]) for f in data["fields"])
    ax.set(xlabel=a["label"], ylabel=b["label"],
           title=heading(f"{data['config']}: tuning {fields}, {sum(len(d['points']) for d in data['strategies'].values())} runs",
                         f"{b['short']} over {a['short']}; star: recommended, cross: misbehaves"))
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize="small")
    return save_figure(fig, path, described=described)


def write_all(out_dir: Path, data: dict[str, Any], text: str) -> list[Path]:
    """``tune.md``, ``tune.json``, ``tune.csv`` and a ``front_<a>_<b>.png`` per pair of objectives."""
    paths = [out_dir / "tune.md", out_dir / "tune.json", out_dir / "tune.csv"]
    write_atomic(paths[0], text.encode())
    write_atomic(paths[1], (json.dumps(data, indent=2, sort_keys=True) + "\n").encode())
    write_csv_rows(paths[2], rows(data))
    figs = {f["key"]: f for f in data["figures"]}
    for ka, kb in itertools.combinations(data["objectives"], 2):
        a, b = figs[ka], figs[kb]
        paths.append(plot_front(out_dir / f"front_{a['short']}_{b['short']}.png", data, a, b))
    return paths
