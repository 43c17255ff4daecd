"""Payloads of every message, packed and unpacked through the schema's records."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .schema import MAX_FRAME, MAX_STEPS, PROTOCOL_VERSION, Err, Schema, hash_words, text_words, words_hash, words_text

__all__ = ["BoardInfo", "ErrorReport", "info_payload", "parse_info", "batch_payload", "step_payload",
           "parse_error", "split_results", "ProtocolError", "setpoints_payload", "parse_telemetry",
           "parse_run_end", "RunEnd"]


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


def setpoints_payload(schema: Schema, periods: int, decimation: int,
                      steps: list[tuple[int, float, float]]) -> bytes:
    """A SETPOINTS payload: run ``periods`` periods, a sample every ``decimation``; ``steps``: (period index,
    mechanical speed reference rad/s, load N*m), the first at period 0, increasing, at most MAX_STEPS."""
    if not 1 <= len(steps) <= MAX_STEPS:
        raise ValueError(f"{len(steps)} profile steps: the protocol takes 1 to {MAX_STEPS}")
    rec = schema.setpoints.zeros(1)
    rec["periods"], rec["decimation"], rec["n_steps"] = periods, decimation, len(steps)
    k = np.zeros(MAX_STEPS, np.int64)
    w = np.zeros(MAX_STEPS)
    load = np.zeros(MAX_STEPS)
    for i, (ki, wi, li) in enumerate(steps):
        k[i], w[i], load[i] = ki, wi, li
    rec["step_k"], rec["speed_rad_s"], rec["load_nm"] = k, w, load
    return schema.setpoints.pack(rec).tobytes()


def parse_telemetry(schema: Schema, payload: bytes) -> np.ndarray:
    """The samples of a TELEMETRY payload (a record array of ``schema.sample``)."""
    k = schema.telemetry_head.packed_dtype.itemsize
    w = schema.sample.packed_dtype.itemsize
    if len(payload) < k:
        raise ProtocolError(f"TELEMETRY: {len(payload)} octets")
    count = int.from_bytes(payload[:2], "little")
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


def parse_run_end(schema: Schema, payload: bytes) -> RunEnd:
    """A RUN_END message's record."""
    r = _one(schema, "run_end", payload)
    return RunEnd(int(r["periods"]), int(r["samples"]), int(r["status"]), int(r["changes"]),
                  int(r["cycles_min"]), int(r["cycles_max"]),
                  sum(int(x) << (16 * i) for i, x in enumerate(r["cycles_sum"])),
                  [int(x) for x in r["hist"]], int(r["hist_width"]))
