"""``mpcgen tune``: cost-function weights and thresholds chosen from the closed loop, with the rule stated.

For each strategy, the closed loop (``simulate``'s scenario: the config's, or
its topology's scenario set) is evaluated over a grid of the tuned fields and
then refined near the front, on the sweep stage's runner
(:class:`codegen.stages.sweep_runner.Session`: a Dask LocalCluster, a
``--scheduler``, or ``--serial``).  docs/tuning.md is the user's manual.

Fields (``section.field`` as in the config; real-valued fields of the
config's topology only):

* ``--weight FIELD[=LO:HI]``: searched on a log scale, 0 < LO < HI; default
  range the config's value / 10^1.5 .. * 10^1.5, clipped to the field's
  allowed range;
* ``--threshold FIELD[=LO:HI]``: searched on a linear scale; default range
  0 .. 2 x the config's value, clipped to the allowed range.

Search rule (a coarse-to-fine search on a lattice of each field's range):

1. round 0: ``--grid N`` values per field (default 9 for one field, 5 for
   two, 4 for three, 3 beyond), evenly spaced on the field's scale, and their
   cartesian product;
2. rounds 1 .. ``--rounds K`` (default 2): the spacing halves; the ``--focus M``
   (default 3) points of the strategy's admissible front nearest the ideal
   point (the recommendation and its runners-up, below; ``--focus 0``: every
   point of the admissible front; the front of all its points when none is
   admissible) get their neighbours at +- the new spacing along each field,
   those not evaluated yet.  With one field this bisects between those front
   points and their neighbours: the front is refined where the recommendation
   is decided.

Lattice values are rounded to 6 significant digits.  Every value the search
can reach lies in the checked range, and every run's config is loaded and
checked as a config file is before it runs.

Each point of a strategy is one run (:func:`codegen.stages.sweep_runner.run_task`);
its figures (:data:`FIGURES`) are aggregated over the scenario runs (the
steady entry of a run where the scenario set has one): the mean over the
runs whose window for that figure is steady (all runs when none is), the
maximum for the peak current.  A point is *admissible* when no run tripped
the guard, every run's tracking verdict is ok and no run has an anomaly
(current spike above 2 x rated or flux collapse below 0.6 x its mean in a
steady window: :func:`codegen.metrics.drive_figures`); the others are marked
and never recommended.

Front: the points not dominated in the ``--objectives`` (all minimised;
default torque ripple, flux ripple and the all-bin current THD, and the
switching frequency when a weight that prices switching is tuned:
:data:`SWITCHING_WEIGHTS`).
Recommendation: among the admissible front, the point nearest (Euclidean) to
the ideal point after scaling each objective to [0, 1] over the admissible
front (0 its best value there, 1 its worst); ties go to the lowest field
values.

The results do not depend on the runner: each run is the same computation, the
outputs of a round are merged in plan order, and the refinement reads only
them (``tune.json`` without ``timing`` is the same bit for bit).
"""
from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from codegen.config import REAL, all_fields, family_of, load_config, owners, schema_for
from codegen.errors import ConfigError, MpcgenError, UsageError
from codegen.model import Model
from codegen.results import emit, metric_sets

__all__ = ["TuneAxis", "Figure", "FIGURES", "DEFAULT_OBJECTIVES", "SWITCHING_WEIGHTS", "allowed_range", "parse_axis",
           "parse_objectives", "default_objectives", "Search", "runs_of", "evaluate", "dominates", "front", "ranked",
           "recommend", "command", "MAX_EVALUATIONS"]

Log = Callable[[str], None]

#: decades either side of the config's value a weight is searched over by default
WEIGHT_DECADES = 1.5
#: values per field in round 0, by the number of tuned fields (beyond: the last)
DEFAULT_GRID = (9, 5, 4, 3)
#: refinement rounds by default, and at most
DEFAULT_ROUNDS, MAX_ROUNDS = 2, 8
#: admissible-front points refined each round by default (those nearest the ideal point; 0: all)
DEFAULT_FOCUS = 3
#: most runs (points x strategies) one tune may evaluate; checked for round 0 and bounding the refinement
MAX_EVALUATIONS = 5000
#: significant digits of a lattice value
DIGITS = 6


