"""Quantisation analysis of a fixed-point controller (``mpcgen report``; ``generate`` for fixed point).

Per strategy of the config's topology:

a. the Q format, representable range and resolution of every real input and
   output field (by unit), and every constant: float64 value of the fixed
   step's own definition (its sin/cos table size and polynomial: like with
   like), stored count, relative rounding error, and whether the float32
   controller defines it the same way (else "differs by definition" and why,
   never a comparison of two definitions);
b. the error of the fixed-point step's outputs (``te_est_nm``,
   ``psi_est_wb``, ``cost_best``) against a float64 ideal: the topology's
   Python reference run with :data:`FLOAT64` (float64 constants, one float64
   rounding per operation) on the same physical states (the fixed inputs
   decoded exactly); the float32 step's error against the same ideal is
   given alongside;
c. decision agreement with the float32 controller (``vector``, and ``sw``
   where the output has it) over the float32 controller's recorded
   closed-loop states and over random states, both controllers seeing the
   same physical state (float32 states converted once to the fixed format);
d. the closed-loop metrics of the fixed controller next to its float32 twin
   (the topology's ``simulate`` for both);
e. saturation inside the guard's limits: per saturating operation of the
   fixed step (``codegen.numfmt.fixed.count_saturations``: the C helper and
   the reference line calling it), the states of each set that pass the
   input guard and saturate it (numerics.md "Saturation inside the guard's
   limits": where it can happen and why it is benign).

:data:`FLOAT64` (``codegen.numfmt.float64``) is an analysis-only number format (no C, no
firmware, not a config choice).
"""
from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from codegen.config import family_strategies
from codegen.errors import UsageError
from codegen.kernels.trig import sincos_constants
from codegen.model import Model
from codegen.numfmt import FLOAT_CONTROLLER, IDEAL, QUANTISED, number_format
from codegen.numfmt.fixed import count_saturations
from codegen.records import REAL, Record, RecordLayout
from codegen.stages.fwdata import evenly_spaced
from codegen.teststates import in_format
from codegen.topology import topology_of

__all__ = ["analyse", "fixed_twin", "ERROR_FIELDS",
           "RIPPLE_KEYS"]

Log = Callable[[str], None]

#: outputs whose fixed-point error against the float64 ideal is reported
ERROR_FIELDS = ("te_est_nm", "psi_est_wb", "cost_best")
#: closed-loop metrics set side by side (those the topology's simulate reports)
RIPPLE_KEYS = ("T_rip_RMSE_nm", "psi_rip_RMSE_wb", "THD_ia_percent", "f_ave_hz", "Cal_ave", "Vo_std_v", "faults")


def fixed_twin(model: Model) -> Model:
    """``model`` itself if it is fixed point, else its fixed-point twin (per-signal formats)."""
    if number_format(model.controller.number_format).quantised:
        return model
    return model.with_controller(number_format=QUANTISED)


#: bins of the error histograms
HIST_BINS = 41
#: adversarial states (the topology's guard-edge cases) the saturation counts add to the analysed sets
ADVERSARIAL_STATES = 20_000


def _stats(err: np.ndarray, hist: bool = False) -> dict[str, Any]:
    """max |err|, RMS; ``hist``: a symmetric histogram of ``err`` (edges, counts)."""
    if err.size == 0:
        return {"max": float("nan"), "rms": float("nan")}
    a = np.abs(err)
    out: dict[str, Any] = {"max": float(a.max()), "rms": float(math.sqrt(float(np.mean(a * a))))}
    if hist:
        top = out["max"] or 1.0
        counts, edges = np.histogram(err, bins=HIST_BINS, range=(-top, top))
        out["hist"] = {"edges": edges.tolist(), "counts": counts.tolist()}
    return out


