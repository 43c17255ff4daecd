"""Mode ``onboard`` on a faulty link: telemetry by sequence number, lost frames asked for again, a
refused SETPOINTS sent again, what stays missing reported as gaps -- never a frame counted twice.

The faults come from the harness's injector (:class:`hil.faults.FaultLink`),
wrapped around the link after the handshake, so that frame 0 "out" is the
SETPOINTS and frame 0 "in" the first TELEMETRY.  The board tests run the
virtual board (the real firmware: hil_proto.c and onboard.c); the property
tests run :func:`hil.onboard.run_on_board` against the Python board of
fake_boards.py under random fault plans.
"""
from __future__ import annotations

import numpy as np
import pytest
from fake_boards import FakeBoard, sample_values
from hil_support import SPMSM, example
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_onboard import SHORT_2L, model_of

from hil.faults import KINDS, Fault, FaultLink
from hil.framing import encode_frame
from hil.onboard import onboard, run_on_board, summary_line
from hil.schema import TELEMETRY_SAMPLES, Msg, Schema
from hil.session import Session

DECIMATION = 4
SAMPLES = 1000  # 4000 periods / 4: 63 TELEMETRY frames, frame 62 of 8 samples
FRAMES = 63


class ShortSetpoints:
    """A link that sends its first SETPOINTS one octet short, with a valid CRC (the board's length check)."""

    def __init__(self, inner) -> None:
        self.inner = inner
        self.done = False

    def __getattr__(self, name):
        return getattr(self.inner, name)

    def write(self, data: bytes) -> None:
        from hil.framing import FrameDecoder

        if not self.done:
            frames = FrameDecoder().feed(data)
            if len(frames) == 1 and getattr(frames[0], "type", None) == Msg.SETPOINTS:
                self.done = True
                data = encode_frame(Msg.SETPOINTS, frames[0].seq, frames[0].payload[:-1])
        self.inner.write(data)


def _onboard(board, faults: list[Fault], *, retries: int = 3, short_setpoints: bool = False,
             silence_s: float = 1.0) -> tuple[dict, FaultLink]:
    m, t = model_of(SPMSM, "s2", SHORT_2L)
    with board(m, t) as link:
        session = Session(link, Schema.of(m), timeout_s=0.3, retries=retries)
        session.handshake()
        flink = FaultLink(ShortSetpoints(link) if short_setpoints else link, faults)
        session.link = flink
        data = onboard(session, m, t, decimation=DECIMATION, show_progress=False, silence_s=silence_s)
    assert sorted(map(str, flink.applied)) == sorted(map(str, faults)), "a planned fault did not happen"
    line = summary_line(data)
    assert "None" not in line and "\n" not in line, line
    return data, flink


@pytest.mark.board
def test_duplicated_and_dropped_telemetry_complete(board):
    data, _ = _onboard(board, [Fault("duplicate", "in", 3), Fault("drop", "in", 7)])
    assert data["complete"] and data["ok"] and data["failure"] is None and data["gaps"] == []
    assert data["samples"] == SAMPLES and data["periods_done"] == 4000
    w = data["wire"]
    assert w["duplicates"] == 1 and w["frames_asked_again"] == 1 and w["setpoints_sent"] == 2, w
    assert w["rerun_differs"] == 0 and w["unexpected"] == 0, w
    # the second SETPOINTS asked for frame 7 only; its RUN_END equals the first's
    assert [(s["frame_first"], s["frame_count"], s["outcome"]) for s in data["setpoints"]] == \
        [(0, FRAMES, "RUN_END"), (7, 1, "RUN_END")]
    line = summary_line(data)
    assert "within tolerance of simulate" in line and "duplicate frames dropped 1" in line, line
    assert "frames asked again 1" in line, line


@pytest.mark.board
def test_without_retries_the_gap_is_reported_never_a_frame_twice(board):
    data, _ = _onboard(board, [Fault("duplicate", "in", 3), Fault("drop", "in", 7)], retries=0)
    assert not data["complete"] and not data["ok"] and data["metrics"] is None
    assert data["samples"] == SAMPLES - TELEMETRY_SAMPLES  # 984: the duplicate not counted, frame 7 missing
    assert data["gaps"] == [{"frames": [7, 7], "samples": [112, 127], "periods": [448, 508]}]
    assert data["wire"]["duplicates"] == 1 and data["wire"]["setpoints_sent"] == 1
    line = summary_line(data)
    assert line.startswith("4000/4000 periods on board  INCOMPLETE (984/1000 samples, status 0, gap: samples "
                           "112-127 (periods 448-508))"), line


