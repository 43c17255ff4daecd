"""Mode ``closed-loop`` (processor in the loop): the host simulates the plant, the board decides.

Every period runs the closed loop of ``mpcgen simulate`` (the topology's
float64 plant, sampling, speed PI and timing rule, in the same compiled C,
through :class:`codegen.simulator.driver.PeriodStepper`) except the
controller step: the period's input record (each sample rounded once to
float32, exactly what the simulator gives its step) goes to the board as a
STEP, the board's RESULT is the decision the plant then gets.  A board whose
step equals the generated C bit for bit therefore gives the simulator's
trace bit for bit; the harness also runs ``simulate``'s loop on the host and
reports where the two traces first differ (``identical_to_simulate``).

The metrics are the topology's ``simulate`` metrics of the board's trace.
Anything topology-specific comes from the topology plugin's simulation facet
(:class:`codegen.topology.Topology`: ``period_stepper``,
``closed_loop_trace``, ``trace_from``, ``trace_metrics``,
``decision_field``), reached through :func:`codegen.topology.topology_of`.
"""
from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

from codegen.model import Model
from codegen.results import clean_json
from codegen.topology import topology_of

from .messages import split_results
from .progress import Progress, cycle_stats
from .session import Session

__all__ = ["closed_loop", "trace_differences", "summary_line"]


def trace_differences(a: dict[str, np.ndarray], b: dict[str, np.ndarray]) -> tuple[list[str], int | None]:
    """Trace fields whose arrays differ bit for bit, and the first period where any differs (None: equal)."""
    fields, first = [], None
    for name in a:
        x, y = np.asarray(a[name]), np.asarray(b[name])
        if x.shape != y.shape:
            fields.append(name)
            first = 0
            continue
        xb = x.reshape(len(x), -1).view(np.uint8).reshape(len(x), -1)
        yb = y.reshape(len(y), -1).view(np.uint8).reshape(len(y), -1)
        rows = np.flatnonzero((xb != yb).any(axis=1))
        if len(rows):
            fields.append(name)
            first = int(rows[0]) if first is None else min(first, int(rows[0]))
    return fields, first


class _Board:
    """One decision per period from the session's board (STEP/RESULT, the session's recovery)."""

    def __init__(self, session: Session) -> None:
        self.session = session
        self.cycles: list[int] = []
        self.stats: list[Any] = []
        self.octets_out = self.octets_in = 0

    def __call__(self, rec: np.ndarray) -> np.ndarray | None:
        res = self.session.run(rec)
        self.octets_out += res.octets_out
        self.octets_in += res.octets_in
        self.stats.append(res.stats)
        if not res.answered[0]:
            return None
        cycles, out = split_results(self.session.schema, res.payloads)
        self.cycles.append(int(cycles[0]))
        return out


def closed_loop(session: Session, model: Model, tables: Any, *, show_progress: bool = True,
                log: Callable[[str], None] = lambda _: None) -> dict[str, Any]:
    """Run the model's scenario with the session's board in the loop; the JSON-ready summary."""
    schema = session.schema
    info = session.info if session.info is not None else session.handshake()
    topo = topology_of(model)
    lib = topo.host_library(model, tables, with_sim=True)
    stepper = topo.period_stepper(lib, model)
    board = _Board(session)
    prog = Progress(f"hil closed-loop {model.name}", stepper.n, info.cycle_unit, enabled=show_progress)
    t0 = time.perf_counter()
    lost_at: int | None = None
    for k in range(stepper.n):
        out = board(stepper.input())
        if out is None:
            lost_at = k
            log(f"period {k}: the board did not answer; the run stops there")
            break
        stepper.finish(out)
        if k % 256 == 0:
            prog.update(k + 1, 0, board.cycles)
    wall = time.perf_counter() - t0
    prog.update(stepper.k, 0, board.cycles, force=True)
    prog.close()
    arrays = stepper.result()

    # the host's own closed loop (mpcgen simulate) over the same scenario, for the equality check
    ref = topo.closed_loop_trace(model, lib)
    ref_arrays = {name: np.asarray(getattr(ref, name))[:stepper.k] for name in arrays}
    diff_fields, first = trace_differences(arrays, ref_arrays)
    dec = topo.decision_field
    dec_equal = bool(np.array_equal(arrays[dec], ref_arrays[dec]))
    metrics = topo.trace_metrics(topo.trace_from(arrays, model), model) if lost_at is None else None
    wire: dict[str, Any] = {"frames_sent": 0, "resent_states": 0, "duplicates": 0, "unexpected": 0, "resets": 0,
                            "board_errors": {}, "discarded": {}}
    for s in board.stats:
        d = s.as_dict()
        for key in ("frames_sent", "resent_states", "duplicates", "unexpected", "resets"):
            wire[key] += d[key]
        for key in ("board_errors", "discarded"):
            for name, v in d[key].items():
                wire[key][name] = wire[key].get(name, 0) + v
    cyc = np.asarray(board.cycles, np.int64)
    summary: dict[str, Any] = {
        "mode": "closed-loop", "config": model.name, "strategy": getattr(tables, "strategy", None)
        or model.controller.strategy, "config_hash": schema.config_hash, "schema_hash": schema.schema_hash,
        "board": info.as_dict(), "periods": stepper.n, "periods_done": stepper.k, "lost_at": lost_at,
        "decision_field": dec, "decisions": arrays[dec].astype(int).tolist() if stepper.k <= 20000 else None,
        "identical_to_simulate": not diff_fields, "decisions_equal_simulate": dec_equal,
        "differing_trace_fields": diff_fields, "first_difference_period": first,
        "metrics": clean_json(metrics) if metrics is not None else None,
        "ok": lost_at is None and dec_equal,
        **cycle_stats(cyc), "cycle_unit": info.cycle_unit,
        "wall_s": round(wall, 3), "periods_per_s": round(stepper.k / max(wall, 1e-9), 1),
        "octets_out": board.octets_out, "octets_in": board.octets_in, "wire": wire,
    }
    return summary


def summary_line(data: dict[str, Any]) -> str:
    """The one-line result of a closed-loop run."""
    m = data["metrics"] or {}
    same = "identical to simulate" if data["identical_to_simulate"] else (
        f"decisions {'equal' if data['decisions_equal_simulate'] else 'DIFFER'}, trace differs from simulate from "
        f"period {data['first_difference_period']} ({', '.join(data['differing_trace_fields'])})")
    metrics = "  ".join(f"{k} {m[k]:.4g}" for k in ("T_rip_RMSE_nm", "psi_rip_RMSE_wb", "THD_ia_percent", "f_ave_hz")
                        if isinstance(m.get(k), (int, float)))
    lost = "" if data["lost_at"] is None else f"  LOST at period {data['lost_at']}"
    return (f"{data['periods_done']}/{data['periods']} periods  {same}{lost}  {metrics}  "
            f"{data['periods_per_s']:,.0f} periods/s  {data['cycle_unit']} min/median/p99/max "
            f"{data['cycles_min']}/{data['cycles_median']}/{data['cycles_p99']}/{data['cycles_max']}")
