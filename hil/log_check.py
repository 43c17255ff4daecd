"""Offline re-verification of a log written by :class:`hil.exchange_log.LoggingLink`
(``mpcgen hil --check-log``).

:func:`check_log` checks the digest chain, that the log ends with the end record of a completed run whose
counts are the log's own, every frame's CRC (a frame that does not decode is a problem), the sequence
numbers of the host's frames, the board's INFO hashes, that every state sent has a result (or was sent
again and that copy has one; a second RESULT of one state is counted) and every result answers a state
sent; it then recomputes the Python reference for every logged state and compares every output bit for
bit.  Each problem is reported with its file line number.
"""
from __future__ import annotations

import json
import os
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from codegen.compare import mismatch_mask
from codegen.model import Model
from codegen.topology import topology_of

from .exchange_log import FORMAT, FORMAT_NAME, DigestChain, Tally, type_name
from .framing import Discarded, Frame, FrameDecoder
from .messages import BoardInfo, ProtocolError, parse_error, parse_info, split_results
from .schema import Msg, Schema

__all__ = ["LogRefused", "LogLines", "Problem", "check_log", "read_log", "summary_line", "truncation_line"]

#: problems listed in full in the JSON (the count is always complete)
LISTED = 20
#: sequence numbers are 16 bits
_SEQ_MASK = 0xFFFF


class LogRefused(ValueError):
    """The file is not a log this version checks, or of another config, or cut mid-line (exit 2)."""


@dataclass(frozen=True, order=True)
class Problem:
    """One thing the log does not prove, at a file line number."""

    line: int
    what: str

    def __str__(self) -> str:
        return f"line {self.line}: {self.what}"


# ---------------------------------------------------------------- reading
@dataclass
class LogLines:
    """A log split into its records, with what its structure and digests say."""

    header: dict[str, Any]
    chunks: list[tuple[int, str, bytes]] = field(default_factory=list)  # (line, direction, octets)
    end: dict[str, Any] | None = None
    end_line: int | None = None
    lines: int = 0  # complete lines
    truncated_at: int | None = None  # the line cut in half (no newline), if any
    problems: list[Problem] = field(default_factory=list)  # edits and structure, in line order
    chain_intact: bool = True  # every line carries the digest of the log up to it
    digest: str = ""  # SHA-256 of the complete lines


def _header(first: bytes, cut: bool) -> dict[str, Any]:
    """The header record of line 1; LogRefused unless it is one of this format."""
    try:
        header = json.loads(first.decode("ascii"))
    except (UnicodeDecodeError, json.JSONDecodeError):
        if cut and first.startswith(b'{"format": "' + FORMAT_NAME.encode()):
            raise LogRefused("truncated at line 1 (cut mid-line): nothing before it to check") from None
        raise LogRefused("not a log written by `mpcgen hil --log` (line 1 is not its JSON header)") from None
    fmt = header.get("format") if isinstance(header, dict) else None
    if not isinstance(fmt, str) or not fmt.startswith(FORMAT_NAME):
        raise LogRefused("not a log written by `mpcgen hil --log` (line 1 has no log format)")
    if fmt != FORMAT:
        raise LogRefused(f"a log of format {fmt}; this version checks {FORMAT} only (its lines carry digests "
                         f"and it ends with an end record): record the run again with --log")
    return header


def read_log(path: Path) -> LogLines:
    """The records of a log, and the problems of its structure and digests; LogRefused if it is not one."""
    parts = path.read_bytes().split(b"\n")
    cut = parts[-1] != b""  # the last line has no newline: cut in half
    lines = parts if cut else parts[:-1]
    if not lines:
        raise LogRefused("empty file")
    log = LogLines(_header(lines[0], cut and len(lines) == 1))
    if cut:
        log.truncated_at = len(lines)
        lines = lines[:-1]
        if not lines:
            raise LogRefused("truncated at line 1 (cut mid-line): nothing before it to check")
    log.lines = len(lines)
    chain = DigestChain()
    for no, raw in enumerate(lines, start=1):
        if not chain.check(raw) and log.chain_intact:
            log.chain_intact = False
            log.problems.append(Problem(no, "the line does not carry the digest of the log up to it: it was "
                                            "edited, or lines were inserted or removed here"))
        if no == 1:
            continue
        if log.end_line is not None:
            if log.end_line == no - 1:
                log.problems.append(Problem(no, "a line after the end record"))
            continue
        try:
            rec = json.loads(raw.decode("ascii"))
        except (UnicodeDecodeError, json.JSONDecodeError):
            log.problems.append(Problem(no, "not a JSON record"))
            continue
        if isinstance(rec, dict) and rec.get("dir") in ("out", "in"):
            try:
                log.chunks.append((no, str(rec["dir"]), bytes.fromhex(rec["hex"])))
            except (KeyError, TypeError, ValueError):
                log.problems.append(Problem(no, "its octets are not hex"))
        elif isinstance(rec, dict) and rec.get("end") is True:
            log.end, log.end_line = rec, no
        else:
            log.problems.append(Problem(no, "neither octets with a direction nor the end record"))
    log.digest = chain.digest
    return log


