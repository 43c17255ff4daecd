"""``mpcgen study``: the horizon study of a long-horizon config at a matched switching frequency.

For each horizon N of ``--horizons``, the switching weight ``controller.lambda_u`` is searched until the
closed loop's average switching frequency ``f_ave_hz`` (the figure of ``mpcgen tune``,
:func:`codegen.stages.tune.evaluate`) is within ``--tolerance`` percent of a target: ``--fsw-khz``, or
by default the f_ave of N = 1 at the config's lambda_u.  Then, per N, the current THD and the torque
ripple of that run, the nodes the sphere decoder entered per step (mean, maximum) and how often its node
budget stopped the search (the step's ``n_nodes`` and ``budget_hit`` outputs, the compiled step run over
the controller inputs of the topology's closed-loop states), the C hash of the N's generated C, and the
estimated Cortex-M7 cycles of a ``mpcgen bench --emulated --json`` file naming the same config hash
(``--bench``), else "not measured".  docs/mpcc-study.md is the user's manual.

Search (per N, on ln lambda_u against ln f_ave, the closed loop run once per value; :data:`RULES`):
round 0 runs every N at the config's lambda_u; each later round runs one new value per N not matched yet
(the N in parallel on the sweep stage's runner): with no sign change of f_ave - target yet, a secant step
through the two values nearest the target (the first step half a decade, every step 0.1 .. 1.5 decades,
towards the target); once bracketed, false position inside the bracket, or its midpoint when the last
two values fell on the same side.  A value within the tolerance ends the N; ``--max-runs`` values, a
bracket narrower than 0.1 %, or a range end already tried end it unmatched (the value nearest the target
is then reported, and the command exits 1 after writing its outputs).  Values are rounded to 6
significant digits; the results do not depend on the runner.
"""
from __future__ import annotations

import argparse
import json
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from codegen.config import family_of, load_config, schema_for
from codegen.errors import ConfigError, MpcgenError, UsageError
from codegen.model import Model
from codegen.results import emit

__all__ = ["HORIZON", "WEIGHT", "RULES", "Match", "check_family", "parse_horizons", "read_bench", "node_statistics",
           "attach_cycles", "command"]

Log = Callable[[str], None]

#: the config fields the study sets per N (read by the long-horizon family only)
HORIZON, WEIGHT = "controller.horizon", "controller.lambda_u"
#: default horizons, tolerance (percent) and runs per N
DEFAULT_HORIZONS, DEFAULT_TOLERANCE, DEFAULT_MAX_RUNS = "1-5", 3.0, 16
#: decades: the first step, the smallest and largest steps before a bracket, the searched span either side
FIRST_STEP, MIN_STEP, MAX_STEP, SPAN = 0.5, 0.1, 1.5, 6.0
#: a bracket narrower than this (ln lambda_u) ends the search: f_ave jumps there
MIN_BRACKET = math.log(1.001)
DIGITS = 6

RULES = {
    "target": "--fsw-khz, else f_ave of N = 1 at the config's controller.lambda_u (f_ave as tune reports it: the "
              "mean over the scenario runs whose f_ave window is steady)",
    "figures": "f_ave_hz, THD_ia_percent (integer harmonics), THD_ia_all_bins_percent and T_rip_RMSE_nm as tune "
               "combines a point's scenario runs: the mean over the runs whose window for that figure is steady "
               "(all runs when none is); the windows are listed",
    "search": "per N on ln lambda_u against ln f_ave: round 0 the config's lambda_u; no sign change of f_ave - "
              "target yet: a secant step through the two values nearest the target (the first 0.5 decade; each "
              "0.1..1.5 decades, towards the target); bracketed: false position, or the bracket's midpoint when "
              "the last two values fell on the same side; values rounded to 6 significant digits, within the "
              "config's lambda_u / 10^6 .. x 10^6 and the field's allowed range",
    "matched": "|f_ave / target - 1| <= the tolerance; unmatched after --max-runs values, a bracket narrower than "
               "0.1 % (f_ave jumps across the target) or a range end already tried: the value nearest the target "
               "is reported and the command exits 1",
    "nodes": "the step's n_nodes and budget_hit over the controller inputs of the topology's closed-loop states "
             "(those verify compares), periods whose input guard tripped left out; budget binds: % of those periods",
    "cycles": "m7_cycles_est_median / _max of a mpcgen bench --emulated --json file (--bench) whose config_hash is "
              "the N's config hash; otherwise not measured",
}


