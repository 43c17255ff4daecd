"""Property-based fuzzing of the harness's side of the wire (hypothesis): the frame decoder
(hil/framing.py), the payload parsers (hil/messages.py) and the session's frame handling
(hil/session.py, through its public API against the Python board of fake_boards.py).

Random and mutated input never raises anything but the documented protocol errors (a
:class:`hil.framing.Discarded` item, :class:`hil.messages.ProtocolError`, and for the handshake
:class:`hil.session.BoardMismatch` / :class:`hil.session.BoardSilent`); every round trip is exact;
nothing corrupted is ever taken as a result.  Derandomised (the same examples every run) and
bounded: a few seconds in all.
"""
from __future__ import annotations

import struct

import numpy as np
import pytest
from cobs import cobs
from fake_boards import CYCLES, FakeBoard, result_output
from hil_support import example
from hypothesis import given, settings
from hypothesis import strategies as st

from hil.crc32 import crc32
from hil.faults import Fault, FaultLink
from hil.framing import Discarded, Frame, FrameDecoder, decode_frame, encode_frame, max_encoded
from hil.messages import (
    ProtocolError,
    RunEnd,
    error_payload,
    info_payload,
    parse_error,
    parse_info,
    parse_run_end,
    parse_setpoints,
    parse_telemetry,
    run_end_payload,
    setpoints_payload,
    split_results,
    telemetry_payload,
)
from hil.schema import HEAD_OCTETS, MAX_FRAME, MAX_STEPS, TELEMETRY_SAMPLES, Msg, Schema
from hil.session import BoardMismatch, BoardSilent, Session

FUZZ = settings(max_examples=300, deadline=None, database=None, derandomize=True)
SLOW = settings(max_examples=60, deadline=None, database=None, derandomize=True)
#: most payload octets of a frame
MAX_PAYLOAD = MAX_FRAME - HEAD_OCTETS - 4
REASONS = {"cobs", "short", "crc", "oversize"}

u16 = st.integers(0, 0xFFFF)
i32 = st.integers(-2**31, 2**31 - 1)
payloads = st.binary(max_size=MAX_PAYLOAD)
frames = st.tuples(u16, u16, st.binary(max_size=300))


def _schema(case: str = "spmsm") -> Schema:
    m, _ = example(case, "s1" if case == "spmsm" else "mpdtc27")
    return Schema.of(m)


def _feed_in_pieces(dec: FrameDecoder, wire: bytes, cuts: list[int]) -> list[Frame | Discarded]:
    out: list[Frame | Discarded] = []
    prev = 0
    for c in sorted({c % (len(wire) + 1) for c in cuts}) + [len(wire)]:
        out += dec.feed(wire[prev:c])
        prev = c
    return out


def _documented(items: list[Frame | Discarded], empty: bool = False) -> None:
    for x in items:
        assert isinstance(x, (Frame, Discarded))
        if isinstance(x, Discarded):  # nothing between two delimiters is no frame, not a discarded one
            assert x.reason in REASONS and (x.octets > 0 or empty)
        else:
            assert 0 <= x.type <= 0xFFFF and 0 <= x.seq <= 0xFFFF and len(x.payload) <= MAX_PAYLOAD


# ---------------------------------------------------------------- framing
@FUZZ
@given(msg=u16, seq=st.integers(-2**20, 2**20), payload=payloads, cuts=st.lists(st.integers(0, 2000), max_size=8))
def test_frame_round_trip_in_any_pieces(msg, seq, payload, cuts):
    wire = encode_frame(msg, seq, payload)
    assert wire[0] == 0 == wire[-1] and 0 not in wire[1:-1] and len(wire) - 2 <= max_encoded()
    assert _feed_in_pieces(FrameDecoder(), wire, cuts) == [Frame(msg, seq & 0xFFFF, payload)]
    assert decode_frame(wire[1:-1]) == Frame(msg, seq & 0xFFFF, payload)


@FUZZ
@given(chunk=st.binary(max_size=2 * MAX_FRAME))
def test_any_chunk_decodes_to_a_frame_or_a_documented_discard(chunk):
    got = decode_frame(chunk)
    _documented([got], empty=not chunk)
    if isinstance(got, Frame):  # a valid frame: encoding it again gives the same frame
        assert decode_frame(encode_frame(got.type, got.seq, got.payload)[1:-1]) == got