# ---------------------------------------------------------------- checking
@dataclass
class _Slot:
    """One state sent: where, under which sequence number, its packed input record, results taken."""

    line: int
    seq: int
    state: bytes
    results: int = 0


class _Audit:
    """Pairs every RESULT with the state its sequence number was sent with, and notes what is wrong."""

    def __init__(self, schema: Schema, header: Mapping[str, Any]) -> None:
        self.schema, self.header = schema, header
        self.problems: list[Problem] = []
        self.slots: list[_Slot] = []
        self.latest: dict[int, int] = {}  # seq -> index of the latest slot sent under it
        self.pairs: list[tuple[_Slot, bytes, int]] = []  # (slot, RESULT payload, its line)
        self.next_seq: int | None = 1  # a session's first frame has sequence number 1
        self.info: BoardInfo | None = None
        self.board_errors: Counter[str] = Counter()
        self.n = Counter[str]()

    def item(self, line: int, direction: str, item: Frame | Discarded) -> None:
        if isinstance(item, Discarded):
            self.n[f"discarded_frames_{direction}"] += 1
            way = "host->board" if direction == "out" else "board->host"
            self.problems.append(Problem(line, f"a {way} frame that does not decode ({item.reason}, "
                                               f"{item.octets} octets)"))
        elif direction == "out":
            self._sent(line, item)
        else:
            self._received(line, item)

    def _sent(self, line: int, f: Frame) -> None:
        if self.next_seq is not None and f.seq != self.next_seq:
            self.n["seq_gaps"] += 1
            self.problems.append(Problem(line, f"host->board {type_name(f.type)} has sequence number {f.seq}, "
                                               f"the session's next was {self.next_seq}: a frame is missing"))
        span = 1
        if f.type == Msg.STEP:
            self._slot(line, f.seq, f.payload, self.schema.input_octets)
        elif f.type == Msg.BATCH:
            span = self._batch(line, f)
        self.next_seq = None if f.type == Msg.SETPOINTS else (f.seq + span) & _SEQ_MASK

    def _slot(self, line: int, seq: int, state: bytes, width: int) -> None:
        if len(state) != width:
            self.n["bad_steps"] += 1
            self.problems.append(Problem(line, f"a STEP of {len(state)} octets, an input record has {width}"))
            return
        self.latest[seq] = len(self.slots)
        self.slots.append(_Slot(line, seq, state))

    def _batch(self, line: int, f: Frame) -> int:
        """Slots of a BATCH's states; the sequence numbers it takes."""
        k, w = self.schema.batch_head.packed_dtype.itemsize, self.schema.input_octets
        body = f.payload[k:]
        count = int(self.schema.batch_head.unpack(f.payload[:k])["count"][0]) if len(f.payload) >= k else -1
        if count < 1 or len(body) != count * w:
            self.n["bad_batches"] += 1
            self.problems.append(Problem(line, f"a BATCH whose count {count} does not match its {len(body)} octets "
                                               f"of {w}-octet records"))
            return max(count, 1)
        for i in range(count):
            self._slot(line, (f.seq + i) & _SEQ_MASK, body[i * w:(i + 1) * w], w)
        return count

    def _received(self, line: int, f: Frame) -> None:
        if f.type == Msg.RESULT:
            if len(f.payload) != self.schema.result_octets:
                self.n["bad_results"] += 1
                self.problems.append(Problem(line, f"a RESULT of {len(f.payload)} octets, expected "
                                                   f"{self.schema.result_octets}"))
                return
            i = self.latest.get(f.seq)
            if i is None:
                self.n["unmatched_results"] += 1
                self.problems.append(Problem(line, f"a RESULT of sequence number {f.seq}, under which no state was "
                                                   f"sent before it"))
                return
            slot = self.slots[i]
            slot.results += 1
            self.n["duplicate_results"] += int(slot.results > 1)
            self.pairs.append((slot, f.payload, line))
        elif f.type == Msg.INFO:
            self._info(line, f)
        elif f.type == Msg.ERROR:
            try:
                self.board_errors[parse_error(self.schema, f.payload).name] += 1
            except ProtocolError:
                self.board_errors["malformed"] += 1

    def _info(self, line: int, f: Frame) -> None:
        try:
            info = parse_info(self.schema, f.payload)
        except ProtocolError as exc:
            self.problems.append(Problem(line, f"an INFO of another layout ({exc})"))
            return
        self.info = self.info or info
        want = (self.header.get("config_hash"), self.header.get("schema_hash"))
        if (info.config_hash, info.schema_hash) != want:
            self.problems.append(Problem(line, f"the board's INFO says config {info.config_hash}, schema "
                                               f"{info.schema_hash}; the header {want[0]}, {want[1]}"))

    def unanswered(self) -> None:
        """A problem for every state sent that has no result, unless the same state has one elsewhere."""
        answered = {s.state for s in self.slots if s.results}
        for s in self.slots:
            if not s.results and s.state not in answered:
                self.n["states_without_result"] += 1
                self.problems.append(Problem(s.line, f"the state sent with sequence number {s.seq} has no result"))

    def compare(self, model: Model, tables: Any) -> dict[str, Any]:
        """Every result against the reference for its state; mismatch problems; the counts."""
        if not self.pairs:
            return {"mismatches": 0, "mismatch_fields": {}}
        schema = self.schema
        states = schema.input.unpack(b"".join(p[0].state for p in self.pairs), len(self.pairs))
        payloads = np.frombuffer(b"".join(p[1] for p in self.pairs), np.uint8).reshape(len(self.pairs), -1)
        _, got = split_results(schema, payloads)
        bad, per_field = mismatch_mask(topology_of(model).step_batch(tables, states), got)
        for i in np.flatnonzero(bad):
            slot, _, line = self.pairs[i]
            self.problems.append(Problem(line, f"the RESULT of sequence number {slot.seq} (state sent at line "
                                               f"{slot.line}) differs from the reference"))
        return {"mismatches": int(bad.sum()), "mismatch_fields": per_field}