# ---------------------------------------------------------------- checks
def check_family(model: Model) -> None:
    """The config's strategy reads ``controller.horizon`` and ``controller.lambda_u`` (one line otherwise)."""
    topo, strategy = model.inverter.topology, model.controller.strategy
    schema = schema_for(topo)
    family = family_of(topo, strategy)
    for name in (HORIZON, WEIGHT):
        spec = schema.get(name)
        if spec is None or (spec.families and family not in spec.families):
            raise UsageError(f"controller.strategy = '{strategy}' has no {name}: the study compares the horizons "
                             f"of a long-horizon strategy at a matched switching frequency (docs/mpcc-study.md); "
                             f"give a config whose strategy reads {HORIZON} and {WEIGHT}")


def parse_horizons(text: str, model: Model) -> list[int]:
    """``--horizons``: ``A-B``, a comma list or one number, each within ``controller.horizon``'s range."""
    from codegen.stages.tune import allowed_range

    lo, hi = (int(v) for v in allowed_range(model, HORIZON))
    form = f"expected A-B, a comma list or one horizon, each an integer in [{lo}, {hi}] (e.g. 1-5 or 1,3,5)"
    try:
        if "-" in text:
            a, b = (int(v) for v in text.split("-"))
            if b < a:
                raise ValueError
            out = list(range(a, b + 1))
        else:
            out = sorted({int(v) for v in text.split(",")})
    except ValueError:
        raise UsageError(f"--horizons = {text!r}: {form}") from None
    bad = [n for n in out if not lo <= n <= hi]
    if bad or not out:
        raise UsageError(f"--horizons = {text!r}: {bad[0] if bad else 'none'} is outside [{lo}, {hi}] "
                         f"({HORIZON}); {form}")
    return out


def read_bench(paths: list[str]) -> list[dict[str, Any]]:
    """The ``--bench`` files: each a ``mpcgen bench --json`` output with ``config_hash`` and ``strategies``."""
    out = []
    for p in paths:
        try:
            data = json.loads(Path(p).read_text())
        except OSError as exc:
            raise UsageError(f"--bench = {p}: cannot read it ({exc.strerror or exc})") from None
        except ValueError as exc:
            raise UsageError(f"--bench = {p}: not JSON ({exc})") from None
        if not (isinstance(data, dict) and isinstance(data.get("config_hash"), str)
                and isinstance(data.get("strategies"), dict)):
            raise UsageError(f"--bench = {p}: not the JSON of mpcgen bench --json (no config_hash and strategies)")
        out.append({"file": str(p), "config_hash": data["config_hash"], "strategies": data["strategies"]})
    return out


# ---------------------------------------------------------------- the search of one N
def _round(v: float) -> float:
    return float(f"{v:.{DIGITS}g}")


