"""Payloads of every message, packed and unpacked through the schema's records."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .schema import (
    MAX_FRAME,
    MAX_STEPS,
    PROTOCOL_VERSION,
    TELEMETRY_SAMPLES,
    Err,
    Schema,
    hash_words,
    text_words,
    words_hash,
    words_text,
)

__all__ = ["BoardInfo", "ErrorReport", "info_payload", "parse_info", "batch_payload", "step_payload",
           "error_payload", "parse_error", "split_results", "ProtocolError", "Setpoints", "setpoints_payload",
           "parse_setpoints", "telemetry_frames", "telemetry_payload", "parse_telemetry", "run_end_payload",
           "parse_run_end", "RunEnd", "SEQ_UNKNOWN"]

#: seq of an ERROR whose frame's seq is unknown (CRC, COBS, SHORT, OVERSIZE: the head is not trusted)
SEQ_UNKNOWN = 0xFFFF


class ProtocolError(Exception):
    """A payload does not have the layout its type says."""


@dataclass(frozen=True)
class BoardInfo:
    """What a board says about itself (INFO)."""

    protocol_version: int
    schema_hash: str
    config_hash: str
    core_clock_hz: int
    overhead_cycles: int
    max_batch: int
    max_frame: int
    target: str
    number_format: str
    cycle_unit: str

    def as_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


@dataclass(frozen=True)
class ErrorReport:
    """An ERROR message."""

    code: int
    seq: int
    detail: int

    @property
    def name(self) -> str:
        try:
            return Err(self.code).name
        except ValueError:
            return f"code{self.code}"


def _one(schema: Schema, layout_name: str, payload: bytes) -> np.void:
    lay = getattr(schema, layout_name)
    if len(payload) != lay.packed_dtype.itemsize:
        raise ProtocolError(f"{lay.record.name}: {len(payload)} octets, expected {lay.packed_dtype.itemsize}")
    return lay.unpack(payload)[0]


def info_payload(schema: Schema, target: str, *, clock_hz: int = 0, overhead: int = 0, cycle_unit: str = "ns",
                 schema_hash: str | None = None, config_hash: str | None = None) -> bytes:
    """An INFO payload (what the firmware sends; tests and simulated boards use it)."""
    rec = schema.info.zeros(1)
    rec["protocol_version"] = PROTOCOL_VERSION
    rec["schema_hash"] = hash_words(schema_hash or schema.schema_hash)
    rec["config_hash"] = hash_words(config_hash or schema.config_hash)
    rec["core_clock_hz"], rec["overhead_cycles"] = clock_hz, overhead
    rec["max_batch"], rec["max_frame"] = schema.max_batch, MAX_FRAME
    rec["target"] = text_words(target, 16)
    rec["number_format"] = text_words(schema.number_format, 8)
    rec["cycle_unit"] = text_words(cycle_unit, 16)
    return schema.info.pack(rec).tobytes()


def parse_info(schema: Schema, payload: bytes) -> BoardInfo:
    """The board's INFO."""
    r = _one(schema, "info", payload)
    return BoardInfo(int(r["protocol_version"]), words_hash(list(r["schema_hash"])),
                     words_hash(list(r["config_hash"])), int(r["core_clock_hz"]), int(r["overhead_cycles"]),
                     int(r["max_batch"]), int(r["max_frame"]), words_text(list(r["target"])),
                     words_text(list(r["number_format"])), words_text(list(r["cycle_unit"])))


def error_payload(schema: Schema, code: int, seq: int, detail: int) -> bytes:
    """An ERROR payload (what the firmware sends; tests and simulated boards use it)."""
    rec = schema.error.zeros(1)
    rec["code"], rec["seq"], rec["detail"] = code, seq & 0xFFFF, detail & 0xFFFF
    return schema.error.pack(rec).tobytes()


def parse_error(schema: Schema, payload: bytes) -> ErrorReport:
    """An ERROR message's record."""
    r = _one(schema, "error", payload)
    return ErrorReport(int(r["code"]), int(r["seq"]), int(r["detail"]))


def step_payload(schema: Schema, state: np.ndarray) -> bytes:
    """A STEP payload: one input record (a length-1 array)."""
    return schema.input.pack(state).tobytes()


def batch_payload(schema: Schema, states: np.ndarray) -> bytes:
    """A BATCH payload: count, then the input records."""
    head = schema.batch_head.zeros(1)
    head["count"] = len(states)
    return schema.batch_head.pack(head).tobytes() + schema.input.pack(states).tobytes()