def _signal_rows(layout: RecordLayout, observed: np.ndarray, ok: np.ndarray) -> list[dict[str, Any]]:
    """Q format, range, resolution of every real field, and its largest decoded |x| over ``observed``."""
    sc = layout.nf.scaling
    rows = []
    for f in layout.fields:
        if f.kind != REAL:
            continue
        seen = np.abs(layout.decode(f.name, observed[f.name][ok])) if ok.any() else np.zeros(1)
        rows.append({"record": layout.record.name, "field": f.name, "unit": f.unit, "q": sc.describe(f.unit),
                     "largest": sc.largest(f.unit), "resolution": sc.resolution(f.unit),
                     "observed_max_abs": float(seen.max())})
    return rows


def _approximation_values(nf: Any) -> dict[str, float]:
    """The float64 values of the sin/cos constants of format ``nf`` by name: its own table size and
    polynomial (``codegen.kernels.trig``), which the float64 ideal's need not share."""
    return {name: float(v) for name, v, *_ in sincos_constants(nf)}


def _definition(name: str, own: float, unit: str, nf_fx: Any, t_32: Any, approximation: set[str]) -> str:
    """"same" when the float32 controller's constant ``name`` is ``own`` (the fixed definition's float64
    value) rounded to float32, else "differs by definition: ..." and why (the sin/cos table size and
    terms, or the two values)."""
    f32 = next((c for c in t_32.consts if c.name == name), None)
    if f32 is not None and t_32.nf.const(own, unit) == f32.value:
        return "same"
    a, b = nf_fx.sincos_form, t_32.nf.sincos_form
    if name in approximation and a != b:
        why = f"N={a.table_n} vs N={b.table_n} (sin/cos table; {a.sin_terms}+{a.cos_terms} vs " \
              f"{b.sin_terms}+{b.cos_terms} polynomial terms)"
    elif f32 is None:
        why = f"not in the {FLOAT_CONTROLLER} step"
    else:
        why = f"{QUANTISED} {own:.6g} vs {FLOAT_CONTROLLER} {float(f32.value):.6g}"
    return f"differs by definition: {why}"


def _constant_rows(t_fx: Any, t_64: Any, t_32: Any) -> list[dict[str, Any]]:
    """Every constant of the fixed step (``t_fx``): its float64 value under the fixed step's own
    definition (the float64 ideal's ``t_64`` value, the sin/cos constants of the fixed format's own
    table and polynomial), the stored count and value, the relative rounding error between the two
    (None without a float64 value), and whether the float32 controller's (``t_32``) constant of that
    name has the same definition (:func:`_definition`)."""
    sc = t_fx.scaling
    approximation = _approximation_values(t_fx.nf)
    own: dict[str, float] = {c.name: float(c.value) for c in t_64.consts} | approximation
    rows = []
    for c in t_fx.consts:
        stored = float(sc.decode(c.unit, int(c.value)))
        v = own.get(c.name)
        rel = None if v is None else abs(stored - v) / abs(v) if v else (0.0 if stored == 0.0 else float("inf"))
        rows.append({"name": c.name, "unit": c.unit, "q": sc.describe(c.unit), "value": v, "count": int(c.value),
                     "stored": stored, "rel_error": rel, "doc": c.doc,
                     "definition": "no float64 value" if v is None else
                     _definition(c.name, v, c.unit, t_fx.nf, t_32, set(approximation))})
    return rows


def _agreement(topo: Any, t32: Any, t_fx: Any, x32: np.ndarray, x_fx: np.ndarray) -> dict[str, Any]:
    """Decision agreement of the fixed and float32 steps on the same physical states (``x32`` float32
    records, ``x_fx`` the same states in fixed point), over the states both input guards pass;
    ``fault_mismatch``: states only one guard trips (a value at a guard limit rounded across it)."""
    o32, ofx = topo.step_batch(t32, x32), topo.step_batch(t_fx, x_fx)
    ok = (o32["fault"] == 0) & (ofx["fault"] == 0)
    n = int(ok.sum())
    out: dict[str, Any] = {"states": len(x32), "compared": n,
                           "fault_mismatch": int(((o32["fault"] == 0) != (ofx["fault"] == 0)).sum())}
    for name in ("vector", "sw"):
        if name in o32.dtype.names:
            same = int((o32[name][ok] == ofx[name][ok]).sum())
            out[name] = {"agree": same, "fraction": same / n if n else float("nan")}
    return out