@dataclass
class Match:
    """The lambda_u search of one horizon: every value run so far (``points``: lambda_u, f_ave_hz, round and the
    point's figures) and, once it ended, ``status`` ("matched" or why not)."""

    horizon: int
    lo: float  # ln lambda_u limits
    hi: float
    points: list[dict[str, Any]] = field(default_factory=list)
    status: str = ""

    def error(self, p: dict[str, Any], target: float) -> float:
        """ln(f_ave / target); -inf when f_ave is 0 or not computed (no switching: lambda_u too large)."""
        f = p["f_ave_hz"]
        return math.log(f / target) if f else -math.inf

    def best(self, target: float) -> dict[str, Any]:
        """The point nearest the target (the first of equals)."""
        return min(self.points, key=lambda p: abs(self.error(p, target)))

    def update(self, target: float, tol: float, max_runs: int) -> float | None:
        """After a round: the next lambda_u to run, or None when the search ended (``status`` set)."""
        f = self.points[-1]["f_ave_hz"]
        if f and abs(f / target - 1.0) <= tol:
            self.status = "matched"
            return None
        if len(self.points) >= max_runs:
            self.status = f"not matched within {max_runs} runs"
            return None
        x = self._next(target)
        if isinstance(x, str):
            self.status = x
            return None
        lam = _round(math.exp(min(max(x, self.lo), self.hi)))
        if any(p["lambda_u"] == lam for p in self.points):
            self.status = (f"not matched: the next value {lam:g} was run already (f_ave does not reach the target "
                           f"within lambda_u {math.exp(self.lo):.3g} .. {math.exp(self.hi):.3g})")
            return None
        return lam

    def _next(self, target: float) -> float | str:
        pts = sorted(self.points, key=lambda p: p["lambda_u"])
        xs = [math.log(p["lambda_u"]) for p in pts]
        ys = [self.error(p, target) for p in pts]
        brackets = [i for i in range(len(pts) - 1) if (ys[i] > 0) != (ys[i + 1] > 0)]
        if brackets:
            near = pts.index(self.best(target))
            i = next((b for b in brackets if near in (b, b + 1)), brackets[0])
            (xa, xb), (ya, yb) = xs[i:i + 2], ys[i:i + 2]
            if xb - xa < MIN_BRACKET:
                return (f"not matched: f_ave jumps from {pts[i]['f_ave_hz']:.0f} to {pts[i + 1]['f_ave_hz']:.0f} Hz "
                        f"between lambda_u = {pts[i]['lambda_u']:g} and {pts[i + 1]['lambda_u']:g}")
            same_side = len(self.points) >= 2 and \
                (self.error(self.points[-1], target) > 0) == (self.error(self.points[-2], target) > 0)
            if same_side or not (math.isfinite(ya) and math.isfinite(yb)):
                return 0.5 * (xa + xb)
            u = min(max(ya / (ya - yb), 0.05), 0.95)
            return xa + u * (xb - xa)
        up = ys[0] > 0  # f_ave above the target everywhere: a larger weight switches less
        edge = xs[-1] if up else xs[0]
        finite = sorted((abs(y), x, y) for x, y in zip(xs, ys) if math.isfinite(y))
        step = FIRST_STEP * math.log(10)
        if len(finite) >= 2 and finite[0][1] != finite[1][1]:
            (_a, x0, y0), (_b, x1, y1) = finite[:2]
            slope = (y1 - y0) / (x1 - x0)
            step = -y0 / slope if slope < 0 else MAX_STEP * math.log(10)
            step = min(max(abs(step), MIN_STEP * math.log(10)), MAX_STEP * math.log(10))
        return edge + (step if up else -step)


# ---------------------------------------------------------------- node statistics and cycles
def node_statistics(model: Model) -> dict[str, Any]:
    """Nodes the step entered per period (mean, max) and the share of periods its budget stopped the search,
    over the controller inputs of the topology's closed-loop states, run through the compiled step; periods
    whose input guard tripped (no search) are left out and counted."""
    from codegen.topology import topology_of

    topo = topology_of(model)
    tables = topo.derive(model)
    lib = topo.host_library(model, tables, with_sim=True)
    out = lib.step_batch(topo.closed_loop_states(model, lib))
    names = out.dtype.names or ()
    if "n_nodes" not in names or "budget_hit" not in names:
        raise MpcgenError(f"{model.name}: the step's output has no n_nodes/budget_hit: not a sphere-decoder step")
    ok = out["fault"] == 0
    nodes = out["n_nodes"][ok].astype(np.int64)
    hit = out["budget_hit"][ok] != 0
    n = int(ok.sum())
    return {"periods": int(len(out)), "searched_periods": n, "guard_tripped_periods": int(len(out) - n),
            "mean": float(nodes.mean()) if n else None, "max": int(nodes.max()) if n else None,
            "budget_hit_percent": 100.0 * float(hit.mean()) if n else None,
            "node_budget": getattr(tables, "node_budget", None)}


