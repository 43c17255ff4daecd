"""``mpcgen sweep``: parameter grids and Monte Carlo mismatch studies of ``simulate``.

A sweep is a *plan*: a list of runs, each a set of config overrides
(``section.field`` -> value) applied on top of the config file and its
``--set`` options.  The plan is built and every run's config is loaded and
checked here (:func:`codegen.config.load_config`, exactly as a file value is
checked), before any cluster is started or any run simulated; bad input is
one line and exit code 2.

* ``--param section.field=LIST_OR_RANGE`` (repeatable): a grid axis, either a
  comma list (``0.2,0.5,1`` -- any TOML value, so ``dq-euler,flux-geometry``
  works for a choice field) or ``START:STOP:STEP`` (STEP > 0, STOP included
  when it lies on the grid).  Several axes span their cartesian product.
* ``--monte-carlo N --spread section.field=+-PCT`` (repeatable): N runs with
  each spread field drawn uniformly in ``nominal * (1 +- PCT/100)``; the
  draws come from ``numpy.random.default_rng(--seed)``, drawn once in the
  client, so a study is reproducible and independent of the runner.  The
  nominal of a ``plant.*`` parameter override that the config leaves unset is
  the controller's own value (``motor.rs_ohm`` for ``plant.rs_ohm``, ...): the
  spread is a mismatch between the plant and the controller's model.  With a
  grid too, every grid point gets the same N draws.

The runs go to :mod:`codegen.stages.sweep_runner` (Dask or serial) and the
results to :mod:`codegen.stages.sweep_output` (JSON, CSV, plot, table).
"""
from __future__ import annotations

import argparse
import difflib
import itertools
import math
import sys
import time
import tomllib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from codegen.config import INT, REAL, all_fields, load_config, owners, parse_override
from codegen.errors import ConfigError, Marker, UsageError
from codegen.model import PLANT_DEFAULTS, Model

__all__ = ["Axis", "Spread", "Plan", "parse_param", "parse_spread", "build_plan", "command", "known_field",
           "field_value", "base_overrides", "runner_of",
           "MAX_AXIS_VALUES", "MAX_RUNS"]

Log = Callable[[str], None]

#: most values one --param axis may expand to
MAX_AXIS_VALUES = 1000
#: most runs one sweep may plan (grid points times Monte Carlo draws)
MAX_RUNS = 100_000
#: command-line shortcuts of the config arguments (as ``mpcgen`` applies them) -> field
_SHORTCUTS = (("strategy", "controller.strategy"), ("predictor", "controller.predictor"),
              ("tables", "controller.tables"), ("number_format", "controller.number_format"),
              ("delay", "controller.delay_compensation"), ("target", "target.name"))


@dataclass(frozen=True)
class Axis:
    """One grid axis: a config field and its values."""

    field: str
    values: tuple[object, ...]


@dataclass(frozen=True)
class Spread:
    """One Monte Carlo field: uniform in ``nominal * (1 +- percent/100)``."""

    field: str
    percent: float
    nominal: float = math.nan


@dataclass
class Plan:
    """Every run of a sweep: its overrides (on top of ``base``) and where it sits in the study."""

    config: str
    base: dict[str, object]
    strategies: list[str]
    axes: list[Axis]
    spreads: list[Spread]
    monte_carlo: int
    seed: int
    #: per run: {"index", "grid_point", "draw", "params"}
    runs: list[dict[str, object]] = field(default_factory=list)
    #: per run: the checked model (the config with base and params applied)
    models: list[Model] = field(default_factory=list)

    @property
    def kind(self) -> str:
        if self.axes and self.monte_carlo:
            return "grid+monte-carlo"
        return "monte-carlo" if self.monte_carlo else "grid"


# ---------------------------------------------------------------- parsing
def known_field(option: str, name: str, text: str) -> str:
    """``name`` if it is a config field, else one line naming the option and close matches."""
    if name in all_fields():
        return name
    guess = difflib.get_close_matches(name, list(all_fields()), n=1)
    maybe = f" (did you mean '{guess[0]}'?)" if guess else ""
    raise UsageError(f"{option} {text!r}: '{name}' is not a config field{maybe}; "
                     f"fields are section.field as in the config file, e.g. controller.eps_t_nm")