def _errors(topo: Any, output: Record, t_fx: Any, t32: Any, t_64: Any, x_fx: np.ndarray) -> dict[str, Any]:
    """Fixed and float32 outputs against the float64 ideal on the same physical states ``x_fx`` (fixed)."""
    lay_fx = topo.input_record.bind(t_fx.nf)
    x64 = in_format(x_fx, topo.input_record.bind(number_format(IDEAL)), lay_fx)
    x32 = in_format(x_fx, topo.input_record.bind(t32.nf), lay_fx)
    ofx, o32, o64 = topo.step_batch(t_fx, x_fx), topo.step_batch(t32, x32), topo.step_batch(t_64, x64)
    ok = (ofx["fault"] == 0) & (o32["fault"] == 0) & (o64["fault"] == 0)
    out_fx, out_32 = output.bind(t_fx.nf), output.bind(t32.nf)
    res: dict[str, Any] = {"states": int(ok.sum())}
    for name in ERROR_FIELDS:
        ideal = o64[name][ok]
        res[name] = {"unit": output.field(name).unit,
                     QUANTISED: _stats(out_fx.decode(name, ofx[name][ok]) - ideal, hist=True),
                     FLOAT_CONTROLLER: _stats(out_32.decode(name, o32[name][ok]) - ideal),
                     "ideal_max_abs": float(np.abs(ideal).max()) if ideal.size else 0.0}
    return res


def _saturations(topo: Any, t_fx: Any, sets: dict[str, np.ndarray]) -> dict[str, Any]:
    """Per set of fixed states: the states passing the input guard and, per saturating operation, how
    many of them saturate it (sites with none left out)."""
    out = {}
    for key, x in sets.items():
        with count_saturations(len(x)) as rec:
            o = topo.step_batch(t_fx, x)
        ok = o["fault"] == 0
        out[key] = {"states": len(x), "passing": int(ok.sum()), "sites": rec.counts(ok)}
    return out