def attach_cycles(rows: list[dict[str, Any]], bench: list[dict[str, Any]], strategy: str) -> list[str]:
    """Fill each row's ``cycles`` from the bench file naming its config hash (else "not measured"); returns
    the files that name no row's config hash."""
    used: set[str] = set()
    for r in rows:
        r["cycles"], r["cycles_note"] = None, "not measured"
        for b in bench:
            if b["config_hash"] != r["config_hash"]:
                continue
            used.add(b["file"])
            e = b["strategies"].get(strategy, {})
            med, mx = e.get("m7_cycles_est_median"), e.get("m7_cycles_est_max")
            if isinstance(med, (int, float)) and isinstance(mx, (int, float)):
                r["cycles"] = {"median": med, "max": mx, "file": b["file"]}
                r["cycles_note"] = f"M7 est. cycles from {b['file']}"
            else:
                r["cycles_note"] = f"not measured ({b['file']} names this config but has no M7 cycle estimate " \
                                   f"of {strategy}: mpcgen bench --emulated)"
    return [b["file"] for b in bench if b["file"] not in used]


# ---------------------------------------------------------------- the command
def _limits(model: Model) -> tuple[float, float]:
    """ln lambda_u limits: the config's value / 10^SPAN .. x 10^SPAN within the field's allowed range."""
    from codegen.stages.tune import allowed_range

    lam = float(model.controller.lambda_u)
    a_lo, a_hi = allowed_range(model, WEIGHT)
    lo, hi = max(lam / 10 ** SPAN, a_lo), min(lam * 10 ** SPAN, a_hi)  # lambda_u > 0: a_lo is an open end
    return math.log(lo), math.log(hi)


class _Study:
    """The configs of every run (loaded and checked once each)."""

    def __init__(self, config: str, base: dict[str, object]) -> None:
        self.config, self.base = config, base
        self.models: dict[tuple[int, float], Model] = {}

    def model(self, n: int, lam: float) -> Model:
        if (n, lam) not in self.models:
            try:
                self.models[(n, lam)] = load_config(self.config, {**self.base, HORIZON: n, WEIGHT: lam})
            except ConfigError as exc:
                raise ConfigError(exc.file, exc.field, exc.value, f"{exc.allowed} (study point N = {n}, "
                                  f"lambda_u = {lam:g})") from None
        return self.models[(n, lam)]

    def plan(self, strategy: str, work: list[tuple[int, float]]) -> Any:
        from codegen.stages.sweep import Plan

        plan = Plan(self.config, dict(self.base), [strategy], [], [], 0, 0)
        for i, (n, lam) in enumerate(work):
            plan.runs.append({"index": i, "grid_point": None, "draw": None, "strategies": [strategy],
                              "params": {HORIZON: n, WEIGHT: lam}})
            plan.models.append(self.model(n, lam))
        return plan


def _point(n: int, lam: float, r: int, out: dict[str, Any], strategy: str) -> dict[str, Any]:
    from codegen.stages.tune import evaluate, runs_of

    ev = evaluate(out["result"], strategy)
    windows = [{"run": scen or strategy, "window": sh.get("window", {}).get("THD_ia_percent", {}).get("description"),
                "steady": "THD_ia_percent" not in sh.get("not_steady", {})}
               for scen, sh, _mn in runs_of(out["result"], strategy)]
    return {"horizon": n, "lambda_u": lam, "round": r, "f_ave_hz": ev["figures"].get("f_ave_hz") or 0.0,
            **ev, "thd_windows": windows, "warnings": list(out["warnings"])}


