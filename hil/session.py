"""A protocol session with one board: handshake, then a pipelined, self-healing replay.

:meth:`Session.handshake` sends HELLO until the board answers with INFO and
refuses a board whose schema or config hash differs from this run's (naming
both).  :meth:`Session.run` sends the states in BATCH frames, several in
flight (at most ``window_octets`` of requests unanswered, so that a
pseudo-terminal or a board's receive buffer never overflows), and collects
one RESULT per state:

* a frame that fails COBS, length or CRC is discarded and counted; nothing
  but a CRC-valid RESULT for an outstanding sequence number is ever taken;
* the board answers in order, so a RESULT of a later frame means the states
  of earlier unanswered frames were lost: they are sent again at once; a
  frame with no answer after ``timeout_s`` is sent again too; each state is
  sent at most ``1 + retries`` times, then counted lost;
* a RESULT for a state already answered (a duplicate) or for a sequence
  number never sent is counted and ignored;
* an INFO mid-run is a board reset: the hashes are checked again and every
  unanswered frame is sent again;
* no valid frame for ``silence_s`` while frames are outstanding: the board
  is silent, every unanswered state is lost and the run ends;
* a RESULT taken after one of a state sent later is counted as reordered
  (it is still taken: its CRC and sequence number are valid).

The link itself failing (:class:`hil.link.LinkError`: hang-up, EIO, a closed
socket, a broken pipe) or Ctrl-C ends the run at once: the result keeps
every state answered so far and names the failure (``RunResult.failure``);
the session takes no further run.  The handshake counts the HELLOs it sends
again (a lost HELLO or INFO) and the frames it discards.

The run therefore ends with every state answered exactly once, or with the
list of those that were not.
"""
from __future__ import annotations

import time
from collections import Counter, OrderedDict, deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from codegen.errors import MpcgenError

from .framing import Discarded, Frame, FrameDecoder, encode_frame
from .link import Link, LinkError
from .messages import BoardInfo, ProtocolError, batch_payload, parse_error, parse_info, step_payload
from .schema import PROTOCOL_VERSION, Msg, Schema

__all__ = ["BoardMismatch", "BoardSilent", "Session", "RunResult", "RunStats", "INTERRUPTED"]

#: ``RunResult.failure`` of a run ended by Ctrl-C
INTERRUPTED = "interrupted (Ctrl-C)"


class BoardMismatch(MpcgenError):
    """The board was built from another protocol, schema or config."""


class BoardSilent(MpcgenError):
    """The board never answered the handshake."""


@dataclass
class RunStats:
    """What went wrong on the wire during a run (all detected, none taken as a result)."""

    frames_sent: int = 0
    resent_states: int = 0
    duplicates: int = 0  # RESULTs of states already answered
    unexpected: int = 0  # RESULTs of sequence numbers never sent
    resets: int = 0  # INFO mid-run
    reordered: int = 0  # RESULTs taken after the RESULT of a state sent later
    silent: bool = False
    discarded: Counter[str] = field(default_factory=Counter)  # harness side: cobs, short, crc, oversize, length
    board_errors: Counter[str] = field(default_factory=Counter)  # ERROR messages by name

    def as_dict(self) -> dict[str, Any]:
        return {"frames_sent": self.frames_sent, "resent_states": self.resent_states, "duplicates": self.duplicates,
                "unexpected": self.unexpected, "resets": self.resets, "reordered": self.reordered,
                "silent": self.silent,
                "discarded": dict(self.discarded), "board_errors": dict(self.board_errors)}


@dataclass
class RunResult:
    """RESULT payloads of the answered states, the answered mask, wire statistics and timing."""

    payloads: np.ndarray  # (n, result octets) uint8; rows of unanswered states are zero
    answered: np.ndarray  # bool (n,)
    stats: RunStats
    wall_s: float
    octets_out: int
    octets_in: int
    given_up: np.ndarray | None = None  # bool (n,): sent, never answered, given up (None: every unanswered one)
    failure: str | None = None  # the link error or Ctrl-C that ended the run early

    @property
    def lost(self) -> list[int]:
        """Indices of the states given up on (retries spent, the board silent)."""
        mask = ~self.answered if self.given_up is None else self.given_up & ~self.answered
        return [int(i) for i in np.flatnonzero(mask)]

    @property
    def unanswered(self) -> list[int]:
        """Indices of the states without a RESULT: the lost ones and, after a failure, those never run."""
        return [int(i) for i in np.flatnonzero(~self.answered)]


@dataclass
class _Unit:
    """One request frame in flight."""

    seq0: int
    idxs: list[int]
    sent_s: float
    octets: int
    remaining: set[int]


#: called with (states done so far, mismatches so far, cycles of the answered states so far)
Tick = Callable[[int, int, list[int]], None]


