"""The quantisation report: markdown, PNG plots and JSON of :func:`codegen.stages.quantisation.analyse`.

``mpcgen report CFG`` prints the markdown (``-o DIR``: writes
``<prefix>_quantisation.md`` and the plots there; ``--json F``: the data);
``mpcgen generate`` writes the markdown of the generated strategy for a
fixed-point config.  Each strategy's section names the C hash
(``codegen.manifest``) of the C generated for the config's target, the hash
``<prefix>_manifest.json`` beside that C names.  The markdown holds no dates,
paths or wall times: the same config gives the same bytes.
"""
from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from codegen import __version__
from codegen.manifest import C_HASH_DEFINITION, c_hash, manifest_name
from codegen.model import Model
from codegen.numfmt import FLOAT_CONTROLLER, QUANTISED
from codegen.stages.quantisation import ERROR_FIELDS, RIPPLE_KEYS

__all__ = ["c_hashes", "markdown", "plots", "report_name"]

#: the target the analysis may run on for another target's report (``generate``)
HOST = "host"

_SETS = {
    "closed_loop": "float32 closed-loop states (converted to fixed)",
    "closed_loop_fixed": "fixed closed-loop states (converted to float32)",
    "random": "random states (float32, converted to fixed)",
    "adversarial": "adversarial states (guard edges, fixed)",
}


def report_name(model: Model) -> str:
    """File name of the markdown report."""
    return f"{model.prefix}_quantisation.md"


def _g(x: float | None, spec: str = ".4g") -> str:
    """A number for the tables; ``n/a`` for NaN and for a metric the run could not compute (None)."""
    return "n/a" if x is None or x != x else format(x, spec)


def _pct(x: float) -> str:
    return "n/a" if x != x else f"{100 * x:.3f} %"


def _formats(d: dict[str, Any]) -> list[str]:
    sc = d["scaling"]
    ev, ea, es = sc["exps_v_a_s"]
    lines = ["", f"Scaling: {sc['mode']}, G = {sc['frac_bits']} fractional bits of the per-unit values, "
                 f"bases 2^{ev} V, 2^{ea} A, 2^{es} s (a value of unit u is stored in Q(G - e(u))).", "",
             "| record | field | unit | Q format | range (+-) | resolution | largest \\|x\\| seen | headroom |",
             "|---|---|---|---|---|---|---|---|"]
    for r in d["signals"]:
        seen = r["observed_max_abs"]
        head = f"{r['largest'] / seen:.3g}x" if seen else "-"
        lines.append(f"| {r['record']} | {r['field']} | {r['unit'] or '1'} | {r['q']} | {_g(r['largest'])} | "
                     f"{_g(r['resolution'])} | {_g(seen)} | {head} |")
    lines += ["", "Largest |x| seen: over the fixed step's inputs and outputs on the float32 closed-loop states.",
              "", "| constant | unit | Q format | value (float64, fixed definition) | stored count | stored value | "
                  "relative error | float32 definition |",
              "|---|---|---|---|---|---|---|---|"]
    for c in d["constants"]:
        value = "-" if c["value"] is None else repr(c["value"])
        rel = "-" if c["rel_error"] is None else _g(c["rel_error"], ".3e")
        lines.append(f"| {c['name']} | {c['unit'] or '1'} | {c['q']} | {value} | {c['count']} | "
                     f"{c['stored']!r} | {rel} | {c['definition']} |")
    lines += ["", "Relative error: the stored value against the float64 value of the same definition, the fixed "
                  "step's own (its sin/cos table size and polynomial). 'differs by definition': the float32 "
                  "controller's constant of that name is another value (another sin/cos table or guard), so the two "
                  "are not compared. The sin/cos constants' precision is the approximation's (a tested property, "
                  "numerics.md), not checked per constant: a small coefficient of a high power of r keeps few counts."]
    return lines


