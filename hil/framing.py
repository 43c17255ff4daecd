"""Frames on the wire: head (type, seq), payload, CRC-32, COBS-encoded between 0x00 delimiters.

:func:`encode_frame` gives the octets to send (a leading and a trailing
delimiter).  :class:`FrameDecoder` takes whatever arrived, in any pieces, and
returns each complete frame or the reason it was discarded: oversize input is
skipped up to the next delimiter, a malformed COBS block, a short frame or a
CRC mismatch is reported and dropped.  Empty chunks (two delimiters in a row)
are ignored.
"""
from __future__ import annotations

import struct
from dataclasses import dataclass

from cobs import cobs

from .crc32 import crc32
from .schema import CRC_OCTETS, HEAD_OCTETS, MAX_FRAME

__all__ = ["Frame", "Discarded", "encode_frame", "decode_frame", "FrameDecoder", "max_encoded"]

_HEAD = struct.Struct("<HH")
_CRC = struct.Struct("<I")


@dataclass(frozen=True)
class Frame:
    """One received frame whose CRC matched."""

    type: int
    seq: int
    payload: bytes


@dataclass(frozen=True)
class Discarded:
    """Input dropped between delimiters, and why ("cobs", "short", "crc", "oversize")."""

    reason: str
    octets: int


def max_encoded(n: int = MAX_FRAME) -> int:
    """Most COBS octets of an ``n``-octet frame (without delimiters)."""
    return n + n // 254 + 1


def encode_frame(msg_type: int, seq: int, payload: bytes = b"") -> bytes:
    """The wire octets of one frame: 0x00, COBS(head, payload, CRC), 0x00."""
    body = _HEAD.pack(int(msg_type), seq & 0xFFFF) + bytes(payload)
    if len(body) + CRC_OCTETS > MAX_FRAME:
        raise ValueError(f"frame of {len(body) + CRC_OCTETS} octets exceeds MAX_FRAME = {MAX_FRAME}")
    return b"\x00" + cobs.encode(body + _CRC.pack(crc32(body))) + b"\x00"


def decode_frame(chunk: bytes) -> Frame | Discarded:
    """One frame from the octets between two delimiters."""
    try:
        raw = cobs.decode(chunk)
    except cobs.DecodeError:
        return Discarded("cobs", len(chunk))
    if len(raw) < HEAD_OCTETS + CRC_OCTETS:
        return Discarded("short", len(chunk))
    if len(raw) > MAX_FRAME:  # fits the receive buffer (COBS overhead) yet longer than a frame may be
        return Discarded("oversize", len(chunk))
    body, (want,) = raw[:-CRC_OCTETS], _CRC.unpack(raw[-CRC_OCTETS:])
    if crc32(body) != want:
        return Discarded("crc", len(chunk))
    msg_type, seq = _HEAD.unpack_from(body)
    return Frame(msg_type, seq, body[HEAD_OCTETS:])


class FrameDecoder:
    """Reassembles frames from a byte stream with a bounded buffer."""

    def __init__(self, max_frame: int = MAX_FRAME) -> None:
        self.limit = max_encoded(max_frame)
        self._buf = bytearray()
        self._oversize = 0  # octets skipped of an oversize chunk (0: not skipping)

    def feed(self, data: bytes) -> list[Frame | Discarded]:
        """Frames (and discarded chunks) completed by ``data``."""
        out: list[Frame | Discarded] = []
        start = 0
        while True:
            end = data.find(b"\x00", start)
            piece = data[start:] if end < 0 else data[start:end]
            if self._oversize:
                self._oversize += len(piece)
            elif len(self._buf) + len(piece) > self.limit:
                self._oversize = len(self._buf) + len(piece)
                self._buf.clear()
            else:
                self._buf += piece
            if end < 0:
                return out
            if self._oversize:
                out.append(Discarded("oversize", self._oversize))
                self._oversize = 0
            elif self._buf:
                out.append(decode_frame(bytes(self._buf)))
                self._buf.clear()
            start = end + 1