class Session:
    """One board behind one link."""

    def __init__(self, link: Link, schema: Schema, *, timeout_s: float = 0.5, retries: int = 3, batch: int = 16,
                 window_octets: int = 2048, silence_s: float | None = None) -> None:
        self.link = link
        self.schema = schema
        self.timeout_s = timeout_s
        self.retries = retries
        self.batch = max(1, min(batch, schema.max_batch))
        self.window_octets = window_octets
        self.silence_s = silence_s if silence_s is not None else timeout_s * (retries + 1)
        self.decoder = FrameDecoder()
        self.info: BoardInfo | None = None
        self.handshake_retries = 0  # HELLOs sent again: no valid INFO within timeout_s
        self.handshake_discarded: Counter[str] = Counter()  # frames discarded during handshakes, by reason
        self.failure: str | None = None  # set when the link failed or the user interrupted: no run after it
        self._seq = 1

    # ------------------------------------------------------------ handshake
    def check(self, info: BoardInfo) -> None:
        """Raise BoardMismatch unless ``info`` matches this run's protocol, schema and config."""
        s = self.schema
        if info.protocol_version != PROTOCOL_VERSION:
            raise BoardMismatch(f"board {info.target!r} speaks protocol version {info.protocol_version}, "
                                f"the harness {PROTOCOL_VERSION}")
        if info.schema_hash != s.schema_hash or info.config_hash != s.config_hash:
            raise BoardMismatch(f"board {info.target!r} was built for config {info.config_hash} (schema "
                                f"{info.schema_hash}), this run is config {s.config_hash} (schema {s.schema_hash}): "
                                f"build the board from the same config")

    def _next_seq(self, n: int = 1) -> int:
        seq = self._seq
        self._seq = (self._seq + n) & 0xFFFF
        return seq

    def adopt_info(self, payload: bytes) -> bool:
        """An INFO the board sent unasked (it reset): parsed, checked against this run's hashes
        (:class:`BoardMismatch` if another build answers) and kept; False when its layout is not this
        protocol's (the caller counts a discarded frame)."""
        try:
            info = parse_info(self.schema, payload)
        except ProtocolError:
            return False
        self.check(info)
        self.info = info
        return True

    def handshake(self, attempts: int = 5) -> BoardInfo:
        """HELLO until INFO answers it; the board's INFO, checked against this run's hashes."""
        for attempt in range(attempts):
            if attempt:
                self.handshake_retries += 1
            seq = self._next_seq()
            self.link.write(encode_frame(Msg.HELLO, seq))
            deadline = time.perf_counter() + self.timeout_s
            while time.perf_counter() < deadline:
                self.link.wait(0.01)
                for item in self.decoder.feed(self.link.read_waiting()):
                    if isinstance(item, Discarded):
                        self.handshake_discarded[item.reason] += 1
                    elif item.type == Msg.INFO and item.seq == seq:
                        try:
                            info = parse_info(self.schema, item.payload)
                        except ProtocolError as exc:
                            raise BoardMismatch(f"the board's INFO does not have this protocol's layout ({exc}): "
                                                f"it speaks another protocol version") from None
                        self.check(info)
                        self.info = info
                        return info
        garbage = sum(self.handshake_discarded.values())
        heard = (f"; {garbage} undecodable chunk(s) arrived ({', '.join(sorted(self.handshake_discarded))}): "
                 "something is talking, at another baud rate or another protocol? check --baud"
                 if garbage else "; nothing at all arrived")
        raise BoardSilent(f"no INFO after {attempts} HELLOs ({self.timeout_s:g} s each){heard}: is a board built "
                          f"with the serial protocol on this port?")

    # ------------------------------------------------------------ replay
    def run(self, states: np.ndarray, expected: np.ndarray | None = None, tick: Tick | None = None) -> RunResult:
        """Every state through the board; ``expected``: packed reference outputs (live mismatch count).

        A link failure or Ctrl-C ends the run early: the result keeps what was answered and names it."""
        s = self.schema
        n = len(states)
        rh = s.result_head.packed_dtype.itemsize
        width = s.result_octets
        payloads = np.zeros((n, width), np.uint8)
        answered = np.zeros(n, bool)
        lost = np.zeros(n, bool)
        attempts = np.zeros(n, np.int64)
        cycles: list[int] = []
        stats = RunStats()
        mismatches = 0
        pending: deque[int] = deque(range(n))
        inflight: OrderedDict[int, _Unit] = OrderedDict()
        owner: dict[int, tuple[int, int, int]] = {}  # seq -> (state, unit seq0, send order)
        unit_of: dict[int, int] = {}  # state -> seq0 of its unit in flight
        in_flight_octets = 0
        done = 0
        sent_order = 0  # states sent so far (resends included): the order RESULTs should come back in
        last_taken = -1  # send order of the latest RESULT taken
        t0 = time.perf_counter()
        out0, in0 = self.link.octets_out, self.link.octets_in
        last_rx = t0

        def requeue(unit: _Unit, count_attempt: bool = True) -> None:
            nonlocal in_flight_octets, done
            inflight.pop(unit.seq0, None)
            in_flight_octets -= unit.octets
            back = []
            for idx in unit.idxs:
                if idx not in unit.remaining or answered[idx]:
                    continue
                unit_of.pop(idx, None)
                if count_attempt:
                    attempts[idx] += 1
                if attempts[idx] > self.retries:
                    lost[idx] = True
                    done += 1
                else:
                    back.append(idx)
                    stats.resent_states += 1
            pending.extendleft(reversed(back))

        def take_result(item: Frame) -> None:
            nonlocal done, mismatches, last_taken
            hit = owner.get(item.seq)
            if hit is None:
                stats.unexpected += 1
                return
            idx = hit[0]
            if answered[idx] or lost[idx]:
                stats.duplicates += 1
                return
            if len(item.payload) != width:
                stats.discarded["length"] += 1
                return
            row = np.frombuffer(item.payload, np.uint8)
            payloads[idx] = row
            answered[idx] = True
            done += 1
            if hit[2] < last_taken:
                stats.reordered += 1
            last_taken = max(last_taken, hit[2])
            cycles.append(int.from_bytes(item.payload[:4], "little", signed=True))
            if expected is not None and not np.array_equal(row[rh:], expected[idx]):
                mismatches += 1
            sender = hit[1]
            if sender in inflight:  # answered in order: what older frames still miss was lost
                older = []
                for k, u in inflight.items():
                    if k == sender:
                        break
                    older.append(u)
                for u in older:
                    requeue(u)
            cur = unit_of.pop(idx, None)
            if cur is not None and cur in inflight:
                unit = inflight[cur]
                unit.remaining.discard(idx)
                if not unit.remaining:
                    requeue(unit)

        def send() -> None:
            nonlocal in_flight_octets, sent_order
            now = time.perf_counter()
            while pending and in_flight_octets < self.window_octets:
                idxs: list[int] = []
                while pending and len(idxs) < self.batch:
                    i = pending.popleft()
                    if not answered[i] and not lost[i]:
                        idxs.append(i)
                if not idxs:
                    break
                seq0 = self._next_seq(len(idxs))
                if len(idxs) == 1:
                    frame = encode_frame(Msg.STEP, seq0, step_payload(s, states[idxs[0]:idxs[0] + 1]))
                else:
                    frame = encode_frame(Msg.BATCH, seq0, batch_payload(s, states[idxs]))
                if inflight and in_flight_octets + len(frame) > self.window_octets:
                    pending.extendleft(reversed(idxs))
                    self._seq = seq0
                    break
                unit = _Unit(seq0, idxs, now, len(frame), set(idxs))
                inflight[seq0] = unit  # in flight before the write: a failing write leaves it unanswered
                in_flight_octets += len(frame)
                for k, idx in enumerate(idxs):
                    owner[(seq0 + k) & 0xFFFF] = (idx, seq0, sent_order)
                    sent_order += 1
                    unit_of[idx] = seq0
                self.link.write(frame)
                stats.frames_sent += 1

        def receive() -> None:
            nonlocal last_rx
            data = self.link.read_waiting()
            if not data:
                self.link.wait(0.002)
                data = self.link.read_waiting()
            for item in self.decoder.feed(data):
                if isinstance(item, Discarded):
                    stats.discarded[item.reason] += 1
                    continue
                last_rx = time.perf_counter()
                if item.type == Msg.RESULT:
                    take_result(item)
                elif item.type == Msg.INFO:
                    stats.resets += 1
                    if not self.adopt_info(item.payload):
                        stats.discarded["length"] += 1
                        continue
                    for unit in list(inflight.values()):
                        requeue(unit)
                elif item.type == Msg.ERROR:
                    try:
                        stats.board_errors[parse_error(s, item.payload).name] += 1
                    except ProtocolError:
                        stats.discarded["length"] += 1
                # PONG and anything else: ignored

        failure = self.failure
        try:
            while failure is None and done < n:
                send()
                receive()
                now = time.perf_counter()
                for unit in [u for u in inflight.values() if now - u.sent_s > self.timeout_s]:
                    requeue(unit)
                if inflight and now - last_rx > self.silence_s:
                    stats.silent = True
                    left = ~answered & ~lost
                    done += int(left.sum())
                    lost |= left
                    inflight.clear()
                    break
                if tick is not None:
                    tick(done, mismatches, cycles)
                if not inflight and not pending and done < n:  # nothing left to send: the rest was lost
                    break
        except LinkError as exc:
            failure = str(exc)
        except KeyboardInterrupt:
            failure = INTERRUPTED
        self.failure = failure
        return RunResult(payloads, answered, stats, time.perf_counter() - t0,
                         self.link.octets_out - out0, self.link.octets_in - in0, lost, failure)
