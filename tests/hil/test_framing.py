"""Frames: COBS + CRC-32 round trips, resynchronisation after garbage, every bad frame discarded."""
from __future__ import annotations

import random

import pytest

from hil import crc32
from hil.framing import Discarded, Frame, FrameDecoder, decode_frame, encode_frame
from hil.schema import MAX_FRAME, Msg


def _payloads() -> list[bytes]:
    rng = random.Random(3)
    out = [b"", b"\x00", b"\x00" * 300, b"\xff" * 253, b"\x01" * 254, b"\x02" * 255, b"\x00\x01" * 200]
    out += [bytes(rng.randrange(256) for _ in range(rng.randrange(0, MAX_FRAME - 8))) for _ in range(40)]
    return out


def test_crc_fast_path_is_the_crc_packages_crc32():
    crc32.check()
    assert crc32.crc32(b"123456789") == 0xCBF43926


@pytest.mark.parametrize("payload", _payloads(), ids=lambda p: f"{len(p)}")
def test_round_trip(payload):
    wire = encode_frame(Msg.PING, 0xBEEF, payload)
    assert wire[0] == 0 and wire[-1] == 0 and 0 not in wire[1:-1]
    assert FrameDecoder().feed(wire) == [Frame(Msg.PING, 0xBEEF, payload)]


def test_frames_split_anywhere_and_back_to_back():
    frames = [(Msg.STEP, i, bytes([i % 256]) * (i * 7 % 500)) for i in range(30)]
    wire = b"".join(encode_frame(*f) for f in frames)
    dec = FrameDecoder()
    rng = random.Random(1)
    got: list = []
    i = 0
    while i < len(wire):
        n = rng.randrange(1, 40)
        got += dec.feed(wire[i:i + n])
        i += n
    assert got == [Frame(*f) for f in frames]


def test_resynchronises_after_garbage():
    rng = random.Random(2)
    good = [encode_frame(Msg.RESULT, i, bytes(rng.randrange(256) for _ in range(80))) for i in range(20)]
    wire = b""
    for g in good:
        wire += bytes(rng.randrange(256) for _ in range(rng.randrange(1, 60))) + g
    items = FrameDecoder().feed(wire)
    frames = [x for x in items if isinstance(x, Frame)]
    assert [f.seq for f in frames] == list(range(20))
    assert all(isinstance(x, Discarded) for x in items if not isinstance(x, Frame))


def test_corrupted_truncated_short_and_oversize_frames_are_discarded():
    wire = encode_frame(Msg.RESULT, 7, bytes(range(1, 200)))
    body = bytearray(wire[1:-1])
    for k in range(len(body)):  # every single-octet corruption is caught
        bad = bytearray(body)
        bad[k] = (bad[k] ^ 0x21) or 0x01
        got = decode_frame(bytes(bad))
        assert isinstance(got, Discarded) and got.reason in ("crc", "cobs", "short"), k
    assert isinstance(decode_frame(bytes(body[: len(body) // 2])), Discarded)
    assert decode_frame(b"\x03\x01\x02") == Discarded("short", 3)
    dec = FrameDecoder()
    items = dec.feed(b"\x05" * (MAX_FRAME + 100) + b"\x00" + wire)
    assert items[0] == Discarded("oversize", MAX_FRAME + 100)
    assert items[1] == Frame(Msg.RESULT, 7, bytes(range(1, 200)))


def test_frames_above_the_limit_are_refused():
    with pytest.raises(ValueError, match="MAX_FRAME"):
        encode_frame(Msg.PING, 1, bytes(MAX_FRAME))
