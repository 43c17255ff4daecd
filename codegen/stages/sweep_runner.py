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
(``--scheduler tcp://HOST:PORT``, or ``tls://HOST:PORT`` with the TLS
credentials of :class:`Tls`; its workers need the same mpcgen installed
and a C compiler, as ``simulate`` does), or ``--serial`` (no Dask).

A :class:`Session` holds one runner open (one cluster, one client) for any
number of plans: ``sweep`` runs one plan, ``tune`` one per refinement round.
A run of a plan may name its own ``strategies`` (``tune``: one strategy per
run); the others take the plan's.
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

__all__ = ["Runner", "Tls", "Session", "check_runner_args", "run_task", "run_plan", "timing_of", "TIMING_KEYS",
           "TLS_OPTIONS", "TLS_CONFIG_KEYS"]

Log = Callable[[str], None]

#: result fields that are wall-clock measurements (kept apart from the metrics)
TIMING_KEYS = frozenset({"wall_s", "periods_per_s"})
#: result fields a sweep's header carries once instead of per run
_HEADER_KEYS = ("config", "versions")
#: seconds to wait for a remote scheduler before giving up
CONNECT_TIMEOUT_S = 10
_ADDRESS_RE = re.compile(r"(tcp|tls|ucx|ws|wss|inproc)://\[?[A-Za-z0-9_.:-]+\]?(:\d{1,5})?(/.*)?")


#: the command-line options of the TLS credentials, in :class:`Tls` field order
TLS_OPTIONS = ("--tls-ca-file", "--tls-cert", "--tls-key")
#: the Dask configuration keys a tls:// scheduler address can take its credentials from instead
TLS_CONFIG_KEYS = ("distributed.comm.tls.ca-file", "distributed.comm.tls.client.cert",
                   "distributed.comm.tls.client.key")


@dataclass(frozen=True)
class Tls:
    """TLS credentials (PEM files): the certificate authority that signed the scheduler's and the workers'
    certificates, and this client's certificate and key, signed by it."""

    ca_file: str
    cert: str
    key: str

    def security(self, cluster: bool = False) -> Any:
        """A ``distributed.Security`` that requires encryption and presents these credentials as the client
        (``cluster``: as the scheduler and the workers of a LocalCluster too)."""
        from distributed import Security

        roles = ("client", "scheduler", "worker") if cluster else ("client",)
        kw = {f"tls_{r}_{part}": path for r in roles for part, path in (("cert", self.cert), ("key", self.key))}
        return Security(require_encryption=True, tls_ca_file=self.ca_file, **kw)


@dataclass(frozen=True)
class Runner:
    """Where the runs go: ``serial``, ``local`` (a LocalCluster of ``workers``) or ``scheduler``; ``tls``:
    the credentials of a TLS connection (None: none given; a tls:// address then takes the Dask
    configuration's)."""

    kind: str
    workers: int = 1
    address: str | None = None
    tls: Tls | None = None

    def describe(self) -> str:
        if self.kind == "serial":
            return "this process (--serial)"
        if self.kind == "local":
            return f"a Dask LocalCluster of {self.workers} worker processes{' (TLS)' if self.tls else ''}"
        return f"the Dask scheduler {self.address}"


def _tls_files(ca_file: str | None, cert: str | None, key: str | None) -> Tls | None:
    """The three TLS files, each a readable file, or None when none is given."""
    given = (ca_file, cert, key)
    if all(v is None for v in given):
        return None
    missing = [o for o, v in zip(TLS_OPTIONS, given) if v is None]
    if missing:
        raise UsageError(f"{', '.join(missing)} missing: a TLS connection needs {', '.join(TLS_OPTIONS)} "
                         "(the CA, this client's certificate and its key, PEM files)")
    for option, path in zip(TLS_OPTIONS, given):
        assert path is not None
        if not os.path.isfile(path) or not os.access(path, os.R_OK):
            raise UsageError(f"{option} = {path}: not a readable file")
    assert ca_file is not None and cert is not None and key is not None
    return Tls(ca_file, cert, key)


def check_runner_args(serial: bool, scheduler: str | None, workers: int | None, tls_ca_file: str | None = None,
                      tls_cert: str | None = None, tls_key: str | None = None) -> Runner:
    """Check ``--serial``, ``--scheduler``, ``--workers`` and the TLS files (nothing is started here)."""
    if serial and scheduler:
        raise UsageError("--serial and --scheduler exclude each other")
    if workers is not None:
        if workers < 1:
            raise UsageError(f"--workers = {workers}: must be an integer >= 1")
        if serial or scheduler:
            raise UsageError("--workers sizes the LocalCluster; it does not go with --serial or --scheduler")
    tls = _tls_files(tls_ca_file, tls_cert, tls_key)
    if serial:
        if tls is not None:
            raise UsageError(f"{'/'.join(TLS_OPTIONS)} secure a Dask connection; they do not go with --serial")
        return Runner("serial")
    if scheduler is not None:
        address = scheduler.strip()
        if not _ADDRESS_RE.fullmatch(address):
            raise UsageError(f"--scheduler = {scheduler!r}: expected a scheduler address such as tcp://HOST:8786")
        if tls is not None and not address.startswith("tls://"):
            raise UsageError(f"--scheduler = {address}: the TLS credentials go with a tls:// address "
                             f"(tls://HOST:PORT of a scheduler started with TLS)")
        if tls is None and address.startswith("tls://"):
            import dask

            if not all(dask.config.get(k, None) for k in TLS_CONFIG_KEYS):
                raise UsageError(f"--scheduler = {address}: a tls:// scheduler needs this client's credentials: "
                                 f"{', '.join(TLS_OPTIONS)}, or the Dask configuration's {', '.join(TLS_CONFIG_KEYS)}")
        return Runner("scheduler", address=address, tls=tls)
    try:
        import distributed  # noqa: F401
    except ImportError:
        raise UsageError("the sweep runs on dask.distributed, which is not installed "
                         "(pip install 'dask[distributed]'), or give --serial") from None
    return Runner("local", workers=workers or os.cpu_count() or 1, tls=tls)


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
def _strategies_of(plan: Any, i: int) -> list[str]:
    """The strategies of run ``i``: its own ``strategies``, else the plan's."""
    own = plan.runs[i].get("strategies")
    return list(own) if own else list(plan.strategies)


