"""Run a sweep's plan: serially in this process, or as ``dask.distributed`` tasks.

Each task is one run: the run's checked :class:`~codegen.model.Model` (the
config with the run's overrides, loaded and checked by the client before
anything started, so a worker needs no copy of the config file) goes through
the training stage (:mod:`codegen.stages.training`: the run's trained tables, when a
strategy needs them and the config names no tables file) and the topology's
``simulate`` for every chosen strategy, and the task returns
plain data (JSON-ready dicts).  The wall-clock fields of ``simulate``
(``wall_s``, ``periods_per_s``) are split off into the task's timing, so the
metrics of a run are the same bit for bit whichever runner computed them.

Runners: a ``LocalCluster`` on this machine's cores (one single-threaded
worker process per core, or ``--workers N``), a running scheduler
(``--scheduler tcp://HOST:PORT``; its workers need the same mpcgen installed
and a C compiler, as ``simulate`` does), or ``--serial`` (no Dask).
"""
from __future__ import annotations

import os
import platform
import re
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from codegen.errors import MpcgenError, UsageError
from codegen.model import Model
from codegen.results import clean_json, metric_sets
from codegen.stages.training import with_trained_tables
from codegen.topology import topology_of

__all__ = ["Runner", "check_runner_args", "run_task", "run_plan", "TIMING_KEYS"]

Log = Callable[[str], None]

#: result fields that are wall-clock measurements (kept apart from the metrics)
TIMING_KEYS = frozenset({"wall_s", "periods_per_s"})
#: result fields a sweep's header carries once instead of per run
_HEADER_KEYS = ("config", "versions")
#: seconds to wait for a remote scheduler before giving up
CONNECT_TIMEOUT_S = 10
_ADDRESS_RE = re.compile(r"(tcp|tls|ucx|ws|wss|inproc)://\[?[A-Za-z0-9_.:-]+\]?(:\d{1,5})?(/.*)?")


@dataclass(frozen=True)
class Runner:
    """Where the runs go: ``serial``, ``local`` (a LocalCluster of ``workers``) or ``scheduler``."""

    kind: str
    workers: int = 1
    address: str | None = None

    def describe(self) -> str:
        if self.kind == "serial":
            return "this process (--serial)"
        if self.kind == "local":
            return f"a Dask LocalCluster of {self.workers} worker processes"
        return f"the Dask scheduler {self.address}"


def check_runner_args(serial: bool, scheduler: str | None, workers: int | None) -> Runner:
    """Check ``--serial``, ``--scheduler`` and ``--workers`` (nothing is started here)."""
    if serial and scheduler:
        raise UsageError("--serial and --scheduler exclude each other")
    if workers is not None:
        if workers < 1:
            raise UsageError(f"--workers = {workers}: must be an integer >= 1")
        if serial or scheduler:
            raise UsageError("--workers sizes the LocalCluster; it does not go with --serial or --scheduler")
    if serial:
        return Runner("serial")
    if scheduler is not None:
        if not _ADDRESS_RE.fullmatch(scheduler.strip()):
            raise UsageError(f"--scheduler = {scheduler!r}: expected a scheduler address such as tcp://HOST:8786")
        return Runner("scheduler", address=scheduler.strip())
    try:
        import distributed  # noqa: F401
    except ImportError:
        raise UsageError("the sweep runs on dask.distributed, which is not installed "
                         "(pip install 'dask[distributed]'), or give --serial") from None
    return Runner("local", workers=workers or os.cpu_count() or 1)


# ---------------------------------------------------------------- one run
def _split_timing(node: Any, timing: dict[str, Any], path: str = "") -> Any:
    """``node`` without the wall-clock fields; those go to ``timing`` under their dotted path."""
    if isinstance(node, dict):
        out = {}
        for k, v in node.items():
            if k in TIMING_KEYS and not isinstance(v, (dict, list)):
                timing[f"{path}{k}"] = v
            else:
                out[k] = _split_timing(v, timing, f"{path}{k}.")
        return out
    if isinstance(node, list):
        return [_split_timing(v, timing, f"{path}{i}.") for i, v in enumerate(node)]
    return node


def run_task(index: int, model: Model, strategies: list[str]) -> dict[str, Any]:
    """One run: the topology's ``simulate`` of ``model`` for ``strategies``, as plain data.

    Returns ``{"index", "result", "warnings", "timing"}``: ``result`` is simulate's JSON (metrics per
    strategy, scenario), without its printable table and wall-clock fields; ``timing`` has those, the
    run's wall time and the worker that ran it.
    """
    t0 = time.perf_counter()
    model = with_trained_tables(model, strategies)  # the run's own training (cached per training config)
    data = topology_of(model).simulate(model, list(strategies), None, log=lambda _msg: None)
    data.pop("_table", None)
    warnings = list(data.pop("_warnings", []))
    for k in _HEADER_KEYS:
        data.pop(k, None)
    timing: dict[str, Any] = {}
    result = _split_timing(clean_json(data), timing)
    timing["run_wall_s"] = time.perf_counter() - t0
    timing["worker"] = f"{platform.node()}:{os.getpid()}"
    return {"index": index, "result": result, "warnings": warnings, "timing": clean_json(timing)}