@dataclass(frozen=True)
class Figure:
    """One figure of a tuned point: the metric key, a short name (plots, --objectives), its axis label, how
    the scenario runs are combined (``mean``/``max``) and where a run holds it (``shown``: the run's printed
    entry, its steady entry when there is one; ``main``: the run's own entry, with its tracking verdict)."""

    key: str
    short: str
    label: str
    combine: str
    source: str
    window: str  # the run's window entry that says whether the figure's window was steady


#: the figures of a tuned point, in table order (``Vo_std_v``: topologies with a neutral point)
FIGURES: tuple[Figure, ...] = (
    Figure("T_rip_RMSE_nm", "T_rip", "torque ripple RMSE / N*m", "mean", "shown", "T_rip_RMSE_nm"),
    Figure("psi_rip_RMSE_wb", "psi_rip", "flux ripple RMSE / Wb", "mean", "shown", "psi_rip_RMSE_wb"),
    Figure("THD_ia_percent", "THD", "THD of i_a, integer harmonics / %", "mean", "shown", "THD_ia_percent"),
    Figure("THD_ia_all_bins_percent", "THD_all", "THD of i_a, all bins / %", "mean", "main",
           "THD_ia_all_bins_percent"),
    Figure("f_ave_hz", "f_ave", "average switching frequency / Hz", "mean", "shown", "f_ave_hz"),
    Figure("Vo_std_v", "Vo", "neutral-point ripple (std) / V", "mean", "shown", "Vo_std_v"),
    Figure("i_peak_per_rated", "i_peak", "peak current in steady windows / rated", "max", "main", ""),
    Figure("Cal_ave", "Cal", "evaluations per step", "mean", "shown", "Cal_ave"),
)
_BY_NAME = {**{f.key: f for f in FIGURES}, **{f.short: f for f in FIGURES}}
#: the objectives of the front unless --objectives says otherwise
DEFAULT_OBJECTIVES = ("T_rip_RMSE_nm", "psi_rip_RMSE_wb", "THD_ia_all_bins_percent")
#: weights that price switching (docs/mpcc.md eq. (2)): a larger one trades ripple for a lower switching
#: frequency, so the default objectives add ``f_ave_hz`` when one is tuned (without it every default
#: objective favours the smallest value and the front is one point at the range's end)
SWITCHING_WEIGHTS = ("controller.lambda_u",)


# ---------------------------------------------------------------- fields
@dataclass(frozen=True)
class TuneAxis:
    """One tuned field: its range and scale (``weight``: log, ``threshold``: linear)."""

    field: str
    role: str
    lo: float
    hi: float
    nominal: float | None

    @property
    def log(self) -> bool:
        return self.role == "weight"

    def value(self, i: int, top: int) -> float:
        """The value at lattice index ``i`` of ``0 .. top`` (the ends exactly LO and HI)."""
        if i <= 0:
            return self.lo
        if i >= top:
            return self.hi
        u = i / top
        v = self.lo * (self.hi / self.lo) ** u if self.log else self.lo + (self.hi - self.lo) * u
        return float(f"{v:.{DIGITS}g}")

    def describe(self) -> str:
        return (f"{self.field} {self.lo:.6g}..{self.hi:.6g} ({'log' if self.log else 'linear'} scale"
                f"{'' if self.nominal is None else f', config value {self.nominal:.6g}'})")


class _Values(Mapping[str, object]):
    """The config's values by field path, as an interval bound (a :class:`codegen.config.Ref`) reads them."""

    def __init__(self, model: Model) -> None:
        self.model = model

    def __getitem__(self, key: str) -> object:
        from codegen.stages.sweep import field_value

        return field_value(self.model, key)

    def __iter__(self) -> Iterator[str]:
        return iter(all_fields())

    def __len__(self) -> int:
        return len(all_fields())


def _bound(b: Any, values: Mapping[str, object]) -> float:
    return float(b.resolve(values)) if hasattr(b, "resolve") else float(b)


def allowed_range(model: Model, name: str) -> tuple[float, float]:
    """The ends of field ``name``'s allowed interval in ``model``'s config (bounds naming other fields
    resolved; whether an end is open is the interval's ``describe``)."""
    iv = schema_for(model.inverter.topology)[name].interval
    if iv is None:
        raise ValueError(f"{name} has no interval")
    values = _Values(model)
    return _bound(iv.lo, values), _bound(iv.hi, values)


