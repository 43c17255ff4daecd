"""Simulated boards in Python for the harness's wire tests (no build, no terminal, no timing).

:class:`FakeBoard` speaks the serial protocol as firmware/runtime/hil_proto.c
does: a frame that fails COBS, length or CRC is answered with ERROR (seq
0xFFFF), HELLO and RESET with INFO, STEP and BATCH with one RESULT per state
(its output octets a hash of the input record's, so that any corrupted
answer taken as a result shows), SETPOINTS with a deterministic on-board
run: TELEMETRY frame i (seq + 1 + i) for the frames of the SETPOINTS' window
(sample values a function of the period index, :func:`sample_values`), then
RUN_END.  ``inject`` holds octets to hand out, one item per read, before what
the board sends (garbage, foreign frames).  It is a :class:`hil.link.Link`,
so :class:`hil.faults.FaultLink` can wrap it.
"""
from __future__ import annotations

import hashlib
from collections import deque

import numpy as np

from hil.framing import Discarded, FrameDecoder, encode_frame
from hil.messages import (
    SEQ_UNKNOWN,
    ProtocolError,
    RunEnd,
    error_payload,
    info_payload,
    parse_setpoints,
    run_end_payload,
    telemetry_payload,
)
from hil.schema import MAX_BATCH, MAX_STEPS, TELEMETRY_SAMPLES, Err, Msg, Schema

#: ERROR code of a frame the decoder discarded
DISCARD_CODE = {"cobs": Err.COBS, "short": Err.SHORT, "crc": Err.CRC, "oversize": Err.OVERSIZE}
#: cycles every RESULT reports
CYCLES = 42


def result_output(schema: Schema, input_octets: bytes) -> bytes:
    """The output octets the fake controller answers an input record with."""
    return hashlib.shake_128(input_octets).digest(schema.output_octets)


def sample_values(schema: Schema, ks: np.ndarray) -> np.ndarray:
    """The samples of the fake on-board run at period indices ``ks`` (a record array of ``schema.sample``)."""
    rec = schema.sample.zeros(len(ks))
    rec["k"] = ks
    for j, name in enumerate(("omega_m_rad_s", "te_nm", "torque_ref_nm", "ia_a", "ib_a")):
        rec[name] = np.sin(0.001 * ks * (j + 1)).astype(np.float32)
    rec[schema.decision_field] = ks % 7
    rec["fault"] = 0
    return rec


class FakeBoard:
    """A protocol board in Python (see the module doc); ``periods_run``: an on-board run stops there
    (status -2), as a diverging plant does."""

    def __init__(self, schema: Schema, *, periods_run: int | None = None) -> None:
        self.schema = schema
        self.periods_run = periods_run
        self.octets_out = 0
        self.octets_in = 0
        self.inject: deque[bytes] = deque()
        self.runs = 0  # on-board runs done
        self._dec = FrameDecoder()
        self._out = bytearray()

    # ------------------------------------------------------------------ Link
    def write(self, data: bytes) -> None:
        self.octets_out += len(data)
        for item in self._dec.feed(data):
            if isinstance(item, Discarded):
                self._error(DISCARD_CODE[item.reason], SEQ_UNKNOWN, item.octets)
            else:
                self._handle(item.type, item.seq, item.payload)

    def read_waiting(self) -> bytes:
        data = (self.inject.popleft() if self.inject else b"") + bytes(self._out)
        self._out.clear()
        self.octets_in += len(data)
        return data

    def wait(self, timeout_s: float) -> None:
        pass

    def close(self) -> None:
        pass

    # ------------------------------------------------------------------ board
    def _send(self, msg: int, seq: int, payload: bytes = b"") -> None:
        self._out += encode_frame(msg, seq, payload)

    def _error(self, code: int, seq: int, detail: int) -> None:
        self._send(Msg.ERROR, seq, error_payload(self.schema, code, seq, detail))

    def _handle(self, msg: int, seq: int, p: bytes) -> None:
        s = self.schema
        if msg in (Msg.HELLO, Msg.RESET):
            self._send(Msg.INFO, seq, info_payload(s, "fake"))
        elif msg == Msg.PING:
            self._send(Msg.PONG, seq, p)
        elif msg == Msg.STEP:
            if len(p) != s.input_octets:
                self._error(Err.LENGTH, seq, len(p))
            else:
                self._result(seq, p)
        elif msg == Msg.BATCH:
            count = int.from_bytes(p[:2], "little") if len(p) >= 2 else -1
            if count < 0:
                self._error(Err.LENGTH, seq, len(p))
            elif not 1 <= count <= min(MAX_BATCH, s.max_batch):
                self._error(Err.BATCH, seq, count)
            elif len(p) != 2 + count * s.input_octets:
                self._error(Err.LENGTH, seq, len(p))
            else:
                for i in range(count):
                    self._result(seq + i, p[2 + i * s.input_octets:2 + (i + 1) * s.input_octets])
        elif msg == Msg.SETPOINTS:
            self._setpoints(seq, p)
        else:
            self._error(Err.TYPE, seq, msg)

    def _result(self, seq: int, input_octets: bytes) -> None:
        self._send(Msg.RESULT, seq, CYCLES.to_bytes(4, "little") + result_output(self.schema, input_octets))

    def _setpoints(self, seq: int, p: bytes) -> None:
        s = self.schema
        try:
            sp = parse_setpoints(s, p)
        except ProtocolError:
            self._error(Err.LENGTH, seq, len(p))
            return
        ks = [k for k, _, _ in sp.steps]
        bad = (1 if sp.periods < 1 else 2 if sp.decimation < 1 else 3 if not 1 <= len(sp.steps) <= MAX_STEPS
               else 4 if ks[0] != 0 or any(b <= a for a, b in zip(ks, ks[1:]))
               else 5 if sp.frame_first < 0 or sp.frame_count < 0 else 0)
        if bad:
            self._error(Err.SETPOINTS, seq, bad)
            return
        self.runs += 1
        periods = sp.periods if self.periods_run is None else min(sp.periods, self.periods_run)
        ks_all = np.arange(0, periods, sp.decimation, dtype=np.int64)
        for idx in range(sp.frame_first, min(sp.frame_first + sp.frame_count,
                                             -(-len(ks_all) // TELEMETRY_SAMPLES))):
            block = ks_all[idx * TELEMETRY_SAMPLES:(idx + 1) * TELEMETRY_SAMPLES]
            self._send(Msg.TELEMETRY, (seq + 1 + idx) & 0xFFFF, telemetry_payload(s, sample_values(s, block)))
        end = RunEnd(periods, len(ks_all), 0 if periods == sp.periods else -2, periods // 3, 1, 9, 5 * periods,
                     [periods] + [0] * 7, 16)
        self._send(Msg.RUN_END, seq, run_end_payload(s, end))