def _summary(plan: Any, out: dict[str, Any]) -> str:
    """A short line about a finished run: its parameters and each strategy's (and scenario run's) torque
    ripple."""
    run = plan.runs[out["index"]]
    params = ", ".join(f"{k.rpartition('.')[2]}={v:.6g}" if isinstance(v, float) else f"{k.rpartition('.')[2]}={v}"
                       for k, v in run["params"].items())
    rip = []
    for s, scenario, m in metric_sets(out["result"]):
        v = m.get("T_rip_RMSE_nm")
        if isinstance(v, float):
            rip.append(f"{s}{'/' + scenario if scenario else ''} {v:.4f}")
    ripple = f"; T_rip {' '.join(rip)} N*m" if rip else ""
    return f"{params}{ripple}"


# ---------------------------------------------------------------- runners
def _log_done(log: Log, plan: Any, out: dict[str, Any], done: int, t_start: float) -> None:
    n = len(plan.runs)
    elapsed = time.perf_counter() - t_start
    eta = elapsed / done * (n - done)
    log(f"sweep: run {out['index'] + 1}/{n} done ({done}/{n}, {elapsed:.1f} s, ~{eta:.0f} s left) "
        f"in {out['timing']['run_wall_s']:.2f} s on {out['timing']['worker']}: {_summary(plan, out)}")


def _run_serial(plan: Any, log: Log) -> list[dict[str, Any]]:
    t_start = time.perf_counter()
    outs = []
    for i, model in enumerate(plan.models):
        outs.append(run_task(i, model, plan.strategies))
        _log_done(log, plan, outs[-1], i + 1, t_start)
    return outs


def _client(runner: Runner, log: Log) -> tuple[Any, Any]:
    """A connected ``distributed.Client`` and the LocalCluster it owns (None for a remote scheduler)."""
    import logging

    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise UsageError("the sweep runs on dask.distributed, which is not installed "
                         "(pip install 'dask[distributed]'), or give --serial") from None
    if runner.kind == "local":
        cluster = LocalCluster(n_workers=runner.workers, threads_per_worker=1, processes=True,
                               dashboard_address=None, silence_logs=logging.CRITICAL)
        log(f"sweep: LocalCluster started, scheduler {cluster.scheduler_address}")
        return Client(cluster), cluster
    try:
        client = Client(runner.address, timeout=f"{CONNECT_TIMEOUT_S}s")
    except (OSError, TimeoutError) as exc:
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise UsageError(f"--scheduler = {runner.address}: cannot connect within {CONNECT_TIMEOUT_S} s "
                         f"({reason[:200]}); start one with 'dask scheduler' and 'dask worker {runner.address}'") from None
    n = len(client.scheduler_info().get("workers", {}))
    log(f"sweep: connected to {runner.address} ({n} workers now"
        f"{'; the runs wait for workers to join' if n == 0 else ''})")
    return client, None


def _run_dask(plan: Any, runner: Runner, log: Log) -> list[dict[str, Any]]:
    from distributed import as_completed

    client, cluster = _client(runner, log)
    try:
        strategies = list(plan.strategies)
        futures = [client.submit(run_task, i, m, strategies, pure=False, key=f"mpcgen-sweep-run-{i}-{os.getpid()}-{time.time_ns()}")
                   for i, m in enumerate(plan.models)]
        outs: list[dict[str, Any]] = []
        t_start = time.perf_counter()
        for fut in as_completed(futures):
            try:
                out = fut.result()
            except MpcgenError:
                client.cancel(futures)
                raise
            except Exception as exc:  # a crash in a worker: one line naming the run
                client.cancel(futures)
                i = futures.index(fut)
                raise MpcgenError(f"sweep run {i} ({plan.runs[i]['params']}) failed: "
                                  f"{type(exc).__name__}: {' '.join(str(exc).split())[:300]}") from None
            outs.append(out)
            _log_done(log, plan, out, len(outs), t_start)
        return outs
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def run_plan(plan: Any, runner: Runner, log: Log) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    """Every run's output (in plan order) and the sweep's timing."""
    t0 = time.perf_counter()
    outs = _run_serial(plan, log) if runner.kind == "serial" else _run_dask(plan, runner, log)
    wall = time.perf_counter() - t0
    outs.sort(key=lambda o: o["index"])
    timing = {"runner": runner.kind, "address": runner.address,
              "workers": runner.workers if runner.kind != "scheduler" else None,
              "wall_s": wall, "runs": [dict(o["timing"], index=o["index"]) for o in outs]}
    log(f"sweep: {len(outs)} runs in {wall:.1f} s on {runner.describe()}")
    return outs, timing