def _another_config(header: Mapping[str, Any], info: BoardInfo | None, model: Model, schema: Schema,
                    given: Mapping[str, Any]) -> str:
    """The one-line refusal of a log recorded with another config: what differs, and both hashes."""
    diffs = []
    log_cfg = (str(header.get("config")), list(header.get("sets") or []))
    this_cfg = (str(given.get("config", model.source)), list(given.get("sets") or []))
    if not _same_file(log_cfg[0], this_cfg[0]) or log_cfg[1] != this_cfg[1]:
        diffs.append(f"config {' --set '.join([log_cfg[0], *log_cfg[1]])} (this check: "
                     f"{' --set '.join([this_cfg[0], *this_cfg[1]])})")
    if header.get("strategy") != model.controller.strategy:
        diffs.append(f"strategy {header.get('strategy')} (this check: {model.controller.strategy})")
    if info is not None and info.number_format != schema.number_format:
        diffs.append(f"number format {info.number_format} (this check: {schema.number_format})")
    if info is not None and info.target != model.target:
        diffs.append(f"target {info.target} (this check: {model.target})")
    what = "; ".join(diffs) or "the same file, overrides, strategy, number format and target"
    return (f"the log is of another config: {what}; config hash {header.get('config_hash')}, schema hash "
            f"{header.get('schema_hash')} (this check: {schema.config_hash}, {schema.schema_hash}): check it with "
            f"the config it was recorded with")