def _errors(d: dict[str, Any]) -> list[str]:
    lines = ["", "| states | output | unit | fixed max | fixed RMS | float32 max | float32 RMS | ideal max \\|x\\| |",
             "|---|---|---|---|---|---|---|---|"]
    for key, e in d["errors"].items():
        for name in ERROR_FIELDS:
            v = e[name]
            lines.append(f"| {key} ({e['states']}) | {name} | {v['unit'] or '1'} | {_g(v[QUANTISED]['max'], '.3e')} | "
                         f"{_g(v[QUANTISED]['rms'], '.3e')} | {_g(v[FLOAT_CONTROLLER]['max'], '.3e')} | "
                         f"{_g(v[FLOAT_CONTROLLER]['rms'], '.3e')} | {_g(v['ideal_max_abs'])} |")
    return lines


def _agreement(d: dict[str, Any]) -> list[str]:
    lines = ["", "| states | count | both guards pass | one guard trips | vector agrees | sw agrees |",
             "|---|---|---|---|---|---|"]
    for key, a in d["agreement"].items():
        sw = _pct(a["sw"]["fraction"]) if "sw" in a else "-"
        lines.append(f"| {_SETS.get(key, key)} | {a['states']} | {a['compared']} | {a['fault_mismatch']} | "
                     f"{_pct(a['vector']['fraction'])} | {sw} |")
    return lines


def _saturation(d: dict[str, Any]) -> list[str]:
    """States passing the input guard that saturate each saturating operation, per set."""
    sat = d.get("saturations", {})
    lines = ["", "Operations whose exact result left the int32 range on states that pass the input guard "
                 "(the C helper and the reference line that calls it; each such result is the int32 extreme, "
                 "numerics.md \"Saturation inside the guard's limits\" says where this can happen and why it "
                 "is benign).", "",
             "| states | passing the guard | operation | states saturating it |", "|---|---|---|---|"]
    for key, v in sat.items():
        if not v["sites"]:
            lines.append(f"| {_SETS.get(key, key)} | {v['passing']} | none | 0 |")
        for site, k in v["sites"].items():
            lines.append(f"| {_SETS.get(key, key)} | {v['passing']} | `{site}` | {k} ({_pct(k / v['passing'])}) |")
    return lines


def _closed_loop(d: dict[str, Any]) -> list[str]:
    lines = ["", "| run | metric | fixed | float32 | fixed / float32 |", "|---|---|---|---|---|"]
    for run, row in d["closed_loop"].items():
        for k in RIPPLE_KEYS:
            if k in row:
                v = row[k]
                lines.append(f"| {run} | {k} | {_g(v[QUANTISED])} | {_g(v[FLOAT_CONTROLLER])} | {_g(v['ratio'], '.4f')} |")
    return lines


def c_hashes(model: Model, strategies: Iterable[str]) -> dict[str, str]:
    """The C hash (``codegen.manifest``) of the C ``generate`` writes for each strategy of ``model`` and
    ``model.target``."""
    return {s: c_hash(model.with_controller(strategy=s)) for s in strategies}


def markdown(model: Model, data: dict[str, Any], hashes: Mapping[str, str],
             plot_files: dict[str, list[str]] | None = None) -> str:
    """The report of ``data`` (``analyse`` of ``model``, or of its host twin: the same arithmetic) about
    the generated C of ``model.target``; ``hashes``: per strategy, the C hash of that C (:func:`c_hashes`);
    ``plot_files``: per strategy, the PNG file names."""
    lines = [f"# {model.prefix}: quantisation report (fixed point)", "",
             f"- config: `{model.name}` (hash {model.config_hash()}), target {model.target}, topology "
             f"{data['topology']}, mpcgen {__version__}"]
    if data["config_hash"] != model.config_hash():
        if data["config_hash"] != model.replace(target=HOST).config_hash():
            raise ValueError(f"the analysis is of config hash {data['config_hash']}, neither {model.name} "
                             f"({model.config_hash()}) nor its {HOST} twin")
        lines.append(f"- analysed: the {HOST} build and the Python reference of this config with target.name = "
                     f"{HOST} (the same arithmetic: target profiles differ only in placement attributes and comments)")
    lines += [f"- generated C: the C hash of each strategy names the `.c`/`.h` files `mpcgen generate` writes for "
              f"target {model.target} (the `c_hash` of `{manifest_name(model)}`; {C_HASH_DEFINITION})",
              "- ideal: the topology's Python reference in float64 (float64 constants, one float64 rounding per "
              "operation) on the fixed inputs decoded exactly; the float32 step on the same states is the second column",
              "- agreement: fixed vs float32 decisions on the same physical states, over the states both input guards "
              "pass; 'one guard trips': a value at a guard limit rounded across it by the conversion, or an angle "
              "beyond the fixed-point angle guard",
              "- closed loop: the topology's scenario run(s) with the fixed controller and with its float32 twin"]
    seen: dict[str, str] = {}
    for s, d in data["strategies"].items():
        lines += ["", f"## Strategy {s}", "", f"- generated C for target {model.target}: C hash `{hashes[s]}`",
                  "", "### Q formats, ranges and constants"]
        key = repr((d["scaling"], [(r["field"], r["q"]) for r in d["signals"]], d["constants"]))
        if key in seen:
            lines += ["", f"Same formats and constants as {seen[key]}."]
        else:
            seen[key] = s
            lines += _formats(d)
        lines += ["", "### Prediction error against the float64 ideal", *_errors(d)]
        lines += ["", "### Decision agreement with the float32 controller", *_agreement(d)]
        if "saturations" in d:
            lines += ["", "### Saturation inside the guard's limits", *_saturation(d)]
        if "closed_loop" in d:
            lines += ["", "### Closed loop: fixed vs float32", *_closed_loop(d)]
        for f in (plot_files or {}).get(s, []):
            lines += ["", f"![{f}]({f})"]
    return "\n".join(lines) + "\n"


