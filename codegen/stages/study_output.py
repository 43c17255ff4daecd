"""A horizon study's results: ``study.json``, ``study.md`` (the table) and ``study.png``.

JSON: the header (config, its hash, versions, overrides, scenario, the target switching frequency and
tolerance, the rules of the search and of each figure, the command that reproduces it, the machine), one
row per horizon N (lambda_u used, f_ave achieved and its error, every value run, the figures, the THD
windows, the node statistics, the M7 cycles or "not measured", the config hash and the C hash of the
N's generated C, the ``simulate`` and ``bench`` commands of that point) and ``timing``.  Everything but
``timing`` and ``machine`` is the same whichever runner computed it.  The plot: current THD and torque
ripple against N (top), nodes per step against N with the budget's share of periods (bottom).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import platform
import shlex
from pathlib import Path
from typing import Any

from codegen import __version__
from codegen.model import Model
from codegen.outputs import write_atomic
from codegen.plotting import heading, new_figure, save_figure
from codegen.results import clean_json, versions

__all__ = ["row", "assemble", "markdown", "plot", "write_all", "command_line"]


def _set(k: str, v: object) -> str:
    return f"--set {shlex.quote(f'{k}={json.dumps(v)}')}"


def row(study: Any, variant: Model, match: Any, chosen: dict[str, Any], target: float, nodes: dict[str, Any],
        strategy: str) -> dict[str, Any]:
    """One horizon's row: the chosen point's figures, its search, nodes, hashes and commands."""
    from codegen.manifest import C_HASH_DEFINITION, c_hash
    from codegen.stages.study import HORIZON, WEIGHT

    n, lam = match.horizon, chosen["lambda_u"]
    base = " ".join(_set(k, v) for k, v in study.base.items())
    point = f"{_set(HORIZON, n)} {_set(WEIGHT, lam)}"
    cfg = shlex.quote(str(study.config))
    return {
        "horizon": n, "lambda_u": lam, "status": match.status, "f_ave_hz": chosen["f_ave_hz"],
        "f_error_percent": 100.0 * (chosen["f_ave_hz"] / target - 1.0),
        "runs": [{"lambda_u": p["lambda_u"], "f_ave_hz": p["f_ave_hz"], "round": p["round"],
                  "f_error_percent": 100.0 * (p["f_ave_hz"] / target - 1.0)} for p in match.points],
        "THD_ia_percent": chosen["figures"].get("THD_ia_percent"),
        "T_rip_RMSE_nm": chosen["figures"].get("T_rip_RMSE_nm"),
        "figures": chosen["figures"], "thd_windows": chosen["thd_windows"],
        "admissible": chosen["admissible"], "reasons": chosen["reasons"], "faults": chosen["faults"],
        "tracking": chosen["tracking"], "scenario_runs": chosen["scenario_runs"], "warnings": chosen["warnings"],
        "nodes": nodes, "config_hash": variant.config_hash(), "c_hash": c_hash(variant),
        "c_hash_target": variant.target, "c_hash_definition": C_HASH_DEFINITION,
        "simulate_command": " ".join(x for x in (f"mpcgen simulate {cfg} --strategy {strategy}", base, point) if x),
        "bench_command": " ".join(x for x in (f"mpcgen bench {cfg} --strategy {strategy} --emulated", base, point,
                                              f"--json bench_N{n}.json") if x),
    }


def command_line(args: argparse.Namespace) -> str:
    """The ``mpcgen study`` command that reproduces the study (runner options left out: they change no result)."""
    parts = ["mpcgen", "study", str(args.config), "--horizons", args.horizons]
    for attr, opt in (("strategy", "--strategy"), ("predictor", "--predictor"), ("tables", "--tables"),
                      ("number_format", "--number-format")):
        if getattr(args, attr, None) is not None:
            parts += [opt, str(getattr(args, attr))]
    if getattr(args, "delay", None) is not None:
        parts.append("--delay-compensation" if args.delay else "--no-delay-compensation")
    for s in args.sets:
        parts += ["--set", s]
    if args.fsw_khz is not None:
        parts += ["--fsw-khz", f"{args.fsw_khz:g}"]
    parts += ["--tolerance", f"{args.tolerance:g}", "--max-runs", str(args.max_runs)]
    for b in args.bench:
        parts += ["--bench", b]
    if args.output:
        parts += ["-o", str(args.output)]
    return shlex.join(parts)


def assemble(args: argparse.Namespace, model: Model, study: Any, rows: list[dict[str, Any]], target: float,
             timing: list[dict[str, Any]], wall: float, runner: Any, unmatched: list[str]) -> dict[str, Any]:
    """The JSON document of a study."""
    from codegen.stages.study import RULES

    sc = model.scenario
    return clean_json({
        "config": model.name, "config_file": str(study.config), "config_hash": model.config_hash(),
        "mpcgen": __version__, "versions": versions(), "topology": model.inverter.topology,
        "strategy": model.controller.strategy, "overrides": dict(study.base),
        "command": command_line(args),
        "scenario": {"set": getattr(sc, "set", "config"), "duration_s": sc.duration_s, "speed_mode": sc.speed_mode,
                     "speed_ref_rpm": sc.speed_ref_rpm, "load_nm": sc.load_nm, "window_s": sc.window_s},
        "config_lambda_u": model.controller.lambda_u, "config_horizon": model.controller.horizon,
        "target": {"f_ave_hz": target, "tolerance_percent": args.tolerance, "max_runs": args.max_runs,
                   "source": (f"--fsw-khz {args.fsw_khz:g}" if args.fsw_khz is not None else
                              f"f_ave of N = 1 at the config's lambda_u = {model.controller.lambda_u:g}")},
        "rules": RULES, "rows": rows, "bench_files_unmatched": unmatched,
        "machine": {"node": platform.node(), "platform": platform.platform(), "processor": platform.machine(),
                    "cpus": os.cpu_count()},
        "timing": {"runner": runner.kind, "workers": runner.workers if runner.kind != "scheduler" else None,
                   "wall_s": wall, "rounds": timing},
    })


# ---------------------------------------------------------------- the table
def _num(v: Any, spec: str = ".4g") -> str:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or (isinstance(v, float) and not math.isfinite(v)):
        return "n/a"
    return format(v, spec)


def _status(r: dict[str, Any]) -> str:
    s = "matched" if r["status"] == "matched" else r["status"]
    if not r["admissible"]:
        s += "; misbehaves: " + "; ".join(r["reasons"])[:120]
    return s


def table(data: dict[str, Any]) -> list[str]:
    """The study's table, one line per N."""
    head = ["N", "lambda_u", "f_ave / kHz (vs target)", "THD i_a / %", "THD i_a all bins / %", "T_rip RMSE / N*m",
            "nodes mean", "nodes max",
            "budget binds / % of periods", "node budget", "M7 est. cycles median / max", "runs", "status"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in data["rows"]:
        nd, cy = r["nodes"], r["cycles"]
        cells = [str(r["horizon"]), _num(r["lambda_u"], ".6g"),
                 f"{_num(r['f_ave_hz'] / 1e3, '.3f')} ({_num(r['f_error_percent'], '+.2f')} %)",
                 _num(r["THD_ia_percent"], ".3f"), _num(r["figures"].get("THD_ia_all_bins_percent"), ".3f"),
                 _num(r["T_rip_RMSE_nm"], ".4f"), _num(nd["mean"], ".1f"),
                 _num(nd["max"], "d"), _num(nd["budget_hit_percent"], ".2f"), _num(nd["node_budget"], "d"),
                 f"{_num(cy['median'], '.0f')} / {_num(cy['max'], '.0f')}" if cy else "not measured",
                 str(len(r["runs"])), _status(r)]
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def _windows(data: dict[str, Any]) -> list[str]:
    """Where the THD of each N was taken (once when every N has the same windows)."""
    def text(r: dict[str, Any]) -> str:
        return "; ".join(f"{w['run']}: {w['window']}" + ("" if w["steady"] else " (not steady)")
                         for w in r["thd_windows"])
    texts = [text(r) for r in data["rows"]]
    if len(set(texts)) == 1:
        return [f"- THD window (every N): {texts[0]}"]
    return [f"- THD window, N = {r['horizon']}: {t}" for r, t in zip(data["rows"], texts)]


def markdown(data: dict[str, Any]) -> str:
    """``study.md``: the command, the machine, what was matched and how, the table, and each N's commands."""
    t, m = data["target"], data["machine"]
    n_runs = sum(len(r["runs"]) for r in data["rows"])
    out = [f"# Horizon study of {data['config']}: THD, torque ripple and search effort at a matched switching "
           "frequency", "",
           f"- command: `{data['command']}`",
           f"- machine: {m['node']}, {m['platform']}, {m['processor']}, {m['cpus']} cores; {n_runs} closed-loop runs "
           f"in {data['timing']['wall_s']:.1f} s on {data['timing']['runner']}",
           f"- config `{data['config_file']}` ({data['topology']}, strategy {data['strategy']}), config hash "
           f"`{data['config_hash']}`, mpcgen {data['mpcgen']}; overrides: "
           + (", ".join(f"`{k}={json.dumps(v)}`" for k, v in data["overrides"].items()) or "none"),
           f"- scenario: scenario.set = {data['scenario']['set']}, duration {data['scenario']['duration_s']:g} s",
           f"- target f_ave: **{t['f_ave_hz'] / 1e3:.4g} kHz** ({t['source']}), tolerance +-{t['tolerance_percent']:g} %, "
           f"at most {t['max_runs']} runs per N",
           *_windows(data), "", "Rules:", ""]
    out += [f"- **{k}**: {v}" for k, v in data["rules"].items()]
    out += ["", *table(data), ""]
    if data["bench_files_unmatched"]:
        out += ["--bench files naming none of these config hashes (not used): "
                + ", ".join(f"`{f}`" for f in data["bench_files_unmatched"]), ""]
    out += ["Per N: config hash, C hash of the generated C, the run that reproduces it, the bench that measures it:", ""]
    for r in data["rows"]:
        out += [f"- N = {r['horizon']}: config hash `{r['config_hash']}`, C hash `{r['c_hash']}` "
                f"({r['c_hash_target']}); lambda_u runs: "
                + ", ".join(f"{p['lambda_u']:g} ({p['f_error_percent']:+.1f} %)" for p in r["runs"]),
                f"  - `{r['simulate_command']}`", f"  - `{r['bench_command']}`"]
    return "\n".join(out) + "\n"


# ---------------------------------------------------------------- the plot
def plot(path: Path, data: dict[str, Any]) -> Path:
    """THD and torque ripple against N (top), nodes per step and the budget's share (bottom)."""
    rows = data["rows"]
    ns = [r["horizon"] for r in rows]

    def col(key: str, sub: str | None = None) -> list[float]:
        vals = [(r[sub] or {}).get(key) if sub else r.get(key) for r in rows]
        return [float(v) if isinstance(v, (int, float)) else math.nan for v in vals]

    fig, (top, bottom) = new_figure(2, height=7.0)
    title = f"{data['config']}: f_ave matched to {data['target']['f_ave_hz'] / 1e3:.4g} kHz"
    top.plot(ns, col("THD_ia_percent"), "o-", color="C0", label="THD of i_a / %")
    top.set(ylabel="THD of i_a / %", title=heading(title, "current THD and torque ripple RMSE against the horizon N"))
    right = top.twinx()
    right.plot(ns, col("T_rip_RMSE_nm"), "s--", color="C1", label="torque ripple RMSE / N*m")
    right.set_ylabel("torque ripple RMSE / N*m")
    top.legend(handles=top.get_lines() + right.get_lines(), loc="best")
    bottom.plot(ns, col("mean", "nodes"), "o-", color="C2", label="nodes per step, mean")
    bottom.plot(ns, col("max", "nodes"), "v--", color="C3", label="nodes per step, max")
    bottom.set(xlabel="horizon N", ylabel="nodes entered per step", yscale="log",
               title="sphere-decoder nodes over the closed-loop states; node budget binds (% of periods) right")
    share = bottom.twinx()
    share.plot(ns, col("budget_hit_percent", "nodes"), "x:", color="C4", label="budget binds / % of periods")
    share.set_ylabel("budget binds / % of periods")
    bottom.legend(handles=bottom.get_lines() + share.get_lines(), loc="upper left")
    for ax in (top, bottom):
        ax.set_xticks(ns)
        ax.grid(True, alpha=0.3)
    described = {"horizons": ns, "lambda_u": col("lambda_u"), "f_ave_hz": col("f_ave_hz"),
                 "THD_ia_percent": col("THD_ia_percent"), "T_rip_RMSE_nm": col("T_rip_RMSE_nm"),
                 "nodes_mean": col("mean", "nodes"), "nodes_max": col("max", "nodes"),
                 "budget_hit_percent": col("budget_hit_percent", "nodes")}
    return save_figure(fig, path, described=clean_json(described))


def write_all(out_dir: Path, data: dict[str, Any], text: str) -> list[Path]:
    """``study.md``, ``study.json`` and ``study.png`` in ``out_dir``."""
    md, js = out_dir / "study.md", out_dir / "study.json"
    write_atomic(md, text.encode())
    write_atomic(js, (json.dumps(data, indent=2, sort_keys=True) + "\n").encode())
    return [md, js, plot(out_dir / "study.png", data)]