def _log_done(log: Log, plan: Any, out: dict[str, Any], done: int, t_start: float, label: str) -> None:
    n = len(plan.runs)
    elapsed = time.perf_counter() - t_start
    eta = elapsed / done * (n - done)
    log(f"{label}: run {out['index'] + 1}/{n} done ({done}/{n}, {elapsed:.1f} s, ~{eta:.0f} s left) "
        f"in {out['timing']['run_wall_s']:.2f} s on {out['timing']['worker']}: {_summary(plan, out)}")


def _client(runner: Runner, log: Log) -> tuple[Any, Any]:
    """A connected ``distributed.Client`` and the LocalCluster it owns (None for a remote scheduler)."""
    import logging

    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise UsageError("the sweep runs on dask.distributed, which is not installed "
                         "(pip install 'dask[distributed]'), or give --serial") from None
    if runner.kind == "local":
        secure: dict[str, Any] = {} if runner.tls is None else {
            "protocol": "tls://", "security": runner.tls.security(cluster=True)}
        cluster = LocalCluster(n_workers=runner.workers, threads_per_worker=1, processes=True,
                               dashboard_address=None, silence_logs=logging.CRITICAL, **secure)
        log(f"dask: LocalCluster started, scheduler {cluster.scheduler_address}")
        return Client(cluster, **({} if runner.tls is None else {"security": runner.tls.security()})), cluster
    assert runner.address is not None
    try:
        security = None if runner.tls is None else runner.tls.security()
        client = Client(runner.address, timeout=f"{CONNECT_TIMEOUT_S}s", security=security)
    except (OSError, TimeoutError, ValueError) as exc:
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise UsageError(f"--scheduler = {runner.address}: cannot connect within {CONNECT_TIMEOUT_S} s "
                         f"({reason[:200]}); start one with 'dask scheduler' and 'dask worker {runner.address}'"
                         + (" and check the TLS credentials" if runner.address.startswith("tls://") else "")) from None
    n = len(client.scheduler_info().get("workers", {}))
    log(f"dask: connected to {runner.address} ({n} workers now"
        f"{'; the runs wait for workers to join' if n == 0 else ''})")
    return client, None


class Session:
    """A runner held open: :meth:`run` runs a plan (any number of times) on one cluster and client,
    closed when the ``with`` block ends (``serial``: no Dask at all)."""

    def __init__(self, runner: Runner, log: Log) -> None:
        self.runner, self.log = runner, log
        self._client: Any = None
        self._cluster: Any = None

    def __enter__(self) -> Session:
        if self.runner.kind != "serial":
            self._client, self._cluster = _client(self.runner, self.log)
        return self

    def __exit__(self, *exc: object) -> None:
        if self._client is not None:
            self._client.close()
        if self._cluster is not None:
            self._cluster.close()
        self._client = self._cluster = None

    def run(self, plan: Any, label: str = "sweep") -> list[dict[str, Any]]:
        """Every run's output of ``plan``, in plan order (progress lines start with ``label``)."""
        outs = self._run_serial(plan, label) if self._client is None else self._run_dask(plan, label)
        outs.sort(key=lambda o: o["index"])
        return outs

    def _run_serial(self, plan: Any, label: str) -> list[dict[str, Any]]:
        t_start = time.perf_counter()
        outs = []
        for i, model in enumerate(plan.models):
            outs.append(run_task(i, model, _strategies_of(plan, i)))
            _log_done(self.log, plan, outs[-1], i + 1, t_start, label)
        return outs

    def _run_dask(self, plan: Any, label: str) -> list[dict[str, Any]]:
        from distributed import as_completed

        client = self._client
        tag = f"{os.getpid()}-{time.time_ns()}"
        futures = [client.submit(run_task, i, m, _strategies_of(plan, i), pure=False, key=f"mpcgen-{label.split()[0]}-run-{i}-{tag}")
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
                raise MpcgenError(f"{label} run {i} ({plan.runs[i]['params']}) failed: "
                                  f"{type(exc).__name__}: {' '.join(str(exc).split())[:300]}") from None
            outs.append(out)
            _log_done(self.log, plan, out, len(outs), t_start, label)
        return outs


def timing_of(runner: Runner, outs: list[dict[str, Any]], wall_s: float) -> dict[str, Any]:
    """The ``timing`` entry of a study: the runner, its workers, the wall time and every run's timing."""
    return {"runner": runner.kind, "address": runner.address,
            "workers": runner.workers if runner.kind != "scheduler" else None,
            "wall_s": wall_s, "runs": [dict(o["timing"], index=o["index"]) for o in outs]}


def run_plan(plan: Any, runner: Runner, log: Log) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    """Every run's output (in plan order) and the sweep's timing."""
    t0 = time.perf_counter()
    with Session(runner, log) as session:
        outs = session.run(plan)
    wall = time.perf_counter() - t0
    log(f"sweep: {len(outs)} runs in {wall:.1f} s on {runner.describe()}")
    return outs, timing_of(runner, outs, wall)