def _split(option: str, text: str, form: str) -> tuple[str, str]:
    name, sep, value = text.partition("=")
    name, value = name.strip(), value.strip()
    if not sep or not name or not value:
        raise UsageError(f"{option} {text!r}: expected {form}")
    return known_field(option, name, text), value


def _number_text(v: float) -> float:
    """A range point written with 12 significant digits (0.1 + 2*0.1 -> 0.3, 3e-7 stays 3e-7)."""
    return float(f"{v:.12g}")


def _range(option: str, text: str, name: str, value: str) -> list[object]:
    form = "START:STOP:STEP with finite numbers, STEP > 0 and STOP >= START (e.g. 0.1:1.5:0.1)"
    try:
        a, b, c = (float(v) for v in value.split(":"))
    except ValueError:
        raise UsageError(f"{option} {text!r}: expected {form}") from None
    if not all(math.isfinite(v) for v in (a, b, c)) or c <= 0:
        raise UsageError(f"{option} {text!r}: expected {form}")
    if b < a:
        raise UsageError(f"{option} {text!r}: empty range (STOP {b:g} < START {a:g})")
    n = int(math.floor((b - a) / c + 1e-9)) + 1
    if n > MAX_AXIS_VALUES:
        raise UsageError(f"{option} {text!r}: {n} values, at most {MAX_AXIS_VALUES} per axis")
    vals: list[object] = [_number_text(a + i * c) for i in range(n)]
    if all_fields()[name].kind == INT:
        if not all(float(v).is_integer() for v in vals):  # type: ignore[arg-type]
            raise UsageError(f"{option} {text!r}: {name} is an integer field; give integer START, STEP")
        vals = [int(v) for v in vals]  # type: ignore[call-overload]
    elif all_fields()[name].kind != REAL:
        raise UsageError(f"{option} {text!r}: {name} is not a number; give a comma list of its values")
    return vals


def parse_param(text: str, option: str = "--param") -> Axis:
    """``section.field=a,b,c`` or ``section.field=START:STOP:STEP`` as a grid axis."""
    name, value = _split(option, text, "SECTION.FIELD=LIST_OR_RANGE, e.g. controller.eps_t_nm=0.1:1.5:0.1 "
                                       "or controller.eps_t_nm=0.2,0.5,1")
    if value.startswith("["):  # a TOML array of values (for values that contain commas themselves)
        try:
            doc = tomllib.loads(f"v = {value}")["v"]
        except tomllib.TOMLDecodeError:
            raise UsageError(f"{option} {text!r}: expected a TOML array of values, e.g. [[[0.0, 5.0]], [[0.0, 10.0]]]") from None
        if not isinstance(doc, list) or not doc:
            raise UsageError(f"{option} {text!r}: the array names no value")
        vals = list(doc)
    elif ":" in value and not value.startswith(('"', "'")):
        vals = _range(option, text, name, value)
    else:
        items = [v.strip() for v in value.split(",")]
        if not all(items):
            raise UsageError(f"{option} {text!r}: empty item in the comma list")
        vals = [parse_override(f"{name}={v}")[1] for v in items]
        for v in vals:
            if isinstance(v, float) and not math.isfinite(v):
                raise UsageError(f"{option} {text!r}: {v} is not a finite number")
    if len(vals) > MAX_AXIS_VALUES:
        raise UsageError(f"{option} {text!r}: {len(vals)} values, at most {MAX_AXIS_VALUES} per axis")
    if len(set(map(repr, vals))) != len(vals):
        raise UsageError(f"{option} {text!r}: a value is repeated")
    return Axis(name, tuple(vals))


