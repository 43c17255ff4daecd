"""``mpcgen hil`` (hil.cli): a replay with its JSON summary; bad input in one line, exit 2, at once;
every codegen command still works through the same entry point."""
from __future__ import annotations

import json

import pytest
from hil_support import SPMSM, TLEVEL

from codegen import cli as codegen_cli
from hil.cli import main

PUBLISHED = ["--set", "controller.tables=published"]


@pytest.mark.board
def test_hil_replay_writes_the_summary(tmp_path, capsys, board):
    if board.port is not None:
        pytest.skip("the command line test starts the virtual board")
    out = tmp_path / "hil.json"
    rc = main(["hil", str(TLEVEL), "--strategy", "mpdtc27", "--states", "300", "--json", str(out)])
    assert rc == 0, capsys.readouterr().err
    data = json.loads(out.read_text())
    # the virtual board times with the host's clock: host_ns_*, never cycles_*; no clock frequency printed
    for key in ("states", "mismatches", "lost", "host_ns_min", "host_ns_median", "host_ns_p99", "host_ns_max",
                "cycle_unit", "complete", "unanswered_ranges", "octets_out_per_s", "octets_in_per_s",
                "uart_921600_octets_per_s_per_direction", "uart_921600_states_per_s"):
        assert key in data
    assert not [k for k in data if k.startswith("cycles_")] and "octets_per_s" not in data
    assert data["states"] == 300 and data["mismatches"] == 0 and data["lost"] == 0 and data["cycle_unit"] == "ns"
    assert data["complete"] and data["unanswered_ranges"] == [] and "resume" not in data
    # per direction against one direction of the UART: the board sends a RESULT per state, so a 921600-baud
    # UART allows 92 160 / (its octets per state) states/s, far below what the pty carries
    assert data["uart_921600_octets_per_s_per_direction"] == 92_160
    per_state = max(data["octets_per_state_in"], data["octets_per_state_out"])
    assert data["uart_921600_states_per_s"] == round(92_160 / per_state, 1) < 2000
    assert data["octets_in"] == 300 * data["octets_per_state_in"]  # one RESULT per state, nothing sent again
    std = capsys.readouterr()
    assert "states/s" in std.err and "mismatches 0" in std.err
    assert "timings in host ns" in std.err and " Hz" not in std.err
    assert "a 921600-baud UART allows" in std.out and "host ns min/median/p99/max" in std.out
    assert "wire:" not in std.out  # a perfect link: no wire counters on the line


@pytest.mark.parametrize("args,msg", [
    (["--states", "0"], "--states = 0"),
    (["--board", "stm32h743"], "--board = 'stm32h743'"),
    (["--port", "/nonexistent/tty"], "--port = '/nonexistent/tty': cannot open"),
    (["--timeout", "0"], "--timeout = 0.0"),
    (["--json", "/proc/x/y.json"], "--json"),
])
def test_bad_input_is_one_line_exit_2(capsys, args, msg):
    rc = main(["hil", str(SPMSM), *PUBLISHED, *args])
    err = capsys.readouterr().err
    assert rc == 2 and msg in err and len(err.strip().splitlines()) == 1, err


def test_port_and_board_exclude_each_other(capsys):
    assert main(["hil", str(SPMSM), "--port", "loop://", "--board", "virtual"]) == 2


def test_codegen_commands_unchanged(capsys, tmp_path):
    assert main(["firmware", str(SPMSM), "--board", "nope", "-o", str(tmp_path)]) == 2
    assert codegen_cli.main(["firmware", str(SPMSM), "--board", "nope", "-o", str(tmp_path)]) == 2
    assert main(["--version"]) == 0 and codegen_cli.main(["--version"]) == 0
    # hil is a registered command (entry point group mpcgen.commands); codegen's own list has no hil
    assert "hil" in codegen_cli.build_parser().format_help()
    assert "hil" not in {c.name for c in codegen_cli.COMMANDS}


def test_log_is_re_verified_offline(tmp_path, capsys):
    """`--log FILE` records every octet, digest-chained, and ends with the end record of the run;
    `--check-log FILE` re-verifies every logged result offline (the damaged logs:
    tests/hil/test_log_integrity.py)."""
    cfg = ["--set", "controller.tables=published", "--strategy", "s1"]
    log = tmp_path / "x.log"
    assert main(["hil", str(SPMSM), *cfg, "--states", "300", "--log", str(log), "-q"]) == 0
    js = tmp_path / "check.json"
    rc = main(["hil", str(SPMSM), *cfg, "--check-log", str(log), "--json", str(js), "-q"])
    data = json.loads(js.read_text())
    assert rc == 0, data["first_problem"]
    assert data["results"] >= 300 and data["distinct_states"] == 300 and data["mismatches"] == 0
    assert data["completed"] and data["end_record"]["run"]["states"] == 300 and data["problems"] == 0
    capsys.readouterr()
    assert main(["hil", str(SPMSM), "--strategy", "s2", "--set", "controller.tables=published",
                 "--check-log", str(log), "-q"]) == 2  # another config: refused, naming what differs
    assert "strategy s1 (this check: s2)" in capsys.readouterr().err