def parse_axis(option: str, text: str, model: Model) -> TuneAxis:
    """``SECTION.FIELD`` or ``SECTION.FIELD=LO:HI`` of ``--weight`` / ``--threshold``, checked against the
    field's kind, topology and allowed range (one line naming the field, value and allowed range)."""
    from codegen.stages.sweep import field_value, known_field

    role = "weight" if option == "--weight" else "threshold"
    name, sep, rng = (part.strip() for part in text.partition("="))
    name = known_field(option, name, text)
    topo = model.inverter.topology
    if topo not in owners(name):
        raise UsageError(f"{option} {name}: not a field of a '{topo}' config (it belongs to inverter.topology = "
                         f"{' or '.join(repr(t) for t in owners(name))}); tuning it would change nothing")
    spec = schema_for(topo)[name]
    family = family_of(topo, model.controller.strategy)
    if spec.families and family not in spec.families:
        raise UsageError(f"{option} {name}: not read by controller.strategy = '{model.controller.strategy}' (only "
                         f"the {' and '.join(spec.families)} strategies read it); tuning it would change nothing")
    if spec.kind != REAL or spec.interval is None:
        raise UsageError(f"{option} {name}: not a real-valued field; only numbers can be tuned")
    values = _Values(model)
    iv = spec.interval
    a_lo, a_hi = _bound(iv.lo, values), _bound(iv.hi, values)
    allowed = iv.describe(values)
    raw = field_value(model, name)
    nominal = float(raw) if isinstance(raw, (int, float)) and not isinstance(raw, bool) else None
    if sep:
        form = "LO:HI with finite numbers LO < HI"
        try:
            lo, hi = (float(v) for v in rng.split(":"))
        except ValueError:
            raise UsageError(f"{option} {text!r}: expected {form}") from None
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise UsageError(f"{option} {text!r}: expected {form}")
        for v in (lo, hi):
            if iv.below(v, values) or iv.above(v, values):
                raise UsageError(f"{option} {name}={rng}: {v:g} is outside the allowed range {allowed} of {name}")
    else:
        if nominal is None or nominal <= 0:
            raise UsageError(f"{option} {name}: the config's value is {raw!r}; with no value > 0 to search around, "
                             f"give the range: {option} {name}=LO:HI (allowed {allowed})")
        if role == "weight":
            lo, hi = nominal / 10 ** WEIGHT_DECADES, nominal * 10 ** WEIGHT_DECADES
        else:
            lo, hi = 0.0, 2.0 * nominal
        lo, hi = max(lo, a_lo), min(hi, a_hi)
        span = hi - lo
        if (iv.lo_open and lo <= a_lo) or lo < a_lo:
            lo = a_lo + 0.01 * span
        if (iv.hi_open and hi >= a_hi) or hi > a_hi:
            hi = a_hi - 0.01 * span
        lo, hi = float(f"{lo:.{DIGITS}g}"), float(f"{hi:.{DIGITS}g}")
    if role == "weight" and lo <= 0:
        raise UsageError(f"{option} {name}={lo:g}:{hi:g}: a weight is searched on a log scale: LO must be > 0 "
                         f"(allowed range {allowed}; tune it with --threshold for a linear scale from 0)")
    return TuneAxis(name, role, lo, hi, nominal)


def default_objectives(fields: list[str] | tuple[str, ...] = ()) -> tuple[str, ...]:
    """The objectives without ``--objectives``: :data:`DEFAULT_OBJECTIVES`, and ``f_ave_hz`` when one of the
    tuned ``fields`` is a switching weight (:data:`SWITCHING_WEIGHTS`)."""
    switching = any(f in SWITCHING_WEIGHTS for f in fields)
    return DEFAULT_OBJECTIVES + (("f_ave_hz",) if switching else ())


def parse_objectives(text: str | None, fields: list[str] | tuple[str, ...] = ()) -> tuple[Figure, ...]:
    """The figures of ``--objectives`` (a comma list of keys or short names; default
    :func:`default_objectives` of the tuned ``fields``)."""
    names = list(default_objectives(fields)) if text is None else [t.strip() for t in text.split(",") if t.strip()]
    allowed = ", ".join(f"{f.key} ({f.short})" for f in FIGURES)
    out: list[Figure] = []
    for n in names:
        if n not in _BY_NAME:
            raise UsageError(f"--objectives: '{n}' is not a figure of a tuned point; allowed: {allowed}")
        if _BY_NAME[n] in out:
            raise UsageError(f"--objectives: '{n}' is named twice")
        out.append(_BY_NAME[n])
    if len(out) < 2:
        raise UsageError(f"--objectives = {text!r}: a front needs at least two figures; allowed: {allowed}")
    return tuple(out)