def parse_spread(text: str, option: str = "--spread") -> Spread:
    """``section.field=+-PCT`` (also ``±PCT``), 0 < PCT < 100, on a real-valued field."""
    form = "SECTION.FIELD=+-PCT with 0 < PCT < 100, e.g. plant.rs_ohm=+-20"
    name, value = _split(option, text, form)
    body = value[2:] if value.startswith("+-") else value[1:] if value.startswith("±") else None
    try:
        pct = float(body.rstrip("%")) if body is not None else math.nan
    except ValueError:
        pct = math.nan
    if not (0.0 < pct < 100.0):
        raise UsageError(f"{option} {text!r}: expected {form}")
    if all_fields()[name].kind != REAL:
        raise UsageError(f"{option} {text!r}: {name} is not a real-valued field; only those can be spread")
    return Spread(name, pct)


def field_value(model: Model, name: str) -> object:
    """The value of config field ``name`` (``section.field``) in ``model``."""
    section, _, key = name.rpartition(".")
    if section in ("meta", "target"):
        return getattr(model, "target" if name == "target.name" else key)
    node: object = model
    for part in section.split("."):
        node = getattr(node, part)
    return getattr(node, key)


def nominal(model: Model, name: str) -> float:
    """The value a spread is centred on (an unset plant override: the controller's value)."""
    v = field_value(model, name)
    section, _, attr = name.partition(".")
    if v is None and section == "plant" and attr in PLANT_DEFAULTS:
        v = model.plant.value(attr, model)
    if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
        raise UsageError(f"--spread {name}: the config gives it no numeric value to spread around; "
                         f"set one with --set {name}=VALUE")
    if v == 0:
        raise UsageError(f"--spread {name}: its value is 0, a percentage spread of it is 0")
    return float(v)


def base_overrides(args: argparse.Namespace) -> dict[str, object]:
    """The ``--set`` and shortcut overrides of the command line, as ``mpcgen`` applies them to the config."""
    out: dict[str, object] = {}
    for text in getattr(args, "sets", []) or []:
        k, v = parse_override(text)
        out[k] = v
    for attr, key in _SHORTCUTS:
        v = getattr(args, attr, None)
        if v is not None:
            out[key] = v
    return out


# ---------------------------------------------------------------- the plan
def build_plan(config: str, model: Model, base: dict[str, object], strategies: list[str],
               params: list[str], spreads: list[str], monte_carlo: int, seed: int) -> Plan:
    """Parse the axes and spreads, draw the Monte Carlo values and load every run's config."""
    if monte_carlo < 0 or seed < 0:
        raise UsageError(f"--monte-carlo = {monte_carlo}, --seed = {seed}: must be integers >= 0")
    axes = [parse_param(t) for t in params]
    sp = [parse_spread(t) for t in spreads]
    if sp and not monte_carlo:
        raise UsageError("--spread goes with --monte-carlo N (the number of runs)")
    if not axes and not monte_carlo:
        raise UsageError("nothing to sweep: give --param SECTION.FIELD=LIST_OR_RANGE and/or "
                         "--monte-carlo N with --spread SECTION.FIELD=+-PCT")
    if monte_carlo and not sp:
        raise UsageError(f"--monte-carlo {monte_carlo} needs at least one --spread SECTION.FIELD=+-PCT")
    for option, name in [("--param", a.field) for a in axes] + [("--spread", s.field) for s in sp]:
        theirs = owners(name)
        if model.inverter.topology not in theirs:
            raise ConfigError(config, name, Marker(f"{option} {name}"),
                              f"belongs to inverter.topology = {' or '.join(repr(t) for t in theirs)}; a "
                              f"'{model.inverter.topology}' config has no such field, so sweeping it would change "
                              "nothing")
    seen: set[str] = set()
    for name in [a.field for a in axes] + [s.field for s in sp]:
        if name in seen:
            raise UsageError(f"{name} is swept twice (--param/--spread); give each field once")
        seen.add(name)
    sp = [Spread(s.field, s.percent, nominal(model, s.field)) for s in sp]
    points = list(itertools.product(*(a.values for a in axes))) if axes else [()]
    draws = max(monte_carlo, 1)
    total = len(points) * draws
    if total > MAX_RUNS:
        raise UsageError(f"the sweep plans {total} runs, at most {MAX_RUNS}")
    plan = Plan(config, base, strategies, axes, sp, monte_carlo, seed)
    factors = np.random.default_rng(seed).uniform(-1.0, 1.0, size=(monte_carlo, len(sp))) if monte_carlo else None
    for g, point in enumerate(points):
        for d in range(draws):
            params_: dict[str, object] = {a.field: v for a, v in zip(axes, point)}
            if factors is not None:
                for s, u in zip(sp, factors[d]):
                    params_[s.field] = s.nominal * (1.0 + s.percent / 100.0 * float(u))
            index = len(plan.runs)
            plan.runs.append({"index": index, "grid_point": g, "draw": d if monte_carlo else None,
                              "params": params_})
    return plan