@FUZZ
@given(data=st.lists(st.binary(max_size=1500) | st.sampled_from([b"\x00", b"\x00\x00", b"\xff" * 300]),
                     max_size=12))
def test_random_streams_never_raise_and_the_buffer_stays_bounded(data):
    dec = FrameDecoder()
    for piece in data:
        _documented(dec.feed(piece))
    tail = dec.feed(b"\x00")  # the delimiter ends whatever was pending
    _documented(tail)
    assert len(tail) <= 1 and dec.feed(b"") == []
    wire = encode_frame(Msg.PING, 5, b"abc")  # and the decoder is in step again
    assert dec.feed(wire) == [Frame(Msg.PING, 5, b"abc")]


@FUZZ
@given(msgs=st.lists(frames, min_size=1, max_size=6), garbage=st.lists(st.binary(max_size=1200), min_size=7,
                                                                      max_size=7),
       cuts=st.lists(st.integers(0, 10_000), max_size=10))
def test_frames_survive_any_garbage_between_them(msgs, garbage, cuts):
    wire = b"".join(g + encode_frame(*f) for g, f in zip(garbage, msgs)) + garbage[-1]
    items = _feed_in_pieces(FrameDecoder(), wire, cuts)
    _documented(items)
    assert [x for x in items if isinstance(x, Frame)] == [Frame(t, s, p) for t, s, p in msgs]


MUTATION = st.tuples(st.sampled_from(["flip", "set", "delete", "insert", "truncate", "repeat"]),
                     st.integers(0, 10_000), st.integers(0, 255), st.integers(1, 64))


def _mutate(wire: bytes, mutations: list[tuple[str, int, int, int]]) -> bytes:
    b = bytearray(wire)
    for kind, pos, value, n in mutations:
        k = pos % max(1, len(b))
        if kind == "flip" and b:
            b[k] ^= 1 << (value % 8)
        elif kind == "set" and b:
            b[k] = value
        elif kind == "delete":
            del b[k:k + n]
        elif kind == "insert":
            b[k:k] = bytes([value]) * n
        elif kind == "truncate":
            del b[k:]
        elif kind == "repeat":
            b[k:k] = b[k:k + n]
    return bytes(b)


@FUZZ
@given(f=frames, mutations=st.lists(MUTATION, min_size=1, max_size=4), cuts=st.lists(st.integers(0, 2000), max_size=4))
def test_mutated_frames_are_discarded_never_taken_changed(f, mutations, cuts):
    wire = encode_frame(*f)
    bad = _mutate(wire, mutations)
    items = _feed_in_pieces(FrameDecoder(), bad + b"\x00", cuts)
    _documented(items)
    # a frame that comes through is the one sent (a mutation that cancels out, or one of a repeated copy):
    # a changed frame never passes the CRC
    assert all(x == Frame(*f) for x in items if isinstance(x, Frame))


@FUZZ
@given(n=st.integers(MAX_PAYLOAD + 1, MAX_PAYLOAD + 600))
def test_oversize_payloads_are_refused_and_oversize_input_skipped(n):
    with pytest.raises(ValueError, match="MAX_FRAME"):
        encode_frame(Msg.PING, 1, bytes(n))
    dec = FrameDecoder()
    items = dec.feed(b"\x07" * (max_encoded() + n) + encode_frame(Msg.PING, 2, b"x"))
    assert items == [Discarded("oversize", max_encoded() + n), Frame(Msg.PING, 2, b"x")]


