"""Mode ``replay``: states through the board, every output compared bit for bit with the reference.

The reference (the topology's ``step_batch``) runs first; the session counts
mismatches live from the packed bytes (equal octets = equal bits), and the
final comparison uses ``codegen.compare`` (per field, and the state with both
results side by side for the first mismatching states).
"""
from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from codegen.compare import describe_mismatch, mismatch_mask
from codegen.model import Model
from codegen.topology import topology_of

from .messages import split_results
from .progress import Progress, cycle_stats
from .session import Session

__all__ = ["UART_921600_OCTETS_PER_S", "replay"]

#: octets per second of a 921 600-baud UART (8N1: 10 bits per octet)
UART_921600_OCTETS_PER_S = 92_160
#: mismatching states described in full
DETAILS = 3


def replay(session: Session, model: Model, tables: Any, sets: dict[str, np.ndarray], *, show_progress: bool = True,
           log: Callable[[str], None] = lambda _: None) -> dict[str, Any]:
    """Replay ``sets`` (source -> states) on the session's board; the JSON-ready summary."""
    schema = session.schema
    info = session.info
    if info is None:
        info = session.handshake()
    topo = topology_of(model)
    names = list(sets)
    states = np.concatenate([sets[k] for k in names]) if names else schema.input.zeros(0)
    source = np.concatenate([np.full(len(sets[k]), j) for j, k in enumerate(names)]) if names else np.zeros(0, int)
    offset = {k: int(sum(len(sets[m]) for m in names[:j])) for j, k in enumerate(names)}
    ref = topo.step_batch(tables, states)
    expected = schema.output.pack(ref)
    prog = Progress(f"hil replay {model.name}", len(states), info.cycle_unit, enabled=show_progress)
    res = session.run(states, expected, tick=prog.update)
    cycles, got = split_results(schema, res.payloads)
    ans = res.answered
    prog.update(int(ans.sum()), 0, cycles[ans], force=True)
    prog.close()
    bad, per_field = mismatch_mask(ref[ans], got[ans]) if ans.any() else (np.zeros(0, bool), {})
    bad_idx = np.flatnonzero(ans)[bad]
    details = [f"state {i} ({names[source[i]]} #{i - offset[names[source[i]]]}):\n"
               + describe_mismatch(states[i], ref[i], got[i], "python", f"board {info.target}")
               for i in bad_idx[:DETAILS]]
    for d in details:
        log("mismatch: " + d)
    octets = res.octets_out + res.octets_in
    wall = max(res.wall_s, 1e-9)
    summary: dict[str, Any] = {
        "mode": "replay", "config": model.name, "strategy": getattr(tables, "strategy", None),
        "config_hash": schema.config_hash, "schema_hash": schema.schema_hash, "board": info.as_dict(),
        "states": len(states), "answered": int(ans.sum()), "mismatches": int(len(bad_idx)),
        "mismatch_fields": per_field, "first_mismatches": details,
        "lost": len(res.lost), "lost_states": [{"source": names[source[i]], "index": i - offset[names[source[i]]]}
                                              for i in res.lost],
        **cycle_stats(cycles[ans]), "cycle_unit": info.cycle_unit,
        "sources": {k: len(v) for k, v in sets.items()},
        "wall_s": round(res.wall_s, 3), "states_per_s": round(len(states) / wall, 1),
        "octets_out": res.octets_out, "octets_in": res.octets_in, "octets_per_s": round(octets / wall, 1),
        "uart_921600_octets_per_s": UART_921600_OCTETS_PER_S,
        "wire": res.stats.as_dict(),
    }
    return summary
