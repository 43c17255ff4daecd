"""Logs that prove what they claim (issue 26): ``mpcgen hil --check-log`` on a real run over the virtual board.

Each test takes the untouched log of one 400-state replay (written by :class:`hil.exchange_log.LoggingLink`,
ended with the run's summary), damages a copy as a hand edit or a cut would, and runs ``--check-log``:
exit 1 with the first damaged line, exit 2 (one line, the file line number) for a line cut in half, exit 0
for the untouched log and for a run the session recovered from dropped and duplicated frames.
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from cobs import cobs
from hil_support import SPMSM

from hil.cli import main
from hil.exchange_log import FORMAT, DigestChain, LoggingLink, Tally
from hil.faults import Fault, FaultLink
from hil.framing import Frame, decode_frame, encode_frame
from hil.messages import step_payload
from hil.schema import Msg, Schema

SETS = ["controller.tables=published"]
CFG = ["--set", *SETS, "--strategy", "s1"]
STATES = 400


def _model() -> tuple[Any, Any, Schema]:
    from codegen.config import load_config
    from codegen.topology import topology_of

    m = load_config(SPMSM, {"controller.tables": "published", "controller.strategy": "s1"})
    return m, topology_of(m).derive(m), Schema.of(m)


def record(path: Path, states: int = STATES, faults: list[Fault] | None = None, abort: bool = False,
           **session_kw: Any) -> dict[str, Any]:
    """A replay of ``states`` states on the virtual board, every octet logged to ``path``; its summary."""
    from hil.boards import open_board
    from hil.replay import replay
    from hil.session import Session
    from hil.states import replay_states

    m, tables, schema = _model()
    header = {"config": str(SPMSM), "sets": SETS, "config_hash": schema.config_hash,
              "schema_hash": schema.schema_hash, "strategy": "s1", "board": "virtual", "mode": "replay"}
    data: dict[str, Any] = {}
    with open_board(m, tables) as board_link, open(path, "w") as fh:
        inner: Any = FaultLink(board_link, faults) if faults else board_link
        try:
            with LoggingLink(inner, fh, header) as link:
                session = Session(link, schema, **session_kw)
                session.handshake()
                if abort:
                    raise RuntimeError("the harness stopped")
                data = replay(session, m, tables, replay_states(m, tables, states, 1), show_progress=False, seed=1)
                link.finish(data)
        except RuntimeError:
            assert abort
    return data


@pytest.fixture(scope="module")
def clean_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("log") / "clean.log"
    data = record(path)
    assert data["complete"] and data["answered"] == STATES and data["mismatches"] == 0
    return path


def check(log: Path, tmp_path: Path) -> tuple[int, dict[str, Any] | None]:
    """``--check-log``'s exit code and JSON."""
    js = tmp_path / "check.json"
    js.unlink(missing_ok=True)
    rc = main(["hil", str(SPMSM), *CFG, "--check-log", str(log), "--json", str(js), "-q"])
    return rc, json.loads(js.read_text()) if js.exists() else None


def lines_of(log: Path) -> list[str]:
    return log.read_text().splitlines(keepends=True)


def copy_with(tmp_path: Path, lines: list[str]) -> Path:
    out = tmp_path / "edited.log"
    out.write_text("".join(lines))
    return out


def records(lines: list[str]) -> list[dict[str, Any]]:
    return [json.loads(x) for x in lines]


def reseal(tmp_path: Path, recs: list[dict[str, Any]]) -> Path:
    """A forger's log: ``recs`` with every digest (and the end record's counts) recomputed."""
    chain, tally, text = DigestChain(), Tally(), []
    for r in recs:
        r = {k: v for k, v in r.items() if k != "sha256"}
        if "dir" in r:
            tally.feed(r["dir"], bytes.fromhex(r["hex"]))
        if r.get("end") is True:
            r["counts"] = tally.counts()
        text.append(chain.seal(r))
    return copy_with(tmp_path, text)


def first_line(data: dict[str, Any] | None) -> int:
    assert data is not None and data["first_problem"] is not None, data
    return int(data["first_problem"]["line"])


def _result_frames(lines: list[str]) -> list[tuple[int, list[bytes], int]]:
    """(line index, the line's octets split at the delimiters, piece index) of every whole RESULT frame."""
    found = []
    for i, r in enumerate(records(lines)):
        if r.get("dir") != "in":
            continue
        pieces = bytes.fromhex(r["hex"]).split(b"\x00")
        for j in range(1, len(pieces) - 1):  # a delimiter on each side within this line
            item = decode_frame(pieces[j]) if pieces[j] else None
            if isinstance(item, Frame) and item.type == Msg.RESULT:
                found.append((i, pieces, j))
    return found


