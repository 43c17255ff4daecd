"""A fault injector between the harness and a board: a Link that wraps the board's link.

Each :class:`Fault` hits one frame (counted per direction, from 0) of the
traffic to the board (``"out"``) or from it (``"in"``):

* ``garbage``: random octets (zeros included) before the frame;
* ``corrupt``: one octet inside the frame changed;
* ``truncate``: the frame cut to half its length (delimiter kept);
* ``drop``: the frame removed;
* ``duplicate``: the frame sent twice;
* ``reorder``: the frame held back and passed on after the next frame of its
  direction (two frames swapped);
* ``reset`` (``"out"`` only): a RESET sent to the board before the frame
  (the board restarts its protocol and announces INFO mid-run);
* ``silent``: from this frame on nothing passes either way.

Frames are cut at the 0x00 delimiters and re-emitted as ``0x00 frame 0x00``;
incoming octets are held back until their frame is complete.
"""
from __future__ import annotations

import random
from dataclasses import dataclass, field

from .framing import encode_frame
from .link import Link
from .schema import Msg

__all__ = ["Fault", "FaultLink", "KINDS"]

KINDS = ("garbage", "corrupt", "truncate", "drop", "duplicate", "reorder", "reset", "silent")


@dataclass(frozen=True)
class Fault:
    """One fault: its kind, direction ("out": to the board, "in": from it) and frame number."""

    kind: str
    direction: str
    frame: int

    def __post_init__(self) -> None:
        if self.kind not in KINDS or self.direction not in ("out", "in"):
            raise ValueError(f"bad fault {self}")
        if self.kind == "reset" and self.direction != "out":
            raise ValueError("a reset is sent to the board (direction 'out')")


@dataclass
class FaultLink:
    """``inner`` with ``faults`` applied; ``applied`` lists the faults that have happened."""

    inner: Link
    faults: list[Fault]
    seed: int = 7
    applied: list[Fault] = field(default_factory=list)

    def __post_init__(self) -> None:
        self._rng = random.Random(self.seed)
        self._count = {"out": 0, "in": 0}
        self._held = b""
        self._silent = False
        self._deferred: dict[str, list[bytes]] = {"out": [], "in": []}  # reordered frames, sent after the next

    @property
    def octets_out(self) -> int:
        return self.inner.octets_out

    @property
    def octets_in(self) -> int:
        return self.inner.octets_in

    def _apply(self, direction: str, data: bytes) -> bytes:
        out = bytearray()
        for chunk in data.split(b"\x00"):
            if not chunk:
                continue
            n = self._count[direction]
            self._count[direction] += 1
            frames = [chunk]
            defer = False
            for f in self.faults:
                if f.direction != direction or f.frame != n:
                    continue
                self.applied.append(f)
                if f.kind == "silent":
                    self._silent = True
                elif f.kind == "garbage":
                    out += bytes(self._rng.randrange(256) for _ in range(self._rng.randrange(5, 40)))
                elif not frames:  # dropped by an earlier fault on this frame: nothing left to alter
                    continue
                elif f.kind == "corrupt":
                    c = bytearray(frames[0])
                    k = self._rng.randrange(len(c))
                    c[k] = (c[k] ^ 0x5A) or 0x01
                    frames = [bytes(c)]
                elif f.kind == "truncate":
                    frames = [frames[0][:max(1, len(frames[0]) // 2)]]
                elif f.kind == "drop":
                    frames = []
                elif f.kind == "duplicate":
                    frames = frames * 2
                elif f.kind == "reorder":
                    defer = True
                elif f.kind == "reset":
                    out += encode_frame(Msg.RESET, 0xFFFE)
            if self._silent:
                return bytes(out)
            if defer:
                self._deferred[direction] += frames
                continue
            for fr in frames + self._deferred[direction]:
                out += b"\x00" + fr + b"\x00"
            self._deferred[direction] = []
        return bytes(out)

    def write(self, data: bytes) -> None:
        if self._silent:
            return
        data = self._apply("out", data)
        if data:
            self.inner.write(data)

    def read_waiting(self) -> bytes:
        data = self._held + self.inner.read_waiting()
        end = data.rfind(b"\x00")
        if end < 0:
            self._held = data
            return b""
        self._held = data[end + 1:]
        if self._silent:
            return b""
        return self._apply("in", data[:end + 1])

    def wait(self, timeout_s: float) -> None:
        self.inner.wait(timeout_s)

    def close(self) -> None:
        self.inner.close()