@pytest.mark.board
@pytest.mark.parametrize("fault", ["corrupt", "truncate", "length"])
def test_a_refused_setpoints_is_sent_again(board, fault):
    faults = [] if fault == "length" else [Fault(fault, "out", 0)]
    data, _ = _onboard(board, faults, short_setpoints=fault == "length")
    assert data["complete"] and data["ok"], data["failure"]
    w = data["wire"]
    assert w["setpoints_sent"] == 2 and sum(w["board_errors"].values()) == 1 and w["frames_asked_again"] == 0, w
    if fault == "length":  # the board's length check: ERROR LENGTH with the SETPOINTS' seq, sent again at once
        assert w["board_errors"] == {"LENGTH": 1}
    first = data["setpoints"][0]["outcome"]
    assert first.startswith("ERROR ") and data["setpoints"][1]["outcome"] == "RUN_END", data["setpoints"]


@pytest.mark.board
@pytest.mark.parametrize("fault", ["corrupt", "length"])
def test_a_refused_setpoints_without_retries_is_one_line(board, fault):
    faults = [] if fault == "length" else [Fault(fault, "out", 0)]
    data, _ = _onboard(board, faults, retries=0, short_setpoints=fault == "length")
    assert data["periods_done"] is None and data["periods_per_s"] is None and not data["ok"]
    assert data["samples"] == 0 and data["gaps"] == []
    line = summary_line(data)
    assert line.startswith("on-board run of 4000 periods FAILED: the board refused the SETPOINTS frame 1x (ERROR "), line
    assert "it arrived corrupted" in line and ("LENGTH" in line) == (fault == "length"), line
    assert "periods/s" not in line and "board errors" in line, line


@pytest.mark.board
def test_a_lost_setpoints_and_a_lost_run_end_are_asked_again(board):
    data, _ = _onboard(board, [Fault("drop", "out", 0), Fault("drop", "in", FRAMES)], silence_s=0.5)
    assert data["complete"] and data["ok"], data["failure"]
    assert [(s["frame_first"], s["frame_count"]) for s in data["setpoints"]] == [(0, FRAMES), (0, FRAMES), (0, 0)]
    assert data["setpoints"][0]["outcome"].startswith("silent") and data["wire"]["silent"] == 2


# ---------------------------------------------------------------- properties, on the Python board
#: one fault per frame and direction (hil/faults.py applies a second fault to a dropped frame and fails)
FAULT = st.builds(Fault, st.sampled_from([k for k in KINDS if k != "reset"]), st.sampled_from(["in", "out"]),
                  st.integers(0, 12)) | st.builds(Fault, st.just("reset"), st.just("out"), st.integers(0, 12))


@pytest.mark.parametrize("periods,decimation", [(100, 1), (301, 3)])
@settings(max_examples=150, deadline=None, database=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(faults=st.lists(FAULT, max_size=6, unique_by=lambda f: (f.direction, f.frame)), retries=st.integers(0, 3), stop=st.none() | st.integers(1, 300))
def test_run_on_board_takes_each_sample_once_or_reports_it(periods, decimation, faults, retries, stop):
    m, _ = example("spmsm", "s1")
    s = Schema.of(m)
    fake = FakeBoard(s, periods_run=stop)
    session = Session(FaultLink(fake, faults), s, timeout_s=0.005, retries=retries)
    run = run_on_board(session, periods, decimation, [(0, 1.0, 0.5)], silence_s=0.03)
    n = -(-periods // decimation)
    ks = run.samples["k"].astype(np.int64)
    # each sample once, in order, each the board's (nothing corrupted taken)
    assert np.array_equal(ks, np.unique(ks)) and np.all(ks % decimation == 0) and np.all(ks < periods)
    assert s.sample.pack(run.samples).tobytes() == s.sample.pack(sample_values(s, ks)).tobytes()
    assert run.wire.setpoints_sent == len(run.attempts) <= retries + 1
    assert run.wire.rerun_differs == 0
    if run.end is not None:
        ran = min(periods, stop or periods)
        assert (run.end.periods, run.end.samples) == (ran, -(-ran // decimation))
    if run.failure is None:  # complete: every sample of the run and its RUN_END
        assert run.end is not None and np.array_equal(ks, np.arange(0, run.end.periods, decimation))
    elif run.end is not None:  # the gaps are exactly the samples missing
        gap = [k for g in run.gaps for k in range(g["periods"][0], g["periods"][1] + 1, decimation)]
        assert sorted(gap + ks.tolist()) == list(range(0, run.end.samples * decimation, decimation))
        assert run.failure.startswith("gap")
    else:
        assert run.failure.startswith(("no RUN_END", "the board refused")) and len(ks) <= n
    dup_in = sum(1 for f in faults if f.kind == "duplicate" and f.direction == "in")
    assert run.wire.duplicates <= dup_in
    if not faults:  # a clean link: one SETPOINTS, every frame once
        assert run.failure is None and run.wire.setpoints_sent == 1 and run.wire.as_dict()["discarded"] == {}