def _runs(strategy_result: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """The runs of one strategy's simulate result: {run: metrics} (a single-run result is "scenario")."""
    if "T_rip_RMSE_nm" in strategy_result:
        return {"scenario": strategy_result}
    return {k: v for k, v in strategy_result.items() if isinstance(v, dict) and "T_rip_RMSE_nm" in v}


def _closed_loop(model_fx: Model, model_32: Model, strategies: list[str], log: Log,
                 traces: Path | None) -> dict[str, Any]:
    """Closed-loop metrics of the fixed controller and its float32 twin, side by side, with the ratio."""
    topo = topology_of(model_fx)
    res = {}
    for label, m in ((QUANTISED, model_fx), (FLOAT_CONTROLLER, model_32)):
        path = traces / f"{label}.npz" if traces is not None else None
        res[label] = topo.simulate(m, strategies, None, log=log, traces=path)["strategies"]
    out: dict[str, Any] = {}
    for s in strategies:
        runs_fx, runs_32 = _runs(res[QUANTISED][s]), _runs(res[FLOAT_CONTROLLER][s])
        out[s] = {}
        for run, m_fx in runs_fx.items():
            m_32 = runs_32[run]
            row = {}
            for k in RIPPLE_KEYS:
                if k not in m_fx or k not in m_32:
                    continue
                if m_fx[k] is None or m_32[k] is None:  # a metric the run could not compute (its reason is there)
                    row[k] = {QUANTISED: m_fx[k], FLOAT_CONTROLLER: m_32[k], "ratio": None}
                    continue
                a, b = float(m_fx[k]), float(m_32[k])
                row[k] = {QUANTISED: a, FLOAT_CONTROLLER: b, "ratio": a / b if b else (1.0 if a == 0 else float("inf"))}
            out[s][run] = row
    return out


def _at_most(x: np.ndarray, n: int | None) -> np.ndarray:
    """At most ``n`` of the records ``x``, evenly spaced (all of them for None)."""
    return x if n is None else evenly_spaced(x, n)


def analyse(model: Model, strategies: list[str] | None = None, random_states: int = 20_000,
            max_closed_loop: int | None = None, log: Log = lambda s: None,
            traces: Path | None = None) -> dict[str, Any]:
    """The quantisation analysis (module doc, a-d) of the fixed-point ``model`` for ``strategies``
    (default: every strategy of the family of its strategy).  ``max_closed_loop``: at most this many of the recorded
    closed-loop states (evenly spaced); ``traces``: directory the closed-loop
    runs' time series are written to (``fixed.npz``, ``float32.npz``).  JSON-ready dict."""
    if not number_format(model.controller.number_format).quantised:
        raise UsageError(f"the quantisation report is about fixed point; {model.source} has "
                         f"controller.number_format = {model.controller.number_format!r} (use --number-format fixed)")
    topo = topology_of(model)
    chosen = list(strategies or family_strategies(model.inverter.topology, model.controller.strategy))
    per: dict[str, Any] = {}
    for s in chosen:
        m_fx = model.with_controller(strategy=s)
        m_32 = m_fx.with_controller(number_format=FLOAT_CONTROLLER, fixed_q=None)
        log(f"quantisation {model.name} / {s}: deriving fixed, float32 and float64 tables")
        t_fx, t_32 = topo.derive(m_fx), topo.derive(m_32)
        lib = topo.host_library(m_32, t_32, with_sim=True)
        log(f"quantisation {model.name} / {s}: recording the float32 closed-loop states")
        cl32 = _at_most(topo.closed_loop_states(m_32, lib), max_closed_loop)
        rnd32 = topo.random_states(m_32, t_32, random_states, 1)
        cl_fx = in_format(cl32, topo.input_record.bind(t_fx.nf))
        log(f"quantisation {model.name} / {s}: recording the fixed-point closed-loop states")
        own_fx = _at_most(topo.closed_loop_states(m_fx, topo.host_library(m_fx, t_fx, with_sim=True)),
                            max_closed_loop)
        own32 = in_format(own_fx, topo.input_record.bind(t_32.nf), topo.input_record.bind(t_fx.nf))
        rnd_fx = in_format(rnd32, topo.input_record.bind(t_fx.nf))
        t_64 = topo.derive(m_fx.with_controller(number_format=IDEAL, fixed_q=None))
        output = topo.output_record(m_fx)
        errors = {"closed_loop": _errors(topo, output, t_fx, t_32, t_64, cl_fx),
                  "random": _errors(topo, output, t_fx, t_32, t_64, rnd_fx)}
        o_fx = topo.step_batch(t_fx, cl_fx)
        ok_in = o_fx["fault"] == 0
        sc = t_fx.scaling
        per[s] = {
            "scaling": {"frac_bits": sc.frac_bits, "exps_v_a_s": list(sc.exps), "mode": sc.mode},
            "signals": (_signal_rows(topo.input_record.bind(t_fx.nf), cl_fx, ok_in)
                        + _signal_rows(output.bind(t_fx.nf), o_fx, ok_in)),
            "constants": _constant_rows(t_fx, t_64, t_32),
            "errors": errors,
            "agreement": {"closed_loop": _agreement(topo, t_32, t_fx, cl32, cl_fx),
                          "closed_loop_fixed": _agreement(topo, t_32, t_fx, own32, own_fx),
                          "random": _agreement(topo, t_32, t_fx, rnd32, rnd_fx)},
            "saturations": _saturations(topo, t_fx, {
                "closed_loop": cl_fx, "closed_loop_fixed": own_fx, "random": rnd_fx,
                "adversarial": topo.adversarial_states(m_fx, t_fx, ADVERSARIAL_STATES)}),
        }
    out: dict[str, Any] = {"config": model.name, "config_hash": model.config_hash(), "topology": topo.name,
                           "strategies": per}
    cl = _closed_loop(model, model.with_controller(number_format=FLOAT_CONTROLLER, fixed_q=None), chosen, log, traces)
    for s in chosen:
        per[s]["closed_loop"] = cl[s]
    return out

