"""Mode ``replay``: states through the board, every output compared bit for bit with the reference.

The reference (the topology's ``step_batch``) runs first; the session counts
mismatches live from the packed bytes (equal octets = equal bits), and the
final comparison uses ``codegen.compare`` (per field, and the state with both
results side by side for the first mismatching states).

A run the link or Ctrl-C ends early keeps what it has: the summary says
``complete: false``, lists the unanswered states (per source, as inclusive
index ranges) and carries a ``resume`` block (the seed, a digest of the
states, the RESULT payloads of the answered ones).  :func:`load_resume` and
:func:`prior_of` read that JSON back (``mpcgen hil --resume FILE``): the next
run sends only the states not answered and its summary is that of the whole
run (per-state results, mismatches, timings, ``outputs_sha256``: the same as
an uninterrupted run; wire counters, octets and wall time summed over the
parts).

Throughput is reported per direction, against what one direction of a
921 600-baud UART carries (8N1: 92 160 octets/s), with the states/s such a
UART would allow at this run's frame sizes (the busier direction limits).
"""
from __future__ import annotations

import base64
import binascii
import hashlib
import json
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from codegen.compare import describe_mismatch, mismatch_mask
from codegen.model import Model
from codegen.topology import topology_of

from .framing import encode_frame
from .messages import batch_payload, split_results, step_payload
from .progress import Progress, cycle_stats, timing_label, timing_prefix, wire_note
from .schema import Msg, Schema
from .session import Session
from .states import index_ranges, mask_of_ranges

__all__ = ["UART_921600_OCTETS_PER_S", "RESUME_FORMAT", "Prior", "replay", "summary_line", "load_resume",
           "prior_of", "uart_figures"]

#: octets per second one direction of a 921 600-baud UART carries (8N1: 10 bits per octet)
UART_921600_OCTETS_PER_S = 92_160
#: mismatching states described in full
DETAILS = 3
#: ``resume.format`` of a summary a later run can finish
RESUME_FORMAT = "mpcgen-hil-resume/1"


@dataclass
class Prior:
    """What earlier parts of a replay answered (read from their JSON): the next part adds to it."""

    path: str
    answered: np.ndarray  # bool (n,)
    payloads: np.ndarray  # (n, result octets) uint8; rows of unanswered states zero
    wire: dict[str, Any]
    wall_s: float
    octets_out: int
    octets_in: int
    parts: int


def states_digest(schema: Schema, states: np.ndarray) -> str:
    """SHA-256 of the packed input records (a resumed run must send the very same states)."""
    return hashlib.sha256(schema.input.pack(states).tobytes()).hexdigest()


def uart_figures(schema: Schema, batch: int, octets_out: int, octets_in: int, wall_s: float) -> dict[str, Any]:
    """Octets/s each way against one direction of a 921 600-baud UART, and the states/s that UART allows
    with this run's frames (a BATCH of ``batch`` states out, one RESULT per state in)."""
    batch = max(1, min(batch, schema.max_batch))
    zeros = schema.input.zeros(batch)
    request = (encode_frame(Msg.BATCH, 0, batch_payload(schema, zeros)) if batch > 1
               else encode_frame(Msg.STEP, 0, step_payload(schema, zeros)))
    out_per_state_f = len(request) / batch
    in_per_state = len(encode_frame(Msg.RESULT, 0, bytes(schema.result_octets)))
    wall = max(wall_s, 1e-9)
    return {"octets_out_per_s": round(octets_out / wall, 1), "octets_in_per_s": round(octets_in / wall, 1),
            "octets_per_state_out": round(out_per_state_f, 2), "octets_per_state_in": in_per_state,
            "uart_921600_octets_per_s_per_direction": UART_921600_OCTETS_PER_S,
            "uart_921600_states_per_s": round(UART_921600_OCTETS_PER_S / max(out_per_state_f, in_per_state), 1)}


def _add_wire(a: dict[str, Any], b: dict[str, Any]) -> dict[str, Any]:
    """Wire counters of two parts of a run, summed (flags or-ed, per-reason counts merged)."""
    out: dict[str, Any] = {}
    for key in {*a, *b}:
        x, y = a.get(key), b.get(key)
        if isinstance(x, bool) or isinstance(y, bool):
            out[key] = bool(x) or bool(y)
        elif isinstance(x, dict) or isinstance(y, dict):
            merged = dict(x or {})
            for k, v in (y or {}).items():
                merged[k] = merged.get(k, 0) + v
            out[key] = merged
        else:
            out[key] = (x or 0) + (y or 0)
    return out


