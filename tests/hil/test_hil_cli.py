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
    for key in ("states", "mismatches", "lost", "cycles_min", "cycles_median", "cycles_p99", "cycles_max",
                "cycle_unit"):
        assert key in data
    assert data["states"] == 900 and data["mismatches"] == 0 and data["lost"] == 0 and data["cycle_unit"] == "ns"
    err = capsys.readouterr().err
    assert "states/s" in err and "mismatches 0" in err


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
    assert "hil" not in codegen_cli.build_parser().format_help()