def _same_file(a: str, b: str) -> bool:
    """Whether two config paths name one file (as given when both do not exist here)."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return os.path.normpath(a) == os.path.normpath(b)


def _first_info(schema: Schema, log: LogLines) -> BoardInfo | None:
    """The first INFO of the log that decodes (for naming the board's target and number format)."""
    dec = FrameDecoder()
    for _, direction, data in log.chunks:
        if direction != "in":
            continue
        for item in dec.feed(data):
            if isinstance(item, Frame) and item.type == Msg.INFO:
                try:
                    return parse_info(schema, item.payload)
                except ProtocolError:
                    pass
    return None


def _end_problems(log: LogLines, tally: Tally) -> list[Problem]:
    """Whether the log ends with the end record of a completed run whose counts are the log's own."""
    if log.end is None or log.end_line is None:
        if log.truncated_at is not None:
            return []  # reported as the truncation
        return [Problem(log.lines, f"the log ends at line {log.lines} without the end record: the run did not "
                                   f"finish, or the log was cut there")]
    out = []
    if log.end.get("counts") != tally.counts():
        out.append(Problem(log.end_line, f"the end record counts {log.end.get('counts')}, the log holds "
                                         f"{tally.counts()}"))
    if log.end.get("completed") is not True:
        run = log.end.get("run") or {}
        done = (f"{run.get('answered')} of {run.get('states')} states answered" if "states" in run else
                f"{run.get('periods_done')} of {run.get('periods')} periods" if "periods" in run else "")
        out.append(Problem(log.end_line, "the run did not complete (" + ", ".join(
            x for x in (done, str(log.end.get("error") or "")) if x) + ")"))
    return out


def check_log(model: Model, tables: Any, path: Path, given: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Re-verify a logged run (see the module's doc); the JSON-ready report, ``ok`` true when nothing is
    wrong.  LogRefused: not a log of this format, of another config (``given``: the ``config`` path and the
    ``sets`` overrides of this check, for the message), or empty; a log cut mid-line is reported
    (``truncated_at_line``), what precedes the cut checked."""
    log = read_log(path)
    header = log.header
    schema = Schema.of(model)
    if (header.get("config_hash"), header.get("schema_hash")) != (schema.config_hash, schema.schema_hash):
        if not log.problems or log.problems[0].line != 1:  # an edited header is an edit, not another config
            raise LogRefused(_another_config(header, _first_info(schema, log), model, schema, given or {}))
    tally = Tally()
    audit = _Audit(schema, header)
    for line, direction, data in log.chunks:
        for item in tally.feed(direction, data):
            audit.item(line, direction, item)
    audit.unanswered()
    ref = audit.compare(model, tables)
    integrity = sorted(log.problems + _end_problems(log, tally))
    others = sorted(audit.problems)
    if not audit.pairs:
        others.append(Problem(log.end_line or log.lines, "no RESULT to re-verify in the log"))
    problems = integrity + others
    first = integrity[0] if integrity else others[0] if others else None
    n = audit.n
    return {
        "log": str(path), "format": FORMAT, "board": header.get("board"), "mode": header.get("mode"),
        "target": audit.info.target if audit.info else None,
        "number_format": audit.info.number_format if audit.info else None,
        "lines": log.lines, "truncated_at_line": log.truncated_at, "digest_chain_intact": log.chain_intact,
        "log_sha256": log.digest,
        "end_record": log.end, "end_line": log.end_line,
        "completed": bool(log.end and log.end.get("completed") is True),
        "states_sent": len(audit.slots), "distinct_states": len({s.state for s in audit.slots}),
        "results": len(audit.pairs), **ref,
        "states_without_result": n["states_without_result"], "unmatched_results": n["unmatched_results"],
        "duplicate_results": n["duplicate_results"], "sequence_gaps": n["seq_gaps"],
        "discarded_frames_out": n["discarded_frames_out"], "discarded_frames_in": n["discarded_frames_in"],
        "bad_batches": n["bad_batches"], "bad_steps": n["bad_steps"], "bad_results": n["bad_results"],
        "board_errors": dict(audit.board_errors), "counts": tally.counts(),
        "problems": len(problems), "first_problem": None if first is None else {"line": first.line,
                                                                                "what": first.what},
        "problem_list": [{"line": p.line, "what": p.what} for p in problems[:LISTED]],
        "ok": not problems and log.truncated_at is None,
    }


def _found(data: Mapping[str, Any]) -> str:
    """What the check found, in a few words."""
    first = data["first_problem"]
    found = (f"{data['results']} results of {data['states_sent']} states sent re-verified, mismatches "
             f"{data['mismatches']}")
    if first is None:
        return found + ", nothing wrong"
    n = data["problems"]
    return found + f"; {n} problem{'' if n == 1 else 's'}, the first at line {first['line']}: {first['what']}"


def _chain(data: Mapping[str, Any]) -> str:
    return "digests intact" if data["digest_chain_intact"] else "digest chain BROKEN"


def summary_line(data: Mapping[str, Any]) -> str:
    """The one-line result of a check."""
    end = ("no end record" if data["end_record"] is None else
           "the end record of a completed run" if data["completed"] else "the end record of an INCOMPLETE run")
    return (f"log check {'OK' if data['ok'] else 'FAILED'}: {data['lines']} lines, {_chain(data)}, {end}; "
            f"{_found(data)}")


def truncation_line(data: Mapping[str, Any]) -> str:
    """The one-line refusal of a log cut mid-line, with what the check of the lines before it found."""
    n = data["truncated_at_line"]
    end = "" if data["end_record"] is not None else ", no end record before it"
    return f"truncated at line {n} (cut mid-line{end}); lines 1-{n - 1} checked, {_chain(data)}: {_found(data)}"