def replay(session: Session, model: Model, tables: Any, sets: dict[str, np.ndarray], *, show_progress: bool = True,
           log: Callable[[str], None] = lambda _: None, seed: int | None = None,
           prior: Prior | None = None) -> dict[str, Any]:
    """Replay ``sets`` (source -> states) on the session's board; the JSON-ready summary.

    ``prior``: what an interrupted run of the same states answered; only the rest is sent."""
    schema = session.schema
    info = session.info
    if info is None:
        info = session.handshake()
    topo = topology_of(model)
    names = list(sets)
    states = np.concatenate([sets[k] for k in names]) if names else schema.input.zeros(0)
    source = np.concatenate([np.full(len(sets[k]), j) for j, k in enumerate(names)]) if names else np.zeros(0, int)
    offset = {k: int(sum(len(sets[m]) for m in names[:j])) for j, k in enumerate(names)}
    n = len(states)
    ref = topo.step_batch(tables, states)
    expected = schema.output.pack(ref)
    payloads = np.zeros((n, schema.result_octets), np.uint8)
    answered = np.zeros(n, bool)
    if prior is not None:
        payloads[prior.answered] = prior.payloads[prior.answered]
        answered |= prior.answered
    todo = np.flatnonzero(~answered)
    prog = Progress(f"hil replay {model.name}", len(todo), info.cycle_unit, enabled=show_progress)
    res = session.run(states[todo], expected[todo], tick=prog.update)
    payloads[todo[res.answered]] = res.payloads[res.answered]
    answered[todo] = res.answered
    given_up = np.zeros(n, bool)
    given_up[todo[res.lost]] = True
    cycles, got = split_results(schema, payloads)
    prog.update(int(res.answered.sum()), 0, cycles[todo][res.answered], force=True)
    prog.close()
    ans = answered
    bad, per_field = mismatch_mask(ref[ans], got[ans]) if ans.any() else (np.zeros(0, bool), {})
    bad_idx = np.flatnonzero(ans)[bad]

    def where(i: int) -> str:
        return f"{names[source[i]]} #{i - offset[names[source[i]]]}"

    details = [f"state {i} ({where(i)}):\n"
               + describe_mismatch(states[i], ref[i], got[i], "python", f"board {info.target}")
               for i in bad_idx[:DETAILS]]
    for d in details:
        log("mismatch: " + d)
    wire = res.stats.as_dict()
    wire["handshake_retries"] = session.handshake_retries
    for reason, count in session.handshake_discarded.items():
        wire["discarded"][reason] = wire["discarded"].get(reason, 0) + count
    wall, octets_out, octets_in, parts = res.wall_s, res.octets_out, res.octets_in, 1
    if prior is not None:
        wire = _add_wire(prior.wire, wire)
        wall, parts = wall + prior.wall_s, parts + prior.parts
        octets_out, octets_in = octets_out + prior.octets_out, octets_in + prior.octets_in
    rh = schema.result_head.packed_dtype.itemsize
    unanswered = ~answered
    complete = not unanswered.any()
    summary: dict[str, Any] = {
        "mode": "replay", "config": model.name, "strategy": getattr(tables, "strategy", None),
        "config_hash": schema.config_hash, "schema_hash": schema.schema_hash, "board": info.as_dict(),
        "seed": seed, "states": n, "answered": int(ans.sum()), "complete": bool(complete),
        "failure": res.failure, "parts": parts, "resumed_from": prior.path if prior is not None else None,
        "mismatches": int(len(bad_idx)), "mismatch_fields": per_field, "first_mismatches": details,
        "lost": int(given_up.sum()),
        "lost_states": [{"source": names[source[i]], "index": int(i - offset[names[source[i]]])}
                        for i in np.flatnonzero(given_up)],
        "unanswered": int(unanswered.sum()),
        "unanswered_ranges": [{"source": names[source[a]], "first": a - offset[names[source[a]]],
                               "last": b - offset[names[source[a]]]}
                              for k in range(len(names))
                              for a, b in index_ranges(unanswered & (source == k))],
        **cycle_stats(cycles[ans], timing_prefix(info.cycle_unit)), "cycle_unit": info.cycle_unit,
        "sources": {k: len(v) for k, v in sets.items()}, "source_order": names,
        "outputs_sha256": hashlib.sha256(np.ascontiguousarray(payloads[ans][:, rh:]).tobytes()).hexdigest(),
        "wall_s": round(wall, 3), "states_per_s": round(int(ans.sum()) / max(wall, 1e-9), 1),
        "octets_out": octets_out, "octets_in": octets_in,
        **uart_figures(schema, session.batch, octets_out, octets_in, wall),
        "wire": wire,
    }
    if not complete:
        summary["resume"] = {
            "format": RESUME_FORMAT, "seed": seed, "states_sha256": states_digest(schema, states),
            "result_octets": schema.result_octets, "answered_ranges": index_ranges(answered),
            "results_zlib_b64": base64.b64encode(zlib.compress(payloads[answered].tobytes(), 6)).decode("ascii")}
    return summary


