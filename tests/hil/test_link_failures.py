"""A run that survives its link (issue 26): the board killed (SIGKILL), its socket closed, Ctrl-C mid-run
end the run with one line naming the port and the error, exit 1, and a JSON that keeps every state
answered (``complete: false``, the unanswered ones); ``--resume`` finishes them and the whole run equals
an uninterrupted one."""
from __future__ import annotations

import json
import os
import signal
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from hil_support import SPMSM, example

from hil import progress
from hil.cli import main
from hil.virtual import SocketBoard, VirtualBoard, build_virtual_board

pytestmark = pytest.mark.board

N = 3000
CFG = [str(SPMSM), "--set", "controller.tables=published", "--strategy", "s1"]
#: what an interrupted run and its resumption must give as an uninterrupted run does
SAME = ("states", "answered", "mismatches", "mismatch_fields", "lost", "sources", "outputs_sha256", "complete",
        "cycle_unit", "unanswered")


@pytest.fixture
def at_third(monkeypatch: pytest.MonkeyPatch) -> Callable[[Callable[[], None]], None]:
    """``at_third(action)``: ``action()`` once, from the run's progress callback, when a third of the states
    is answered (mid-run, at a point the test does not have to guess)."""

    def arm(action: Callable[[], None]) -> None:
        fired = []
        update = progress.Progress.update

        def tick(self: progress.Progress, done: int, *a: Any, **kw: Any) -> None:
            if not fired and done >= N // 3:
                fired.append(done)
                action()
            update(self, done, *a, **kw)

        monkeypatch.setattr(progress.Progress, "update", tick)

    return arm


@pytest.fixture
def virtual_boards(monkeypatch: pytest.MonkeyPatch) -> list[VirtualBoard]:
    """The virtual boards the command starts, as they start."""
    started: list[VirtualBoard] = []
    start = VirtualBoard.start

    def record(self: VirtualBoard) -> VirtualBoard:
        started.append(self)
        return start(self)

    monkeypatch.setattr(VirtualBoard, "start", record)
    return started


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The summary of the same run, uninterrupted."""
    out = tmp_path_factory.mktemp("whole") / "whole.json"
    assert main(["hil", *CFG, "--states", str(N), "--json", str(out), "-q"]) == 0
    return dict(json.loads(out.read_text()))


@pytest.fixture(scope="module")
def socket_board() -> Iterator[SocketBoard]:
    m, t = example("spmsm", "s1")
    with SocketBoard(build_virtual_board(m, t)) as sb:
        yield sb


def _interrupted(capsys: pytest.CaptureFixture[str], out: Path, port_args: list[str],
                 extra: list[str] | None = None) -> tuple[dict[str, Any], str]:
    """Run, expecting the link to fail mid-run: exit 1, one error line, no traceback; the JSON and the line."""
    rc = main(["hil", *CFG, *port_args, "--states", str(N), "--json", str(out), "-q", *(extra or [])])
    std = capsys.readouterr()
    errors = [line for line in std.err.splitlines() if line.startswith("mpcgen:")]
    assert rc == 1, std.err
    assert "Traceback" not in std.err + std.out and len(errors) == 1, std.err
    data = dict(json.loads(out.read_text()))
    assert data["complete"] is False and N // 3 <= data["answered"] < N
    assert data["unanswered"] == N - data["answered"] > 0 and data["mismatches"] == 0
    covered = sum(r["last"] - r["first"] + 1 for r in data["unanswered_ranges"])
    assert covered == data["unanswered"] and {r["source"] for r in data["unanswered_ranges"]} <= set(data["sources"])
    assert str(out) in errors[0] and "--resume" in errors[0]
    assert "INCOMPLETE" in std.out
    return data, errors[0]


def _resumed(capsys: pytest.CaptureFixture[str], first: Path, out: Path, port_args: list[str],
             whole: dict[str, Any]) -> dict[str, Any]:
    """``--resume first``: exit 0, the whole run's summary equal to the uninterrupted one."""
    rc = main(["hil", *CFG, *port_args, "--resume", str(first), "--json", str(out), "-q"])
    assert rc == 0, capsys.readouterr().err
    data = dict(json.loads(out.read_text()))
    assert data["complete"] and data["parts"] == 2 and data["resumed_from"] == str(first)
    assert {k: data[k] for k in SAME} == {k: whole[k] for k in SAME}
    assert "resume" not in data and data["failure"] is None
    return data


def test_board_killed_mid_run(tmp_path, capsys, at_third, virtual_boards, uninterrupted):
    """SIGKILL of the virtual board's process mid-run: the pty hangs up (EIO), the run ends cleanly; the log
    written so far is complete JSON lines."""

    def kill() -> None:
        proc = virtual_boards[-1].proc
        assert proc is not None
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()

    at_third(kill)
    first, log = tmp_path / "part1.json", tmp_path / "part1.log"
    data, line = _interrupted(capsys, first, [], ["--log", str(log)])
    assert "serial link /dev/" in line and "failed" in line and data["failure"] in line
    records = [json.loads(x) for x in log.read_text().splitlines()]
    assert records[0]["format"] and any(r.get("dir") == "in" for r in records[1:])
    end = records[-1]  # the log ends with its end record, naming the failure
    assert end.get("end") is True and end["completed"] is False and end["error"] == data["failure"]
    _resumed(capsys, first, tmp_path / "whole.json", [], uninterrupted)  # the kill fired once only