def run_search(study: _Study, strategy: str, horizons: list[int], target_hz: float | None, tol: float,
               max_runs: int, limits: tuple[float, float], lam0: float, session: Any,
               log: Log) -> tuple[dict[int, Match], float, list[dict[str, Any]]]:
    """Every N's search on ``session``; returns the searches, the target (Hz) and each round's timing."""
    from codegen.stages import sweep_runner

    matches = {n: Match(n, *limits) for n in horizons}
    work = [(n, lam0) for n in sorted(set(horizons) | ({1} if target_hz is None else set()))]
    timing, r, target = [], 0, target_hz
    while work:
        log(f"study round {r}: {len(work)} runs (" + ", ".join(f"N={n} lambda_u={lam:g}" for n, lam in work) + ")")
        t0 = time.perf_counter()
        outs = session.run(study.plan(strategy, work), label=f"study round {r}")
        timing.append({"round": r, **sweep_runner.timing_of(session.runner, outs, time.perf_counter() - t0)})
        points = [_point(n, lam, r, o, strategy) for (n, lam), o in zip(work, outs)]
        if target is None:
            ref = next(p for p in points if p["horizon"] == 1)
            if not ref["f_ave_hz"]:
                raise MpcgenError(f"N = 1 at lambda_u = {lam0:g} does not switch (f_ave not computed or 0): no "
                                  "target switching frequency; give --fsw-khz")
            target = float(ref["f_ave_hz"])
            log(f"study: target f_ave {target:.1f} Hz (N = 1 at lambda_u = {lam0:g}), tolerance {100 * tol:g} %")
        work = []
        for p in points:
            m = matches.get(p["horizon"])
            if m is None:
                continue
            m.points.append(p)
            nxt = m.update(target, tol, max_runs)
            b = m.best(target)
            log(f"study round {r}: N={m.horizon}: lambda_u {p['lambda_u']:g} -> f_ave {p['f_ave_hz']:.1f} Hz "
                f"({100 * (p['f_ave_hz'] / target - 1):+.2f} %); " + (f"next {nxt:g}" if nxt is not None else
                f"{m.status} (lambda_u {b['lambda_u']:g}, {100 * (b['f_ave_hz'] / target - 1):+.2f} %)"))
            if nxt is not None:
                work.append((m.horizon, nxt))
        r += 1
    assert target is not None
    return matches, target, timing


def command(args: argparse.Namespace, model: Model, log: Log, out_dir: Path | None) -> int:
    """``mpcgen study``: check everything, search every N's lambda_u, measure, write study.md/.json/.png."""
    from codegen.stages import study_output, sweep
    from codegen.stages.sweep_runner import Session

    check_family(model)
    horizons = parse_horizons(args.horizons, model)
    if args.fsw_khz is not None and not (math.isfinite(args.fsw_khz) and 0 < args.fsw_khz < 0.5e-3 / model.controller.dt_s):
        raise UsageError(f"--fsw-khz = {args.fsw_khz:g}: must be in (0, {0.5e-3 / model.controller.dt_s:g}) kHz "
                         "(above 0, below half the control frequency)")
    if not (math.isfinite(args.tolerance) and 0 < args.tolerance <= 50):
        raise UsageError(f"--tolerance = {args.tolerance:g}: must be a percentage in (0, 50]")
    if not 1 <= args.max_runs <= 100:
        raise UsageError(f"--max-runs = {args.max_runs}: must be an integer in [1, 100]")
    bench = read_bench(args.bench)
    runner = sweep.runner_of(args)
    study = _Study(args.config, sweep.base_overrides(args))
    strategy, lam0 = model.controller.strategy, _round(float(model.controller.lambda_u))
    for n in sorted(set(horizons) | {1}):  # every round-0 config checked before anything runs
        study.model(n, lam0)
    log(f"study {model.name}: horizons {', '.join(map(str, horizons))}, target "
        + (f"{args.fsw_khz:g} kHz" if args.fsw_khz is not None else f"f_ave of N = 1 at lambda_u = {lam0:g}")
        + f", tolerance {args.tolerance:g} %; on {runner.describe()}")
    t0 = time.perf_counter()
    with Session(runner, log) as session:
        matches, target, timing = run_search(
            study, strategy, horizons, None if args.fsw_khz is None else 1e3 * args.fsw_khz,
            args.tolerance / 100, args.max_runs, _limits(model), lam0, session, log)
    wall = time.perf_counter() - t0
    rows = []
    for n in horizons:
        m = matches[n]
        chosen = m.points[-1] if m.status == "matched" else m.best(target)
        variant = study.model(n, chosen["lambda_u"])
        log(f"study N={n}: nodes per step over the closed-loop states")
        rows.append(study_output.row(study, variant, m, chosen, target, node_statistics(variant), strategy))
    unmatched = attach_cycles(rows, bench, strategy)
    for f in unmatched:
        log(f"study: --bench {f} names none of the study's config hashes; not used")
    data = study_output.assemble(args, model, study, rows, target, timing, wall, runner, unmatched)
    emit(study_output.markdown(data), out_dir, study_output.write_all, data)
    missed = [r for r in rows if r["status"] != "matched"]
    if missed:
        raise MpcgenError("f_ave not matched for " + "; ".join(f"N = {r['horizon']}: {r['status']}" for r in missed))
    return 0