@FUZZ
@given(head=st.tuples(u16, u16), size=st.integers(MAX_PAYLOAD - 8, max_encoded()), fill=st.binary(max_size=64))
def test_no_frame_longer_than_max_frame_is_taken(head, size, fill):
    """Frames with a valid CRC of any length up to what the receive buffer holds (max_encoded octets):
    one longer than MAX_FRAME is discarded as oversize, as the firmware's decoder does."""
    body = struct.pack("<HH", *head) + (fill * (size // max(1, len(fill)) + 1) if fill else bytes(size))[:size]
    raw = body + struct.pack("<I", crc32(body))
    items = FrameDecoder().feed(b"\x00" + cobs.encode(raw) + b"\x00")
    _documented(items)
    assert len(items) == 1
    if len(raw) <= MAX_FRAME:
        assert items[0] == Frame(head[0], head[1], body[HEAD_OCTETS:])
    else:
        assert isinstance(items[0], Discarded) and items[0].reason == "oversize"


# ---------------------------------------------------------------- payload parsers
PARSERS = [parse_info, parse_error, parse_run_end, parse_setpoints, parse_telemetry]


@pytest.mark.parametrize("case", ["spmsm", "tlevel"])
@FUZZ
@given(payload=st.binary(max_size=MAX_PAYLOAD), which=st.sampled_from(PARSERS))
def test_parsers_take_any_payload_or_raise_protocol_error(case, payload, which):
    try:
        which(_schema(case), payload)
    except ProtocolError:
        pass


@FUZZ
@given(which=st.sampled_from(PARSERS), data=st.data())
def test_parsers_take_any_payload_of_the_right_length(which, data):
    s = _schema()
    size = {parse_info: s.info, parse_error: s.error, parse_run_end: s.run_end,
            parse_setpoints: s.setpoints}.get(which)
    if size is None:  # TELEMETRY: a count, then that many samples
        n = data.draw(st.integers(0, TELEMETRY_SAMPLES + 2))
        payload = n.to_bytes(2, "little") + data.draw(st.binary(min_size=n * s.sample.packed_dtype.itemsize,
                                                                max_size=n * s.sample.packed_dtype.itemsize))
        if not 1 <= n <= TELEMETRY_SAMPLES:
            with pytest.raises(ProtocolError):
                which(s, payload)
            return
    else:
        k = size.packed_dtype.itemsize
        payload = data.draw(st.binary(min_size=k, max_size=k))
    which(s, payload)  # any octets of the right length are a record


@FUZZ
@given(code=u16, seq=u16, detail=u16)
def test_error_round_trip(code, seq, detail):
    s = _schema()
    e = parse_error(s, error_payload(s, code, seq, detail))
    assert (e.code, e.seq, e.detail) == (code, seq, detail) and e.name


@FUZZ
@given(target=st.text(st.characters(min_codepoint=1, max_codepoint=127), max_size=16),
       unit=st.text(st.characters(min_codepoint=1, max_codepoint=127), max_size=16),
       clock=st.integers(0, 2**31 - 1), overhead=st.integers(0, 2**31 - 1),
       hashes=st.tuples(st.integers(0, 2**64 - 1), st.integers(0, 2**64 - 1)))
def test_info_round_trip(target, unit, clock, overhead, hashes):
    s = _schema()
    sh, ch = (f"{h:016x}" for h in hashes)
    info = parse_info(s, info_payload(s, target, clock_hz=clock, overhead=overhead, cycle_unit=unit,
                                      schema_hash=sh, config_hash=ch))
    assert (info.target, info.cycle_unit, info.core_clock_hz, info.overhead_cycles) == (target, unit, clock, overhead)
    assert (info.schema_hash, info.config_hash, info.number_format) == (sh, ch, s.number_format)


f32 = st.floats(width=32, allow_nan=False)


@FUZZ
@given(periods=i32, decimation=u16, steps=st.lists(st.tuples(i32, f32, f32), min_size=1, max_size=MAX_STEPS),
       first=i32, count=i32)
def test_setpoints_round_trip(periods, decimation, steps, first, count):
    s = _schema()
    sp = parse_setpoints(s, setpoints_payload(s, periods, decimation, steps, first, count))
    assert (sp.periods, sp.decimation, sp.frame_first, sp.frame_count) == (periods, decimation, first, count)
    assert sp.steps == [(k, float(np.float32(w)), float(np.float32(ld))) for k, w, ld in steps]


@pytest.mark.parametrize("case", ["spmsm", "tlevel"])
@FUZZ
@given(data=st.data())
def test_telemetry_round_trip_is_bit_exact(case, data):
    s = _schema(case)
    n = data.draw(st.integers(1, TELEMETRY_SAMPLES))
    w = s.sample.packed_dtype.itemsize
    octets = data.draw(st.binary(min_size=n * w, max_size=n * w))  # any bits: NaNs, infinities, negative zeros
    samples = s.sample.unpack(octets, n)
    payload = telemetry_payload(s, samples)
    assert payload[2:] == octets
    assert s.sample.pack(parse_telemetry(s, payload)).tobytes() == octets


@FUZZ
@given(v=st.tuples(i32, i32, i32, i32, i32, i32), total=st.integers(0, 2**64 - 1), hist=st.lists(i32, min_size=8,
                                                                                                max_size=8),
       width=i32)
def test_run_end_round_trip(v, total, hist, width):
    s = _schema()
    end = RunEnd(*v, total, hist, width)
    assert parse_run_end(s, run_end_payload(s, end)) == end


@FUZZ
@given(data=st.data())
def test_split_results_round_trip(data):
    s = _schema()
    n = data.draw(st.integers(0, 40))
    rows = data.draw(st.binary(min_size=n * s.result_octets, max_size=n * s.result_octets))
    payloads = np.frombuffer(rows, np.uint8).reshape(n, s.result_octets)
    cycles, outs = split_results(s, payloads)
    assert cycles.tolist() == np.frombuffer(payloads[:, :4].tobytes(), "<i4").tolist()
    assert s.output.pack(outs).tobytes() == payloads[:, 4:].tobytes()


# ---------------------------------------------------------------- the session, through its public API
FOREIGN = st.one_of(
    st.binary(min_size=1, max_size=300),  # garbage
    st.builds(lambda t, q, p: encode_frame(t, q, p),  # valid frames the run must ignore or refuse
              st.sampled_from([Msg.PONG, Msg.TELEMETRY, Msg.RUN_END, Msg.ERROR, Msg.HELLO, 77, Msg.INFO]),
              u16, st.binary(max_size=120)),
    st.builds(lambda q, p: encode_frame(Msg.RESULT, q, p), u16, st.binary(max_size=40)),  # RESULTs of bad length
)
REPLAY_FAULT = st.builds(Fault, st.sampled_from(["garbage", "corrupt", "truncate", "drop", "duplicate"]),
                         st.sampled_from(["in", "out"]), st.integers(0, 30)) | st.builds(
    Fault, st.just("reset"), st.just("out"), st.integers(0, 30))


def _is_info(octets: bytes) -> bool:
    items = FrameDecoder().feed(octets + b"\x00")
    return any(isinstance(x, Frame) and x.type == Msg.INFO for x in items)


def _states(s: Schema, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return s.input.unpack(rng.integers(1, 255, n * s.input_octets, dtype=np.uint8).tobytes(), n)


@SLOW
@given(n=st.integers(1, 70), seed=st.integers(0, 1000), batch=st.integers(1, 16),
       faults=st.lists(REPLAY_FAULT, max_size=6, unique_by=lambda f: (f.direction, f.frame)),
       foreign=st.lists(FOREIGN, max_size=8))
def test_session_run_takes_only_valid_results(n, seed, batch, faults, foreign):
    s = _schema()
    fake = FakeBoard(s)
    fake.inject.extend(foreign)
    session = Session(FaultLink(fake, faults), s, timeout_s=0.01, retries=4, batch=batch, silence_s=0.2)
    states = _states(s, n, seed)
    try:
        res = session.run(states)
    except BoardMismatch:  # a foreign INFO of the right length: the documented refusal of another board
        assert any(_is_info(f) for f in foreign)
        return
    packed = s.input.pack(states)
    for i in np.flatnonzero(res.answered):
        assert res.payloads[i].tobytes() == CYCLES.to_bytes(4, "little") + result_output(s, packed[i].tobytes())
    assert res.answered.sum() + len(res.lost) == n and not (set(res.lost) & set(np.flatnonzero(res.answered)))
    if not faults and not foreign:
        assert res.answered.all() and res.stats.resent_states == 0


@SLOW
@given(foreign=st.lists(FOREIGN, max_size=6), info_ok=st.booleans())
def test_handshake_takes_only_its_info(foreign, info_ok):
    s = _schema()
    fake = FakeBoard(s)
    fake.inject.extend(foreign)
    if not info_ok:
        fake.write = lambda data: None  # a board that never answers
    session = Session(fake, s, timeout_s=0.02)
    try:
        info = session.handshake(attempts=2)
    except BoardSilent:
        assert not info_ok
        return
    except BoardMismatch:  # only an INFO that answers the HELLO's seq and is not this config's
        assert any(_is_info(f) for f in foreign)
        return
    assert info_ok and info.target == "fake" and info.schema_hash == s.schema_hash