def test_socket_closed_mid_run(tmp_path, capsys, at_third, socket_board, uninterrupted):
    """The board's side closes the socket:// connection mid-run; the resumed run takes a new connection."""
    at_third(socket_board.drop_links)
    first = tmp_path / "part1.json"
    data, line = _interrupted(capsys, first, ["--port", socket_board.url])
    assert f"serial link {socket_board.url} failed" in line
    assert "socket disconnected" in line or "Broken pipe" in line or "reset" in line, line
    _resumed(capsys, first, tmp_path / "whole.json", ["--port", socket_board.url], uninterrupted)


def test_ctrl_c_mid_run(tmp_path, capsys, at_third, uninterrupted):
    def interrupt() -> None:
        raise KeyboardInterrupt

    at_third(interrupt)
    first = tmp_path / "part1.json"
    data, line = _interrupted(capsys, first, [])
    assert data["failure"] == "interrupted (Ctrl-C)" and line.startswith("mpcgen: error: interrupted (Ctrl-C)")
    _resumed(capsys, first, tmp_path / "whole.json", [], uninterrupted)


def test_a_failed_run_without_json_writes_one(tmp_path, capsys, at_third, monkeypatch):
    """No --json: the answered states still go to a file, named in the error line."""
    def interrupt() -> None:
        raise KeyboardInterrupt

    at_third(interrupt)
    monkeypatch.chdir(tmp_path)
    assert main(["hil", *CFG, "--states", str(N), "-q"]) == 1
    err = capsys.readouterr().err
    written = list(tmp_path.glob("hil-*.partial.json"))
    assert len(written) == 1 and written[0].name in err
    assert json.loads(written[0].read_text())["complete"] is False


def test_resume_bad_input_is_one_line_exit_2(tmp_path, capsys, at_third, uninterrupted):
    def interrupt() -> None:
        raise KeyboardInterrupt

    at_third(interrupt)
    first = tmp_path / "part1.json"
    assert main(["hil", *CFG, "--states", str(N), "--json", str(first), "-q"]) == 1
    done = tmp_path / "done.json"
    done.write_text(json.dumps(uninterrupted))
    garbled = json.loads(first.read_text())
    garbled["resume"]["results_zlib_b64"] = "AAAA"
    broken = tmp_path / "broken.json"
    broken.write_text(json.dumps(garbled))
    capsys.readouterr()
    cases = [
        ([*CFG, "--resume", str(tmp_path / "none.json")], "no such file"),
        ([*CFG, "--resume", str(done)], "complete: nothing to resume"),
        ([*CFG, "--resume", str(first), "--states", "2000"], f"--states = 2000: the run in --resume = '{first}' has"),
        ([*CFG, "--resume", str(first), "--seed", "7"], "--seed = 7"),
        ([str(SPMSM), "--set", "controller.tables=published", "--strategy", "s2", "--resume", str(first)],
         "this one"),
        ([*CFG, "--resume", str(first), "--mode", "closed-loop"], "--resume finishes an interrupted replay"),
        ([*CFG, "--resume", str(broken)], "damaged"),
    ]
    for args, msg in cases:
        rc = main(["hil", *args, "-q"])
        err = capsys.readouterr().err
        assert rc == 2 and msg in err and len(err.strip().splitlines()) == 1, (args, err)


def test_closed_loop_board_killed_mid_run(tmp_path, capsys, monkeypatch, virtual_boards):
    """Mode closed-loop: the periods run so far are kept in the JSON, one line names the port, exit 1."""
    update = progress.Progress.update
    fired: list[int] = []

    def tick(self: progress.Progress, done: int, *a: Any, **kw: Any) -> None:
        if not fired and done >= 1000:
            fired.append(done)
            proc = virtual_boards[-1].proc
            assert proc is not None
            os.kill(proc.pid, signal.SIGKILL)
            proc.wait()
        update(self, done, *a, **kw)

    monkeypatch.setattr(progress.Progress, "update", tick)
    out = tmp_path / "cl.json"
    short = ["--set", "scenario.duration_s=0.2", "--set", "scenario.speed_ref_rpm=[[0.0,500.0]]",
             "--set", "scenario.load_nm=[[0.0,10.0]]"]
    rc = main(["hil", *CFG, "--mode", "closed-loop", *short, "--json", str(out), "-q"])
    std = capsys.readouterr()
    errors = [line for line in std.err.splitlines() if line.startswith("mpcgen:")]
    assert rc == 1 and "Traceback" not in std.err and len(errors) == 1, std.err
    assert "serial link /dev/" in errors[0] and "closed loop stopped at period" in errors[0]
    data = json.loads(out.read_text())
    assert data["lost_at"] is not None and 1000 <= data["periods_done"] < data["periods"] and not data["ok"]
    assert data["failure"] in errors[0] and "host_ns_min" in data and "LOST at period" in std.out