def summary_line(data: dict[str, Any]) -> str:
    """The one-line result of a replay: states, mismatches, throughput each way, timings, wire faults."""
    prefix = timing_prefix(data["cycle_unit"])
    done = (f"{data['states']} states" if data["complete"] else
            f"{data['answered']}/{data['states']} states answered (INCOMPLETE: {data['unanswered']} unanswered)")
    part = f"  part {data['parts']}" if data["parts"] > 1 else ""
    return (f"{done}{part}  mismatches {data['mismatches']}  lost {data['lost']}  "
            f"{data['states_per_s']:,.0f} states/s (a 921600-baud UART allows {data['uart_921600_states_per_s']:,.0f})"
            f"  host->board {data['octets_out_per_s']:,.0f} octets/s, board->host {data['octets_in_per_s']:,.0f} "
            f"octets/s (921600-baud UART: {data['uart_921600_octets_per_s_per_direction']:,} each way)  "
            f"{timing_label(data['cycle_unit'])} min/median/p99/max {data[prefix + '_min']}/"
            f"{data[prefix + '_median']}/{data[prefix + '_p99']}/{data[prefix + '_max']}{wire_note(data['wire'])}")


def load_resume(path: str | Path) -> dict[str, Any]:
    """The JSON of an interrupted replay (``--json`` of that run); ValueError naming what is wrong."""
    p = Path(path)
    if not p.is_file():
        raise ValueError("no such file")
    try:
        doc = json.loads(p.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"not a JSON file ({exc})") from None
    if not isinstance(doc, dict) or doc.get("mode") != "replay":
        raise ValueError("not the JSON summary of an `mpcgen hil --mode replay` run (give the file its --json wrote)")
    if doc.get("complete") is True:
        raise ValueError("that run is complete: nothing to resume")
    block = doc.get("resume")
    if not isinstance(block, dict) or block.get("format") != RESUME_FORMAT:
        raise ValueError(f"no resume block of format {RESUME_FORMAT} (written by an interrupted run)")
    if not isinstance(block.get("seed"), int) or not isinstance(doc.get("states"), int):
        raise ValueError("its resume block names no seed or state count")
    return doc


def prior_of(doc: dict[str, Any], path: str | Path, schema: Schema, states: np.ndarray) -> Prior:
    """What the run of ``doc`` (:func:`load_resume`) answered, checked against this run's config, schema
    and states; ValueError naming the difference."""
    if doc.get("config_hash") != schema.config_hash or doc.get("schema_hash") != schema.schema_hash:
        raise ValueError(f"that run is config {doc.get('config_hash')} (schema {doc.get('schema_hash')}), this one "
                         f"{schema.config_hash} (schema {schema.schema_hash}): give the same config and overrides")
    block = doc["resume"]
    n = len(states)
    if doc["states"] != n or block.get("states_sha256") != states_digest(schema, states):
        raise ValueError("its states differ from this run's (same config, --states and --seed give the same states)")
    width = schema.result_octets
    if block.get("result_octets") != width:
        raise ValueError(f"its results have {block.get('result_octets')} octets, this schema {width}")
    try:
        answered = mask_of_ranges(block["answered_ranges"], n)
        raw = zlib.decompress(base64.b64decode(block["results_zlib_b64"], validate=True))
        wire = dict(doc["wire"])
        wall_s, octets_out, octets_in = float(doc["wall_s"]), int(doc["octets_out"]), int(doc["octets_in"])
        parts = int(doc.get("parts", 1))
    except (KeyError, TypeError, ValueError, binascii.Error, zlib.error) as exc:
        raise ValueError(f"its resume block is damaged ({exc})") from None
    if len(raw) != int(answered.sum()) * width:
        raise ValueError(f"its resume block holds {len(raw)} octets of results, {int(answered.sum())} answered "
                         f"states need {int(answered.sum()) * width}")
    payloads = np.zeros((n, width), np.uint8)
    payloads[answered] = np.frombuffer(raw, np.uint8).reshape(-1, width)
    return Prior(str(path), answered, payloads, wire, wall_s, octets_out, octets_in, parts)