def check_runs(plan: Plan, log: Log) -> None:
    """Load every run's config (base overrides and the run's parameters), as the config is checked."""
    t0 = time.perf_counter()
    for run in plan.runs:
        params = run["params"]
        assert isinstance(params, dict)
        try:
            plan.models.append(load_config(plan.config, {**plan.base, **params}))
        except ConfigError as exc:
            where = ", ".join(f"{k}={v!r}" for k, v in params.items())
            raise ConfigError(exc.file, exc.field, exc.value, f"{exc.allowed} (sweep run {run['index']}: {where})") from None
    log(f"sweep: {len(plan.runs)} run configs checked in {time.perf_counter() - t0:.2f} s")


# ---------------------------------------------------------------- command
#: the default LocalCluster starts only for a plan of at least this many runs; fewer run serially
LOCAL_CLUSTER_FROM_RUNS = 4


def runner_of(args: argparse.Namespace) -> Any:
    """The checked runner of ``--serial``, ``--scheduler``, ``--workers`` and ``--tls-ca-file``,
    ``--tls-cert``, ``--tls-key`` (:func:`codegen.stages.sweep_runner.check_runner_args`)."""
    from codegen.stages import sweep_runner

    return sweep_runner.check_runner_args(args.serial, args.scheduler, args.workers,
                                          getattr(args, "tls_ca_file", None), getattr(args, "tls_cert", None),
                                          getattr(args, "tls_key", None))


def command(args: argparse.Namespace, model: Model, log: Log, strategies: list[str],
            outputs: dict[str, Path | None]) -> int:
    """``mpcgen sweep``: check everything, run the plan (Dask or serial), write JSON, CSV and the plot
    (``strategies`` and the output files ``outputs`` "json", "csv", "plot" checked by the command line)."""
    from codegen.stages import sweep_output, sweep_runner

    runner = runner_of(args)
    plan = build_plan(args.config, model, base_overrides(args), strategies, args.param, args.spread,
                      args.monte_carlo, args.seed)
    check_runs(plan, log)
    if runner.kind == "local" and args.workers is None and len(plan.runs) < LOCAL_CLUSTER_FROM_RUNS:
        # a LocalCluster takes seconds to start: a small plan runs here (the same results, bit for bit)
        runner = sweep_runner.Runner("serial")
        log(f"sweep: {len(plan.runs)} run(s): serially in this process (a LocalCluster starts from "
            f"{LOCAL_CLUSTER_FROM_RUNS} runs; --workers N starts one anyway)")
    warned = set(model.warnings)
    for m in plan.models:
        for w in m.warnings:
            if w not in warned:
                warned.add(w)
                print(f"mpcgen: warning: {w}", file=sys.stderr)
    log(f"sweep {model.name}: {plan.kind}, {len(plan.runs)} runs x {len(strategies)} strategies "
        f"({', '.join(strategies)}) on {runner.describe()}")
    results, timing = sweep_runner.run_plan(plan, runner, log)
    data = sweep_output.assemble(plan, model, results, timing)
    print(sweep_output.table(data))
    if outputs["json"] is not None:
        sweep_output.write_json(outputs["json"], data)
    if outputs["csv"] is not None:
        sweep_output.write_csv(outputs["csv"], data)
    if outputs["plot"] is not None:
        sweep_output.plot(outputs["plot"], data)
    return 0