# ---------------------------------------------------------------- one evaluated point
def runs_of(result: dict[str, Any], strategy: str) -> list[tuple[str, dict[str, Any], dict[str, Any]]]:
    """(scenario run, shown entry, main entry) of ``strategy`` in a run's simulate result: a scenario set's
    ``<key>_steady`` entry is shown for ``<key>`` (the figures ``simulate`` prints), the verdict and drive
    figures are the ``<key>`` entry's."""
    sets = {scen: m for s, scen, m in metric_sets(result) if s == strategy}
    if None in sets:
        return [("", sets[None], sets[None])]
    out = []
    for scen, m in sets.items():
        assert scen is not None
        if scen.endswith("_steady") and scen[: -len("_steady")] in sets:
            continue
        out.append((scen, sets.get(f"{scen}_steady", m), m))
    return out


def _finite(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(float(v))


def _steady(f: Figure, shown: dict[str, Any], main: dict[str, Any]) -> bool:
    """Was ``f``'s window steady in this run (as the run's own entries say)?"""
    if f.source == "shown":
        return f.window not in shown.get("not_steady", {})
    info = main.get("drive_figures", {}).get(f.window, {}) if f.window else {}
    return info.get("steady", True) is not False


def evaluate(result: dict[str, Any], strategy: str) -> dict[str, Any]:
    """The figures of one point of ``strategy`` from its run's simulate ``result``: ``figures``, the
    verdict (``faults``, ``tracking``, ``anomalies``, ``locked_cycle_runs``), ``admissible`` with the
    ``reasons`` it is not, and ``scenario_runs`` (every scalar metric of each scenario run)."""
    runs = runs_of(result, strategy)
    figures: dict[str, Any] = {}
    for f in FIGURES:
        vals = [(float(sh[f.key] if f.source == "shown" else mn[f.key]), _steady(f, sh, mn))
                for _scen, sh, mn in runs if _finite((sh if f.source == "shown" else mn).get(f.key))]
        steady = [v for v, ok in vals if ok] or [v for v, _ok in vals]
        if not steady:
            figures[f.key] = None
        elif f.combine == "max":
            figures[f.key] = max(steady)
        else:
            figures[f.key] = math.fsum(steady) / len(steady)
    faults = sum(max(int(sh.get("faults") or 0), int(mn.get("faults") or 0)) for _s, sh, mn in runs)
    tracking = [f"{scen or strategy}: {r}" for scen, _sh, mn in runs for r in mn.get("tracking_reasons", [])]
    failed = any(mn.get("tracking") == "failed" for _s, _sh, mn in runs)
    anomalies = [f"{scen or strategy}: {a}" for scen, _sh, mn in runs for a in mn.get("anomalies", [])]
    reasons: list[str] = []
    if faults:
        reasons.append(f"guard tripped in {faults} periods")
    if failed:
        reasons.append("tracking failed" + (f" ({tracking[0]})" if tracking else ""))
    reasons += anomalies
    return {
        "figures": figures, "faults": faults, "tracking": "failed" if failed else "ok",
        "tracking_reasons": tracking, "anomalies": anomalies,
        "locked_cycle_runs": [scen or strategy for scen, _sh, mn in runs if mn.get("locked_cycle")],
        "admissible": not reasons, "reasons": reasons,
        "scenario_runs": {scen or strategy: {k: v for k, v in sh.items() if _scalar(v)}
                          | {k: v for k, v in mn.items() if _scalar(v) and k not in sh}
                          for scen, sh, mn in runs},
    }


def _scalar(v: Any) -> bool:
    return isinstance(v, (int, float, str, bool)) or v is None


# ---------------------------------------------------------------- front and recommendation
def _vector(point: dict[str, Any], objectives: tuple[Figure, ...]) -> tuple[float, ...] | None:
    vals = [point["figures"].get(f.key) for f in objectives]
    return tuple(float(v) for v in vals) if all(_finite(v) for v in vals) else None


def dominates(a: tuple[float, ...], b: tuple[float, ...]) -> bool:
    """``a`` is no worse than ``b`` in every objective and better in one (all minimised)."""
    return all(x <= y for x, y in zip(a, b)) and any(x < y for x, y in zip(a, b))


def front(points: list[dict[str, Any]], objectives: tuple[Figure, ...]) -> list[int]:
    """Indices (into ``points``) of the non-dominated points with every objective computed, in order."""
    vecs = [_vector(p, objectives) for p in points]
    out = []
    for i, a in enumerate(vecs):
        if a is None:
            continue
        if not any(b is not None and dominates(b, a) for j, b in enumerate(vecs) if j != i):
            out.append(i)
    return out


def ranked(points: list[dict[str, Any]], candidates: list[int],
           objectives: tuple[Figure, ...]) -> list[tuple[int, dict[str, float]]]:
    """The candidates (each with every objective computed) by their distance to the ideal point, each
    objective scaled to [0, 1] over the candidates (0 the best value among them, 1 the worst); ties keep
    the candidates' order.  With each: its scaled objectives and ``distance``."""
    vecs = [(i, v) for i in candidates if (v := _vector(points[i], objectives)) is not None]
    if not vecs:
        return []
    los = [min(v[k] for _i, v in vecs) for k in range(len(objectives))]
    his = [max(v[k] for _i, v in vecs) for k in range(len(objectives))]
    out = []
    for i, v in vecs:
        z = [(x - lo) / (hi - lo) if hi > lo else 0.0 for x, lo, hi in zip(v, los, his)]
        out.append((i, {f.key: zk for f, zk in zip(objectives, z)} | {"distance": math.sqrt(math.fsum(x * x for x in z))}))
    return sorted(out, key=lambda e: e[1]["distance"])  # stable: ties keep the candidates' order


def recommend(points: list[dict[str, Any]], candidates: list[int],
              objectives: tuple[Figure, ...]) -> tuple[int | None, dict[str, float]]:
    """The candidate nearest to the ideal point (:func:`ranked`; ties: the first) and its scaled objectives
    and distance; None when there is no candidate."""
    order = ranked(points, candidates, objectives)
    return order[0] if order else (None, {})


# ---------------------------------------------------------------- the search
@dataclass
class Search:
    """The lattice search of every strategy: points evaluated so far, round by round."""

    config: str
    base: dict[str, object]
    strategies: list[str]
    axes: list[TuneAxis]
    objectives: tuple[Figure, ...]
    grid: int
    rounds: int
    focus: int = DEFAULT_FOCUS
    #: per strategy: the evaluated points in evaluation order (each with ``lattice``, ``params``, ``round``)
    points: dict[str, list[dict[str, Any]]] = field(default_factory=dict)
    #: per strategy: lattice index -> position in ``points`` (several indices may round to one value)
    seen: dict[str, dict[tuple[int, ...], int]] = field(default_factory=dict)
    models: dict[tuple[float, ...], Model] = field(default_factory=dict)

    @property
    def top(self) -> int:
        """The lattice's last index: (grid - 1) * 2^rounds."""
        return (self.grid - 1) * 2 ** self.rounds

    def step(self, r: int) -> int:
        """Lattice spacing of round ``r``."""
        return self.top // ((self.grid - 1) * 2 ** r)

    def values(self, idx: tuple[int, ...]) -> tuple[float, ...]:
        return tuple(a.value(i, self.top) for a, i in zip(self.axes, idx))

    def model(self, vals: tuple[float, ...]) -> Model:
        """The checked config of one point (loaded once, shared by the strategies)."""
        if vals not in self.models:
            params = {a.field: v for a, v in zip(self.axes, vals)}
            try:
                self.models[vals] = load_config(self.config, {**self.base, **params})
            except ConfigError as exc:
                where = ", ".join(f"{k}={v!r}" for k, v in params.items())
                raise ConfigError(exc.file, exc.field, exc.value, f"{exc.allowed} (tune point {where})") from None
        return self.models[vals]

    def grid_indices(self) -> list[tuple[int, ...]]:
        import itertools

        s = self.step(0)
        return list(itertools.product(*([i * s for i in range(self.grid)] for _ in self.axes)))

    def fronts(self, strategy: str) -> tuple[list[int], list[int]]:
        """(front of all points, front of the admissible points), indices into ``points[strategy]``."""
        pts = self.points.get(strategy, [])
        adm = [i for i, p in enumerate(pts) if p["admissible"]]
        sub = front([pts[i] for i in adm], self.objectives)
        return front(pts, self.objectives), [adm[i] for i in sub]

    def refine(self, strategy: str, r: int) -> list[tuple[int, ...]]:
        """Round ``r``'s new lattice indices of ``strategy``: the neighbours at +- step(r) along each field of
        the ``focus`` admissible-front points nearest the ideal point (all of them for focus 0; the whole
        front when none is admissible), not evaluated yet, in index order."""
        whole, adm = self.fronts(strategy)
        if adm and self.focus:
            base = [i for i, _z in ranked(self.points[strategy], adm, self.objectives)[: self.focus]]
        else:
            base = adm or whole
        s = self.step(r)
        seen = self.seen.get(strategy, {})
        new: set[tuple[int, ...]] = set()
        for i in base:
            idx = tuple(self.points[strategy][i]["lattice"])
            for k in range(len(self.axes)):
                for d in (-s, s):
                    j = idx[k] + d
                    if 0 <= j <= self.top:
                        cand = idx[:k] + (j,) + idx[k + 1:]
                        if cand not in seen:
                            new.add(cand)
        return sorted(new)


def _plan(search: Search, work: list[tuple[str, tuple[int, ...]]]) -> Any:
    """A sweep plan of ``work`` (strategy, lattice index): one run per point and strategy."""
    from codegen.stages.sweep import Plan

    plan = Plan(search.config, dict(search.base), list(search.strategies), [], [], 0, 0)
    for n, (s, idx) in enumerate(work):
        vals = search.values(idx)
        plan.runs.append({"index": n, "grid_point": None, "draw": None, "strategies": [s],
                          "params": {a.field: v for a, v in zip(search.axes, vals)}})
        plan.models.append(search.model(vals))
    return plan


def _work(search: Search, todo: dict[str, list[tuple[int, ...]]]) -> list[tuple[str, tuple[int, ...]]]:
    """The runs of a round: per strategy its new indices whose value was not evaluated already (two indices
    can round to one value), in strategy and index order."""
    work: list[tuple[str, tuple[int, ...]]] = []
    for s in search.strategies:
        by_value = {tuple(p["params"].values()): n for n, p in enumerate(search.points.get(s, []))}
        seen = search.seen.setdefault(s, {})
        planned: dict[tuple[float, ...], tuple[int, ...]] = {}
        for idx in todo.get(s, []):
            vals = search.values(idx)
            if vals in by_value:
                seen[idx] = by_value[vals]
            elif vals not in planned:
                planned[vals] = idx
                work.append((s, idx))
    return work


def _merge(search: Search, work: list[tuple[str, tuple[int, ...]]], outs: list[dict[str, Any]],
           r: int) -> None:
    for (s, idx), out in zip(work, outs):
        vals = search.values(idx)
        pts = search.points.setdefault(s, [])
        point = {"strategy": s, "round": r, "lattice": list(idx),
                 "params": {a.field: v for a, v in zip(search.axes, vals)},
                 "config_hash": search.model(vals).with_controller(strategy=s).config_hash(),
                 **evaluate(out["result"], s), "warnings": list(out["warnings"])}
        search.seen.setdefault(s, {})[idx] = len(pts)
        pts.append(point)


def run_search(search: Search, session: Any, log: Log) -> list[dict[str, Any]]:
    """Round 0 and the refinement rounds on ``session``; returns each round's timing."""
    from codegen.stages import sweep_runner

    timing = []
    todo = {s: search.grid_indices() for s in search.strategies}
    for r in range(search.rounds + 1):
        work = _work(search, todo)
        if not work:
            log(f"tune round {r}: nothing new to evaluate (every neighbour of the fronts is evaluated)")
            break
        plan = _plan(search, work)
        log(f"tune round {r}: {len(work)} runs ("
            + ", ".join(f"{s} {sum(1 for w in work if w[0] == s)}" for s in search.strategies)
            + (f"), lattice step {search.step(r)}/{search.top}" if r else f"), grid of {search.grid} per field"))
        t0 = time.perf_counter()
        outs = session.run(plan, label=f"tune round {r}")
        wall = time.perf_counter() - t0
        _merge(search, work, outs, r)
        timing.append({"round": r, **sweep_runner.timing_of(session.runner, outs, wall)})
        for s in search.strategies:
            whole, adm = search.fronts(s)
            best, _ = recommend(search.points[s], adm, search.objectives)
            pick = "none admissible" if best is None else ", ".join(
                f"{k.rpartition('.')[2]}={v:.6g}" for k, v in search.points[s][best]["params"].items())
            log(f"tune round {r}: {s}: {len(search.points[s])} points, front {len(whole)}, admissible front "
                f"{len(adm)}, recommended {pick}")
        if r < search.rounds:
            todo = {s: search.refine(s, r + 1) for s in search.strategies}
    return timing


# ---------------------------------------------------------------- command
def default_grid(n_axes: int) -> int:
    return DEFAULT_GRID[min(n_axes, len(DEFAULT_GRID)) - 1]


def check_args(args: argparse.Namespace, model: Model) -> tuple[list[TuneAxis], tuple[Figure, ...], int, int, int]:
    """The tuned fields, objectives, grid, rounds and focus of the command line (UsageError before any run)."""
    axes = [parse_axis("--weight", t, model) for t in args.weight]
    axes += [parse_axis("--threshold", t, model) for t in args.threshold]
    if not axes:
        raise UsageError("nothing to tune: give --weight SECTION.FIELD[=LO:HI] (log scale) and/or "
                         "--threshold SECTION.FIELD[=LO:HI] (linear scale), e.g. --weight controller.lambda_psi_nm_per_wb")
    seen: set[str] = set()
    for a in axes:
        if a.field in seen:
            raise UsageError(f"{a.field} is tuned twice (--weight/--threshold); give each field once")
        seen.add(a.field)
    objectives = parse_objectives(args.objectives, [a.field for a in axes])
    grid = default_grid(len(axes)) if args.grid is None else args.grid
    if not 2 <= grid <= 50:
        raise UsageError(f"--grid = {grid}: must be an integer in [2, 50] (values per field in round 0)")
    if not 0 <= args.rounds <= MAX_ROUNDS:
        raise UsageError(f"--rounds = {args.rounds}: must be an integer in [0, {MAX_ROUNDS}]")
    if args.focus < 0:
        raise UsageError(f"--focus = {args.focus}: must be an integer >= 0 (0: refine the whole admissible front)")
    return axes, objectives, grid, args.rounds, args.focus


def command(args: argparse.Namespace, model: Model, log: Log, strategies: list[str], out_dir: Path | None) -> int:
    """``mpcgen tune``: check everything, search on the runner, write the table, JSON, CSV and front plots."""
    from codegen.stages import sweep, tune_output
    from codegen.stages.sweep_runner import Session

    runner = sweep.runner_of(args)
    axes, objectives, grid, rounds, focus = check_args(args, model)
    search = Search(args.config, sweep.base_overrides(args), strategies, axes, objectives, grid, rounds, focus)
    first = len(search.grid_indices()) * len(strategies)
    if first > MAX_EVALUATIONS:
        raise UsageError(f"round 0 plans {first} runs ({grid} values per field, {len(axes)} fields, "
                         f"{len(strategies)} strategies), at most {MAX_EVALUATIONS}: lower --grid")
    t0 = time.perf_counter()
    for idx in search.grid_indices():  # every round-0 config checked before anything runs
        search.model(search.values(idx))
    log(f"tune {model.name}: {', '.join(a.describe() for a in axes)}; objectives "
        f"{', '.join(f.key for f in objectives)}; {len(strategies)} strategies; round 0 configs checked in "
        f"{time.perf_counter() - t0:.2f} s; on {runner.describe()}")
    t0 = time.perf_counter()
    with Session(runner, log) as session:
        rounds_timing = run_search(search, session, log)
    wall = time.perf_counter() - t0
    n = sum(len(p) for p in search.points.values())
    log(f"tune: {n} runs in {wall:.1f} s on {runner.describe()}")
    data = tune_output.assemble(search, model, {"runner": runner.kind, "address": runner.address,
                                                "workers": runner.workers if runner.kind != "scheduler" else None,
                                                "wall_s": wall, "rounds": rounds_timing}, log)
    emit(tune_output.markdown(data), out_dir, tune_output.write_all, data)
    if out_dir is not None:
        print(tune_output.summary(data), end="")
    if any(s["recommended"] is None for s in data["strategies"].values()):
        raise MpcgenError("no admissible point for " + ", ".join(
            s for s, d in data["strategies"].items() if d["recommended"] is None)
            + ": every evaluated value misbehaves (see the table's reasons); widen the range or check the config")
    return 0