# ---------------------------------------------------------------- exit 0
def test_untouched_complete_log_passes(clean_log: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rc, data = check(clean_log, tmp_path)
    out = capsys.readouterr().out
    assert rc == 0, out
    assert data is not None and data["ok"] and data["problems"] == 0 and data["first_problem"] is None
    assert data["format"] == FORMAT and data["completed"] and data["digest_chain_intact"]
    assert data["results"] >= STATES and data["distinct_states"] == STATES and data["mismatches"] == 0
    assert data["states_without_result"] == data["unmatched_results"] == data["sequence_gaps"] == 0
    end = data["end_record"]
    assert end["completed"] is True and end["run"]["states"] == STATES and end["run"]["answered"] == STATES
    assert end["counts"] == data["counts"] and end["counts"]["in"]["RESULT"] == data["results"]
    assert data["lines"] == len(lines_of(clean_log)) and data["end_line"] == data["lines"]
    assert "log check OK" in out and "the end record of a completed run" in out and "nothing wrong" in out


def test_every_line_carries_the_digest_of_the_log_up_to_it(clean_log: Path) -> None:
    import hashlib

    raw = clean_log.read_bytes()
    lines = raw.splitlines(keepends=True)
    before = b""
    for line in lines:
        digest = json.loads(line)["sha256"]
        body = line[:line.rindex(b', "sha256"')] + b"}"
        assert hashlib.sha256(before + body).hexdigest() == digest
        before += line
    assert json.loads(lines[0])["format"] == FORMAT and json.loads(lines[-1])["end"] is True


def test_a_run_recovered_from_wire_faults_passes(tmp_path: Path) -> None:
    """A dropped request (sent again under a new number) and a duplicated RESULT: still every state has a
    checked result; the duplicate is counted."""
    log = tmp_path / "faults.log"
    data = record(log, 200, [Fault("drop", "out", 3), Fault("duplicate", "in", 6)], timeout_s=0.2)
    assert data["complete"] and data["wire"]["resent_states"] > 0
    rc, rep = check(log, tmp_path)
    assert rc == 0, rep
    assert rep is not None and rep["duplicate_results"] >= 1 and rep["states_sent"] > rep["distinct_states"]


# ---------------------------------------------------------------- exit 1: edits, gaps, incomplete runs
def test_flipped_decision_byte_with_stale_crc_fails_at_its_line(clean_log: Path, tmp_path: Path) -> None:
    _, _, schema = _model()
    lines = lines_of(clean_log)
    i, pieces, j = _result_frames(lines)[5]
    raw = bytearray(cobs.decode(pieces[j]))
    field_at = schema.output.packed_dtype.fields[schema.decision_field][1]  # type: ignore[index]
    raw[4 + schema.result_head.packed_dtype.itemsize + field_at] ^= 0x01  # frame head, result head, the field
    old = b"\x00".join(pieces).hex()
    pieces[j] = cobs.encode(bytes(raw))  # the CRC left as it was
    assert lines[i].count(old) == 1
    lines[i] = lines[i].replace(old, b"\x00".join(pieces).hex())
    rc, rep = check(copy_with(tmp_path, lines), tmp_path)
    assert rc == 1 and first_line(rep) == i + 1 and "edited" in rep["first_problem"]["what"]
    assert rep["discarded_frames_in"] == 1 and not rep["digest_chain_intact"]


def test_flipped_raw_byte_fails_at_its_line(clean_log: Path, tmp_path: Path) -> None:
    lines = lines_of(clean_log)
    i = next(k for k, r in enumerate(records(lines)) if r.get("dir") == "out" and len(r["hex"]) > 40)
    at = lines[i].index('"hex": "') + 8 + 20  # the 11th octet of the chunk
    lines[i] = lines[i][:at] + ("0" if lines[i][at] != "0" else "1") + lines[i][at + 1:]
    rc, rep = check(copy_with(tmp_path, lines), tmp_path)
    assert rc == 1 and first_line(rep) == i + 1


@pytest.mark.parametrize("direction", ["out", "in"])
def test_deleted_line_fails_where_it_was(clean_log: Path, tmp_path: Path, direction: str) -> None:
    lines = lines_of(clean_log)
    i = [k for k, r in enumerate(records(lines)) if r.get("dir") == direction][3]
    del lines[i]
    rc, rep = check(copy_with(tmp_path, lines), tmp_path)
    assert rc == 1 and first_line(rep) == i + 1


def test_deleted_in_lines_fail_and_leave_states_without_results(clean_log: Path, tmp_path: Path) -> None:
    lines = lines_of(clean_log)
    recs = records(lines)
    ins = [k for k, r in enumerate(recs) if r.get("dir") == "in"]
    keep = set(ins[:2])
    edited = [x for k, x in enumerate(lines) if recs[k].get("dir") != "in" or k in keep]
    rc, rep = check(copy_with(tmp_path, edited), tmp_path)
    assert rc == 1 and first_line(rep) == ins[2] + 1
    assert rep is not None and rep["results"] < STATES and rep["states_without_result"] > 0
    # the same cut with the chain and the end record's counts recomputed (a forger): the missing results fail
    rc, rep = check(reseal(tmp_path, records(edited)), tmp_path)
    assert rc == 1 and rep is not None and rep["digest_chain_intact"] and rep["states_without_result"] > 0
    assert "has no result" in rep["first_problem"]["what"]


@pytest.mark.parametrize("keep", [1, 2, 0.5, -1])
def test_truncated_at_a_line_boundary_fails(clean_log: Path, tmp_path: Path, keep: float) -> None:
    lines = lines_of(clean_log)
    n = int(len(lines) * keep) if isinstance(keep, float) else keep % len(lines)
    rc, rep = check(copy_with(tmp_path, lines[:n]), tmp_path)
    assert rc == 1 and first_line(rep) == n and "without the end record" in rep["first_problem"]["what"]
    assert not rep["completed"]


def test_log_of_an_incomplete_run_fails(tmp_path: Path) -> None:
    """The board falls silent after a few results: the run ends with states unanswered, the end record says
    so, and the states sent without an answer are named."""
    log = tmp_path / "silent.log"
    data = record(log, STATES, [Fault("silent", "in", 6)], timeout_s=0.1, retries=1)
    assert not data["complete"] and 0 < data["answered"] < STATES
    rc, rep = check(log, tmp_path)
    assert rc == 1 and rep is not None and rep["end_record"]["completed"] is False
    assert first_line(rep) == rep["end_line"] and f"of {STATES} states answered" in rep["first_problem"]["what"]
    assert rep["states_without_result"] > 0 and rep["results"] == data["answered"]


def test_log_of_an_aborted_run_fails(tmp_path: Path) -> None:
    log = tmp_path / "aborted.log"
    record(log, abort=True)
    rc, rep = check(log, tmp_path)
    assert rc == 1 and rep is not None and first_line(rep) == rep["end_line"]
    assert "RuntimeError: the harness stopped" in rep["first_problem"]["what"]


def test_lines_after_the_end_record_fail(clean_log: Path, tmp_path: Path) -> None:
    lines = lines_of(clean_log)
    rc, rep = check(copy_with(tmp_path, lines + lines[-2:-1]), tmp_path)
    assert rc == 1 and first_line(rep) == len(lines) + 1


def test_fabricated_result_in_a_resealed_log_is_a_mismatch_at_its_line(clean_log: Path, tmp_path: Path) -> None:
    """The digests re-computed by a forger: the frames themselves still have to prove the results."""
    from codegen.topology import topology_of

    m, tables, schema = _model()
    recs = records(lines_of(clean_log))
    x = topology_of(m).random_states(m, tables, 1, 3)
    extra = [{"t": 98.0, "dir": "out", "hex": encode_frame(Msg.STEP, 60000, step_payload(schema, x)).hex()},
             {"t": 98.1, "dir": "in", "hex": encode_frame(Msg.RESULT, 60000, bytes(schema.result_octets)).hex()}]
    rc, rep = check(reseal(tmp_path, recs[:-1] + extra + recs[-1:]), tmp_path)
    assert rc == 1 and rep is not None and rep["mismatches"] == 1 and rep["digest_chain_intact"]
    assert rep["sequence_gaps"] == 1  # 60000 is not the session's next sequence number
    assert any(p["line"] == len(recs) + 1 and "differs from the reference" in p["what"] for p in rep["problem_list"])
    # a RESULT one octet short, a frame that does not decode, a RESULT answering nothing sent
    extra = [{"t": 98.0, "dir": "in", "hex": encode_frame(Msg.RESULT, 60001, bytes(schema.result_octets - 1)).hex()},
             {"t": 98.1, "dir": "in", "hex": (b"\x00\x07\x01\x02\x03\x00").hex()},
             {"t": 98.2, "dir": "in", "hex": encode_frame(Msg.RESULT, 60002, bytes(schema.result_octets)).hex()}]
    rc, rep = check(reseal(tmp_path, recs[:-1] + extra + recs[-1:]), tmp_path)
    assert rc == 1 and rep is not None and first_line(rep) == len(recs)
    assert rep["bad_results"] == rep["discarded_frames_in"] == rep["unmatched_results"] == 1
    assert rep["mismatches"] == 0 and rep["problems"] == 3


def test_end_record_counts_must_be_the_logs(clean_log: Path, tmp_path: Path) -> None:
    """A forger who re-computes the chain but not the end record's counts is caught at the end record."""
    recs = records(lines_of(clean_log))
    path = reseal(tmp_path, recs)
    recs = records(lines_of(path))
    recs[-1]["counts"]["in"]["RESULT"] += 1
    text, chain = [], DigestChain()
    for r in recs:
        text.append(chain.seal({k: v for k, v in r.items() if k != "sha256"}))
    rc, rep = check(copy_with(tmp_path, text), tmp_path)
    assert rc == 1 and first_line(rep) == len(recs) and "end record counts" in rep["first_problem"]["what"]


# ---------------------------------------------------------------- exit 2: cut mid-line, old format, other config
def test_line_cut_in_half_is_refused_naming_its_line(clean_log: Path, tmp_path: Path,
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    lines = lines_of(clean_log)
    k = len(lines) // 2
    log = copy_with(tmp_path, lines[:k] + [lines[k][:37]])
    capsys.readouterr()
    rc, rep = check(log, tmp_path)
    err = capsys.readouterr().err.strip()
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert f"truncated at line {k + 1}" in err and f"lines 1-{k} checked" in err and "results" in err
    assert "column" not in err
    assert rep is not None and rep["truncated_at_line"] == k + 1 and rep["lines"] == k and rep["results"] > 0
    assert rep["digest_chain_intact"] and rep["mismatches"] == 0


def test_old_format_log_is_refused_naming_its_version(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = tmp_path / "v1.log"
    log.write_text(json.dumps({"format": "mpcgen-hil-log/1", "config": "x"}) + "\n"
                   + json.dumps({"t": 0.0, "dir": "out", "hex": "00"}) + "\n")
    capsys.readouterr()
    assert check(log, tmp_path)[0] == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "mpcgen-hil-log/1" in err and FORMAT in err, err


@pytest.mark.parametrize("text", ["", "hello\n", "[1, 2]\n"])
def test_not_a_log_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str) -> None:
    log = tmp_path / "x.log"
    log.write_text(text)
    capsys.readouterr()
    assert check(log, tmp_path)[0] == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


def test_log_of_another_config_is_refused_naming_what_differs(clean_log: Path, tmp_path: Path,
                                                              capsys: pytest.CaptureFixture[str]) -> None:
    capsys.readouterr()
    rc = main(["hil", str(SPMSM), "--set", *SETS, "--strategy", "s2", "--check-log", str(clean_log), "-q"])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and len(err.splitlines()) == 1
    assert "strategy s1 (this check: s2)" in err and "config hash" in err
    assert "number format" not in err and "target" not in err  # only what differs is named


@pytest.mark.parametrize("other,named", [
    (["--number-format", "fixed"], "number format float32 (this check: fixed)"),
    (["--set", "target.name=stm32h743"], "target host (this check: stm32h743)"),
])
def test_another_number_format_or_target_is_named(clean_log: Path, capsys: pytest.CaptureFixture[str],
                                                  other: list[str], named: str) -> None:
    capsys.readouterr()
    rc = main(["hil", str(SPMSM), *CFG, *other, "--check-log", str(clean_log), "-q"])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and len(err.splitlines()) == 1 and named in err and "strategy" not in err, err


def test_edited_header_is_an_edit_not_another_config(clean_log: Path, tmp_path: Path) -> None:
    lines = lines_of(clean_log)
    lines[0] = lines[0].replace('"strategy": "s1"', '"strategy": "s2"')
    rc, rep = check(copy_with(tmp_path, lines), tmp_path)
    assert rc == 1 and first_line(rep) == 1
