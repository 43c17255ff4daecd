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
    assert data["states"] == 300 and data["mismatches"] == 0 and data["lost"] == 0 and data["cycle_unit"] == "ns"
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
    # hil is a registered command (entry point group mpcgen.commands); codegen's own list has no hil
    assert "hil" in codegen_cli.build_parser().format_help()
    assert "hil" not in {c.name for c in codegen_cli.COMMANDS}


def test_log_is_re_verified_offline(tmp_path, capsys):
    """`--log FILE` records every octet; `--check-log FILE` re-verifies every logged result offline,
    and a fabricated wrong result in the log is caught."""
    import json

    import numpy as np

    from codegen.config import load_config
    from codegen.topology import topology_of
    from hil.framing import encode_frame
    from hil.messages import batch_payload, step_payload
    from hil.schema import Msg, Schema

    cfg = ["--set", "controller.tables=published", "--strategy", "s1"]
    log = tmp_path / "x.log"
    assert main(["hil", str(SPMSM), *cfg, "--states", "300", "--log", str(log), "-q"]) == 0
    js = tmp_path / "check.json"
    assert main(["hil", str(SPMSM), *cfg, "--check-log", str(log), "--json", str(js), "-q"]) == 0
    data = json.loads(js.read_text())
    assert data["results"] >= 300 and data["distinct_states"] == 300 and data["mismatches"] == 0
    assert data["discarded_frames_in"] == data["bad_results"] == data["bad_batches"] == 0
    m = load_config(SPMSM, {"controller.tables": "published", "controller.strategy": "s1"})
    schema = Schema.of(m)
    # a RESULT one octet short alone fails the check (a protocol fault, not a result)
    clean = log.read_text()
    with open(log, "a") as fh:
        short = encode_frame(Msg.RESULT, 60002, bytes(schema.result_octets - 1))
        fh.write(json.dumps({"t": 98.0, "dir": "in", "hex": short.hex()}) + "\n")
    assert main(["hil", str(SPMSM), *cfg, "--check-log", str(log), "--json", str(js), "-q"]) == 1
    assert json.loads(js.read_text())["bad_results"] == 1
    log.write_text(clean)
    # a fabricated answer: a valid frame whose outputs are all zero
    x = topology_of(m).random_states(m, topology_of(m).derive(m), 1, 3)
    bad = encode_frame(Msg.RESULT, 60000, bytes(schema.result_octets))
    with open(log, "a") as fh:
        fh.write(json.dumps({"t": 99.0, "dir": "out",
                             "hex": encode_frame(Msg.STEP, 60000, step_payload(schema, x)).hex()}) + "\n")
        fh.write(json.dumps({"t": 99.1, "dir": "in", "hex": bad.hex()}) + "\n")
        # a RESULT one octet short and a frame that does not decode: counted, not skipped silently
        short = encode_frame(Msg.RESULT, 60001, bytes(schema.result_octets - 1))
        fh.write(json.dumps({"t": 99.2, "dir": "in", "hex": short.hex()}) + "\n")
        fh.write(json.dumps({"t": 99.3, "dir": "in", "hex": (bytes([7, 1, 2, 3]) + b"\x00").hex()}) + "\n")
    assert main(["hil", str(SPMSM), *cfg, "--check-log", str(log), "--json", str(js), "-q"]) == 1
    data = json.loads(js.read_text())
    assert data["mismatches"] == 1 and data["bad_results"] == 1 and data["discarded_frames_in"] == 1
    # a BATCH whose count says 2 but whose body holds one state: a fault, its state not paired with
    # the RESULT that follows (that result is unmatched, not compared)
    log.write_text(clean)
    two = batch_payload(schema, np.concatenate([x, x]))
    batch = encode_frame(Msg.BATCH, 60010, two[:len(two) - schema.input_octets])  # count 2, one state
    with open(log, "a") as fh:
        fh.write(json.dumps({"t": 99.0, "dir": "out", "hex": batch.hex()}) + "\n")
        fh.write(json.dumps({"t": 99.1, "dir": "in",
                             "hex": encode_frame(Msg.RESULT, 60010, bytes(schema.result_octets)).hex()}) + "\n")
    assert main(["hil", str(SPMSM), *cfg, "--check-log", str(log), "--json", str(js), "-q"]) == 1
    data = json.loads(js.read_text())
    assert data["bad_batches"] == 1 and data["mismatches"] == 0 and data["unmatched_results"] == 1
    capsys.readouterr()
    assert main(["hil", str(SPMSM), "--strategy", "s2", "--set", "controller.tables=published",
                 "--check-log", str(log), "-q"]) == 2  # another config: refused, naming both hashes
    assert "config" in capsys.readouterr().err