def plots(model: Model, data: dict[str, Any], traces: Path | None, outdir: Path) -> dict[str, list[str]]:
    """Per strategy: the torque of every closed-loop run, fixed vs float32 (from ``traces``:
    ``fixed.npz``, ``float32.npz``), and the histograms of the fixed outputs' errors; file names."""
    from codegen.plotting import new_figure, save_figure

    out: dict[str, list[str]] = {}
    runs: dict[str, Any] = {}
    if traces is not None and (traces / f"{QUANTISED}.npz").exists():
        runs = {label: np.load(traces / f"{label}.npz") for label in (QUANTISED, FLOAT_CONTROLLER)}
    for s, d in data["strategies"].items():
        files = []
        for run in d.get("closed_loop", {}) if runs else {}:
            key = f"{s}/{run}"
            if f"{key}/te_nm" not in runs[QUANTISED].files:
                continue
            fig, (ax,) = new_figure()
            for label, style in ((FLOAT_CONTROLLER, {"color": "tab:orange", "lw": 0.5}),
                                 (QUANTISED, {"color": "tab:blue", "lw": 0.5, "alpha": 0.8})):
                z = runs[label]
                ax.plot(z[f"{key}/t_s"], z[f"{key}/te_nm"], label=f"Te, {label} controller", **style)
            z = runs[QUANTISED]
            ax.plot(z[f"{key}/t_s"], z[f"{key}/torque_ref_nm"], color="k", lw=0.8, label="T* (fixed)")
            ax.set(xlabel="time t / s", ylabel="torque / (N*m)", title=f"{model.name} {s} {run}: torque, fixed vs float32")
            ax.grid(True, alpha=0.3)
            ax.legend(loc="best")
            name = f"{model.prefix}_quant_{s}_{run}_torque.png"
            save_figure(fig, outdir / name)
            files.append(name)
        fig, axes = new_figure(len(ERROR_FIELDS), height=2.6 * len(ERROR_FIELDS))
        for ax, field in zip(axes, ERROR_FIELDS):
            unit = next((e[field]["unit"] for e in d["errors"].values()), "")
            for key, e in d["errors"].items():
                h = e[field][QUANTISED].get("hist")
                if h:
                    edges = np.asarray(h["edges"])
                    ax.stairs(h["counts"], edges, label=key)
            ax.set(xlabel=f"fixed - float64 ideal, {field} / {unit or '1'}", ylabel="states",
                   title=f"{model.name} {s}: error of {field}")
            ax.grid(True, alpha=0.3)
            ax.legend(loc="best")
        name = f"{model.prefix}_quant_{s}_errors.png"
        save_figure(fig, outdir / name)
        files.append(name)
        out[s] = files
    for z in runs.values():
        z.close()
    return out
