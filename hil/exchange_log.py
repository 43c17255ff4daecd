"""A log of every exchange with a board, and its offline re-verification (``mpcgen hil --check-log``).

:class:`LoggingLink` wraps any :class:`~hil.link.Link` and writes one JSON line per chunk of octets
that crosses it (direction, time since the start, hex octets), after a header line naming the
config file, the overrides, the config and schema hashes, the strategy and the board.
:func:`check_log` decodes both directions offline, pairs every RESULT with the state its
STEP/BATCH carried under the same sequence number (in the order they crossed the wire, so a
resend under a new number or a reset is followed), recomputes the Python reference for those
states and compares every output bit for bit: a board's answers can be re-verified later, or
on another machine, from the log alone plus the config.
"""
from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any, TextIO

import numpy as np

from codegen.compare import mismatch_mask
from codegen.model import Model
from codegen.topology import topology_of

from .framing import Frame, FrameDecoder
from .link import Link
from .messages import split_results
from .schema import Msg, Schema

__all__ = ["FORMAT", "LoggingLink", "check_log"]

#: first line of every log: {"format": FORMAT, ...}
FORMAT = "mpcgen-hil-log/1"


class LoggingLink:
    """A :class:`~hil.link.Link` that logs every octet written and read to ``out``."""

    def __init__(self, link: Link, out: TextIO, header: dict[str, Any]) -> None:
        self.link, self.out = link, out
        self.t0 = time.perf_counter()
        out.write(json.dumps({"format": FORMAT, **header}) + "\n")

    def _log(self, direction: str, data: bytes) -> None:
        if data:
            self.out.write(json.dumps({"t": round(time.perf_counter() - self.t0, 6), "dir": direction,
                                       "hex": data.hex()}) + "\n")

    @property
    def octets_out(self) -> int:
        return int(getattr(self.link, "octets_out", 0))

    @property
    def octets_in(self) -> int:
        return int(getattr(self.link, "octets_in", 0))

    def write(self, data: bytes) -> None:
        self._log("out", data)
        self.link.write(data)

    def read_waiting(self) -> bytes:
        data = self.link.read_waiting()
        self._log("in", data)
        return data

    def wait(self, timeout_s: float) -> None:
        self.link.wait(timeout_s)

    def close(self) -> None:
        self.out.flush()
        self.link.close()


def read_log(path: Path) -> tuple[dict[str, Any], list[tuple[str, bytes]]]:
    """The header and the (direction, octets) chunks of a log; ValueError if it is not one."""
    lines = path.read_text().splitlines()
    if not lines:
        raise ValueError("empty file")
    header = json.loads(lines[0])
    if not isinstance(header, dict) or header.get("format") != FORMAT:
        raise ValueError(f"not a log of format {FORMAT}")
    chunks = []
    for i, line in enumerate(lines[1:], start=2):
        rec = json.loads(line)
        if rec.get("dir") not in ("out", "in"):
            raise ValueError(f"line {i}: no direction")
        chunks.append((rec["dir"], bytes.fromhex(rec["hex"])))
    return header, chunks


def check_log(model: Model, tables: Any, path: Path) -> dict[str, Any]:
    """Re-verify a logged run: every RESULT in the log against the reference for its state."""
    header, chunks = read_log(path)
    schema = Schema.of(model)
    if header.get("config_hash") != schema.config_hash or header.get("schema_hash") != schema.schema_hash:
        raise ValueError(f"the log is of config {header.get('config_hash')} and schema {header.get('schema_hash')}, "
                         f"this config gives {schema.config_hash} and {schema.schema_hash}")
    dec = {"out": FrameDecoder(), "in": FrameDecoder()}
    in_w, out_w = schema.input_octets, schema.result_octets
    k = schema.batch_head.packed_dtype.itemsize
    state_of: dict[int, bytes] = {}  # sequence number -> packed input record, latest request wins
    pairs: list[tuple[bytes, bytes]] = []
    unmatched = 0
    # what the log holds that no result can be checked against: reported, never skipped silently
    faults = {"discarded_frames_out": 0, "discarded_frames_in": 0, "bad_batches": 0, "bad_results": 0}
    for direction, data in chunks:
        for item in dec[direction].feed(data):
            if not isinstance(item, Frame):
                faults[f"discarded_frames_{direction}"] += 1
                continue
            if direction == "out" and item.type == Msg.STEP:
                state_of[item.seq] = item.payload
            elif direction == "out" and item.type == Msg.BATCH:
                body = item.payload[k:]
                count = schema.batch_head.unpack(item.payload[:k])["count"][0] if len(item.payload) >= k else -1
                if len(body) % in_w or len(body) // in_w != count:
                    faults["bad_batches"] += 1  # its states are not taken: no result is paired with them
                    continue
                for i in range(len(body) // in_w):
                    state_of[(item.seq + i) & 0xFFFF] = body[i * in_w:(i + 1) * in_w]
            elif direction == "in" and item.type == Msg.RESULT and len(item.payload) != out_w:
                faults["bad_results"] += 1
            elif direction == "in" and item.type == Msg.RESULT:
                st = state_of.get(item.seq)
                if st is None:
                    unmatched += 1
                else:
                    pairs.append((st, item.payload))
    if not pairs:
        return {"log": str(path), "results": 0, "mismatches": 0, "unmatched_results": unmatched, **faults}
    states = schema.input.unpack(b"".join(p[0] for p in pairs), len(pairs))
    payloads = np.frombuffer(b"".join(p[1] for p in pairs), np.uint8).reshape(len(pairs), out_w)
    _, got = split_results(schema, payloads)
    ref = topology_of(model).step_batch(tables, states)
    bad, per_field = mismatch_mask(ref, got)
    return {"log": str(path), "board": header.get("board"), "results": len(pairs),
            "distinct_states": len({p[0] for p in pairs}), "mismatches": int(bad.sum()),
            "mismatch_fields": per_field, "unmatched_results": unmatched, **faults}
