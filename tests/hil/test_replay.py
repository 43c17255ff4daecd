"""Replay on the board (virtual unless --hil-port): every state of every source, bit for bit."""
from __future__ import annotations

import pytest
from hil_support import CASE_IDS, CASES, example

from hil.framing import Frame, encode_frame
from hil.progress import timing_prefix
from hil.replay import replay
from hil.schema import Msg, Schema
from hil.session import Session
from hil.states import replay_states

pytestmark = pytest.mark.board


@pytest.mark.parametrize("config,strategy", CASES, ids=CASE_IDS)
def test_replay_every_strategy_bit_for_bit(board, config, strategy):
    m, t = example(config, strategy)
    sets = replay_states(m, t, 6000)
    with board(m, t) as link:
        session = Session(link, Schema.of(m))
        session.handshake()
        data = replay(session, m, t, sets, show_progress=False)
    assert data["sources"] == {"closed_loop": 2000, "random": 2000, "adversarial": 2000}
    assert data["states"] == data["answered"] == 6000
    assert data["mismatches"] == 0 and data["lost"] == 0, data["first_mismatches"]
    assert data["wire"]["discarded"] == {} and data["wire"]["board_errors"] == {}
    t = timing_prefix(data["cycle_unit"])  # host_ns on the virtual board, cycles on silicon
    assert 0 <= data[f"{t}_min"] <= data[f"{t}_median"] <= data[f"{t}_p99"] <= data[f"{t}_max"]
    assert data["complete"] and data["wire"]["reordered"] == 0


@pytest.mark.parametrize("config,strategy", [("spmsm", "conventional"), ("spmsm", "s3"), ("tlevel", "mpdtc27")])
def test_replay_fixed_point_bit_for_bit(board, config, strategy):
    """Fixed point: int32 members on the wire, a schema of its own, every state bit for bit."""
    m, t = example(config, strategy, "fixed")
    schema = Schema.of(m)
    assert {f.ctype for f in schema.input.members + schema.output.members} <= {"int32_t", "uint16_t"}
    assert schema.number_format == "fixed"
    assert schema.schema_hash != Schema.of(example(config, strategy, "float32")[0]).schema_hash
    sets = replay_states(m, t, 3000)
    with board(m, t) as link:
        session = Session(link, schema)
        session.handshake()
        data = replay(session, m, t, sets, show_progress=False)
    assert data["states"] == data["answered"] == 3000
    assert data["mismatches"] == 0 and data["lost"] == 0, data["first_mismatches"]


def test_ping_echoes_cobs_edge_payloads(board):
    """PONG returns every payload unchanged: the C COBS decoder and encoder at block boundaries."""
    m, t = example("spmsm", "s1")
    payloads = [b"", b"\x00", b"\x00" * 7, b"\x01" * 253, b"\x01" * 254, b"\x01" * 255, b"\x07" * 254 + b"\x00",
                bytes(range(256)) * 3, b"\xff" * 1016]
    with board(m, t) as link:
        session = Session(link, Schema.of(m))
        session.handshake()
        for seq, p in enumerate(payloads, start=100):
            link.write(encode_frame(Msg.PING, seq, p))
        got: list = []
        for _ in range(200):
            link.wait(0.01)
            got += [x for x in session.decoder.feed(link.read_waiting()) if isinstance(x, Frame)]
            if len(got) >= len(payloads):
                break
    assert [(f.type, f.seq, f.payload) for f in got] == [(Msg.PONG, s, p) for s, p in enumerate(payloads, start=100)]


def test_board_rejects_bad_requests_with_coded_errors(board):
    m, t = example("spmsm", "s2")
    with board(m, t) as link:
        session = Session(link, Schema.of(m))
        session.handshake()
        link.write(encode_frame(Msg.STEP, 5, b"\x01\x02"))  # wrong length
        link.write(encode_frame(0x77, 6))  # unknown type
        link.write(encode_frame(Msg.BATCH, 7, b"\x00\x00"))  # empty batch
        link.write(b"\x00\x05\x01\x02\x00")  # COBS code past the end
        got: list = []
        for _ in range(200):
            link.wait(0.01)
            got += [x for x in session.decoder.feed(link.read_waiting()) if isinstance(x, Frame)]
            if len(got) >= 4:
                break
    from hil.messages import parse_error

    errs = [(parse_error(session.schema, f.payload).name, f.seq) for f in got if f.type == Msg.ERROR]
    assert errs == [("LENGTH", 5), ("TYPE", 6), ("BATCH", 7), ("COBS", 0xFFFF)]