def split_results(schema: Schema, payloads: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(cycles, output records) from an (n, result_octets) uint8 array of RESULT payloads."""
    k = schema.result_head.packed_dtype.itemsize
    heads = np.ascontiguousarray(payloads[:, :k]).view(schema.result_head.packed_dtype).reshape(-1)
    outs = schema.output.unpack(np.ascontiguousarray(payloads[:, k:]).tobytes(), len(payloads))
    return heads["cycles"].astype(np.int64), outs


def telemetry_frames(samples: int) -> int:
    """TELEMETRY frames of a run of ``samples`` samples (frame i holds samples i*TELEMETRY_SAMPLES ...)."""
    return -(-samples // TELEMETRY_SAMPLES)


@dataclass(frozen=True)
class Setpoints:
    """A SETPOINTS message: run ``periods`` periods, a sample every ``decimation``, the profile ``steps``
    ((period index, mechanical speed reference rad/s, load N*m)), sending TELEMETRY frames
    ``frame_first`` .. ``frame_first + frame_count - 1``."""

    periods: int
    decimation: int
    steps: list[tuple[int, float, float]]
    frame_first: int
    frame_count: int


def setpoints_payload(schema: Schema, periods: int, decimation: int, steps: list[tuple[int, float, float]],
                      frame_first: int = 0, frame_count: int | None = None) -> bytes:
    """A SETPOINTS payload: run ``periods`` periods, a sample every ``decimation``; ``steps``: (period index,
    mechanical speed reference rad/s, load N*m), the first at period 0, increasing, at most MAX_STEPS;
    the TELEMETRY frames ``frame_first`` .. ``frame_first + frame_count - 1`` sent (default: every frame)."""
    if not 1 <= len(steps) <= MAX_STEPS:
        raise ValueError(f"{len(steps)} profile steps: the protocol takes 1 to {MAX_STEPS}")
    if frame_count is None:
        frame_count = telemetry_frames(-(-periods // decimation)) if periods > 0 and decimation > 0 else 0
    rec = schema.setpoints.zeros(1)
    rec["periods"], rec["decimation"], rec["n_steps"] = periods, decimation, len(steps)
    rec["frame_first"], rec["frame_count"] = frame_first, frame_count
    k = np.zeros(MAX_STEPS, np.int64)
    w = np.zeros(MAX_STEPS)
    load = np.zeros(MAX_STEPS)
    for i, (ki, wi, li) in enumerate(steps):
        k[i], w[i], load[i] = ki, wi, li
    rec["step_k"], rec["speed_rad_s"], rec["load_nm"] = k, w, load
    return schema.setpoints.pack(rec).tobytes()


def parse_setpoints(schema: Schema, payload: bytes) -> Setpoints:
    """A SETPOINTS message's record (its steps as many as ``n_steps`` says, at most MAX_STEPS)."""
    r = _one(schema, "setpoints", payload)
    n = min(int(r["n_steps"]), MAX_STEPS)
    steps = [(int(r["step_k"][i]), float(r["speed_rad_s"][i]), float(r["load_nm"][i])) for i in range(n)]
    return Setpoints(int(r["periods"]), int(r["decimation"]), steps, int(r["frame_first"]), int(r["frame_count"]))


def telemetry_payload(schema: Schema, samples: np.ndarray) -> bytes:
    """A TELEMETRY payload: count, then the samples (a record array of ``schema.sample``; 1 to
    TELEMETRY_SAMPLES of them; what the firmware sends, tests and simulated boards use it)."""
    if not 1 <= len(samples) <= TELEMETRY_SAMPLES:
        raise ValueError(f"{len(samples)} samples: a TELEMETRY frame holds 1 to {TELEMETRY_SAMPLES}")
    head = schema.telemetry_head.zeros(1)
    head["count"] = len(samples)
    return schema.telemetry_head.pack(head).tobytes() + schema.sample.pack(samples).tobytes()


def parse_telemetry(schema: Schema, payload: bytes) -> np.ndarray:
    """The samples of a TELEMETRY payload (a record array of ``schema.sample``, 1 to TELEMETRY_SAMPLES)."""
    k = schema.telemetry_head.packed_dtype.itemsize
    w = schema.sample.packed_dtype.itemsize
    if len(payload) < k:
        raise ProtocolError(f"TELEMETRY: {len(payload)} octets")
    count = int.from_bytes(payload[:2], "little")
    if not 1 <= count <= TELEMETRY_SAMPLES:
        raise ProtocolError(f"TELEMETRY: {count} samples, a frame holds 1 to {TELEMETRY_SAMPLES}")
    if len(payload) != k + count * w:
        raise ProtocolError(f"TELEMETRY: {len(payload)} octets for {count} samples, expected {k + count * w}")
    return schema.sample.unpack(payload[k:], count)


@dataclass(frozen=True)
class RunEnd:
    """The end of an on-board run (RUN_END)."""

    periods: int
    samples: int
    status: int
    changes: int
    cycles_min: int
    cycles_max: int
    cycles_sum: int
    hist: list[int]
    hist_width: int


def run_end_payload(schema: Schema, end: RunEnd) -> bytes:
    """A RUN_END payload (what the firmware sends; tests and simulated boards use it)."""
    rec = schema.run_end.zeros(1)
    for name in ("periods", "samples", "status", "changes", "cycles_min", "cycles_max", "hist_width"):
        rec[name] = getattr(end, name)
    rec["cycles_sum"] = [(end.cycles_sum >> (16 * i)) & 0xFFFF for i in range(4)]
    rec["hist"] = end.hist
    return schema.run_end.pack(rec).tobytes()


def parse_run_end(schema: Schema, payload: bytes) -> RunEnd:
    """A RUN_END message's record."""
    r = _one(schema, "run_end", payload)
    return RunEnd(int(r["periods"]), int(r["samples"]), int(r["status"]), int(r["changes"]),
                  int(r["cycles_min"]), int(r["cycles_max"]),
                  sum(int(x) << (16 * i) for i, x in enumerate(r["cycles_sum"])),
                  [int(x) for x in r["hist"]], int(r["hist_width"]))
