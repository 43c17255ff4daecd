"""Faults between harness and board: each is detected and reported (in the JSON and on the summary line),
nothing corrupted is taken as a result, and every state is answered exactly once or listed as lost."""
from __future__ import annotations

import numpy as np
import pytest
from hil_support import example

from hil.faults import Fault, FaultLink
from hil.progress import timing_prefix
from hil.replay import replay, summary_line
from hil.schema import Schema
from hil.session import BoardMismatch, Session

pytestmark = pytest.mark.board

N = 400  # random states per run (25 frames of 16)


def _run(board, faults: list[Fault], **session_kw):
    m, t = example("spmsm", "conventional")
    from hil.states import replay_states

    sets = replay_states(m, t, N, sources=("random",))
    with board(m, t) as link:
        flink = FaultLink(link, faults)
        session = Session(flink, Schema.of(m), timeout_s=0.2, retries=3, **session_kw)
        session.handshake()
        data = replay(session, m, t, sets, show_progress=False)
    assert sorted(map(str, flink.applied)) == sorted(map(str, faults)), "a planned fault did not happen"
    # every fault leaves a trace on the console: the line of a clean run is never printed
    assert "  wire: " in summary_line(data), (faults, data["wire"])
    return data


def _all_answered_once(data) -> None:
    assert data["states"] == data["answered"] == N and data["lost"] == 0 and data["lost_states"] == []
    assert data["mismatches"] == 0, data["first_mismatches"]


@pytest.mark.parametrize("direction", ["out", "in"])
def test_garbage_between_frames(board, direction):
    data = _run(board, [Fault("garbage", direction, 3), Fault("garbage", direction, 9)])
    _all_answered_once(data)
    w = data["wire"]
    reported = sum(w["board_errors"].values()) if direction == "out" else sum(w["discarded"].values())
    assert reported >= 2, w


@pytest.mark.parametrize("direction", ["out", "in"])
def test_corrupted_octet_inside_a_frame(board, direction):
    data = _run(board, [Fault("corrupt", direction, 5)])
    _all_answered_once(data)
    w = data["wire"]
    if direction == "out":
        assert sum(w["board_errors"].values()) >= 1 and w["resent_states"] >= 1, w
    else:
        assert sum(w["discarded"].values()) == 1 and w["resent_states"] >= 1, w


@pytest.mark.parametrize("direction", ["out", "in"])
def test_truncated_frame(board, direction):
    data = _run(board, [Fault("truncate", direction, 4)])
    _all_answered_once(data)
    w = data["wire"]
    assert (sum(w["board_errors"].values()) if direction == "out" else sum(w["discarded"].values())) >= 1, w
    assert w["resent_states"] >= 1


@pytest.mark.parametrize("direction", ["out", "in"])
def test_dropped_frame(board, direction):
    data = _run(board, [Fault("drop", direction, 6)])
    _all_answered_once(data)
    assert data["wire"]["resent_states"] >= 1


@pytest.mark.parametrize("direction", ["out", "in"])
def test_duplicated_frame(board, direction):
    data = _run(board, [Fault("duplicate", direction, 2)])
    _all_answered_once(data)
    assert data["wire"]["duplicates"] >= 1


@pytest.mark.parametrize("direction", ["out", "in"])
def test_reordered_frames_are_counted(board, direction):
    """Two frames swapped: in, two RESULTs of one BATCH (the later taken first); out, two BATCHes (the
    board answers the later one first, the earlier one's states are sent again)."""
    data = _run(board, [Fault("reorder", direction, 5)])
    _all_answered_once(data)
    w = data["wire"]
    assert w["reordered"] >= 1, w
    assert "reordered" in summary_line(data)
    if direction == "out":
        assert w["resent_states"] >= 1


@pytest.mark.parametrize("kind,direction", [("drop", "in"), ("corrupt", "in"), ("drop", "out"), ("corrupt", "out")])
def test_handshake_retries_are_counted(board, kind, direction):
    """A lost or corrupted HELLO or INFO: the handshake says HELLO again, and the run counts it.  Towards
    the harness, frames 0 and 1 are hit: frame 0 is the INFO a board announces when it starts unless
    opening the port flushed it, then frame 1 answers the first HELLO (else frame 0 does, and frame 1 the
    second)."""
    frames = [0] if direction == "out" else [0, 1]
    data = _run(board, [Fault(kind, direction, k) for k in frames])
    _all_answered_once(data)
    retries = data["wire"]["handshake_retries"]
    assert retries >= 1, data["wire"]
    assert f"handshake retries {retries}" in summary_line(data)
    if kind == "corrupt" and direction == "in":
        assert sum(data["wire"]["discarded"].values()) >= 1


def test_board_reset_mid_run(board):
    data = _run(board, [Fault("reset", "out", 8)])
    _all_answered_once(data)
    assert data["wire"]["resets"] == 1


def test_board_goes_silent(board):
    data = _run(board, [Fault("silent", "in", 10)])
    w = data["wire"]
    assert w["silent"] and data["lost"] > 0 and data["mismatches"] == 0
    assert data["answered"] + data["lost"] == N
    lost = [s["index"] for s in data["lost_states"]]
    assert len(lost) == data["lost"] == len(set(lost)) and lost == sorted(lost) and lost[-1] == N - 1


def test_every_fault_in_one_run(board):
    faults = [Fault("garbage", "out", 2), Fault("corrupt", "in", 4), Fault("truncate", "out", 7),
              Fault("drop", "in", 11), Fault("duplicate", "out", 14), Fault("reset", "out", 18),
              Fault("corrupt", "out", 21), Fault("garbage", "in", 23)]
    data = _run(board, faults)
    _all_answered_once(data)
    assert data["wire"]["resets"] == 1


def test_board_built_from_another_config_is_refused(board):
    if board.port is not None:
        pytest.skip("needs the virtual board (a second image)")
    m, t = example("spmsm", "conventional")
    other, _ = example("spmsm", "s1")
    with board(m, t, image_model=other) as link:
        with pytest.raises(BoardMismatch) as exc:
            Session(link, Schema.of(m)).handshake()
    msg = str(exc.value)
    assert Schema.of(other).config_hash in msg and Schema.of(m).config_hash in msg
    assert Schema.of(other).schema_hash in msg and "build the board from the same config" in msg


def test_nothing_corrupted_is_a_match(board):
    """Corrupting every 3rd result frame: every answered output still equals the reference."""
    faults = [Fault("corrupt", "in", k) for k in range(1, 60, 3)]
    data = _run(board, faults)
    _all_answered_once(data)
    assert data["wire"]["discarded"].get("crc", 0) + data["wire"]["discarded"].get("cobs", 0) \
        + data["wire"]["discarded"].get("short", 0) >= len(faults) - 1
    assert np.isfinite(data[timing_prefix(data["cycle_unit"]) + "_max"])


def test_a_fault_after_a_drop_on_the_same_frame_has_nothing_to_alter():
    """Two faults on one frame, the first a drop: the frame stays dropped (the injector once indexed an
    empty frame list)."""

    class Sink:
        octets_out = octets_in = 0

        def __init__(self) -> None:
            self.sent = b""

        def write(self, data: bytes) -> None:
            self.sent += data

    sink = Sink()
    flink = FaultLink(sink, [Fault("drop", "out", 0), Fault("corrupt", "out", 0), Fault("truncate", "out", 0)])
    flink.write(b"\x00abc\x00\x00def\x00")
    assert sink.sent == b"\x00def\x00"
    assert len(flink.applied) == 3
