"""Progress lines of long phases (issue 28: ``bench --emulated`` on the T-type config printed nothing for
153 s while ``make`` built the 63-MPDTC fixed-point image): a line per phase, a heartbeat every few seconds,
on stderr, silenced by ``-q``, the JSON unchanged."""
from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

import codegen.stages.emulate as emulate
import codegen.stages.progress as progress
from codegen.cli import main
from codegen.stages.emulate import build_progress, uart_progress
from codegen.stages.progress import phase

from conftest import SPMSM


def test_phase_lines_and_heartbeats() -> None:
    lines: list[str] = []
    with phase(lines.append, "building", every_s=0.05) as p:
        time.sleep(0.2)
        p.note("2/3 objects")
        time.sleep(0.2)
    assert lines[0] == "  building ..." and lines[-1].startswith("  building: done in ")
    beats = lines[1:-1]
    assert len(beats) >= 4 and all(b.startswith("    ... building: ") for b in beats), lines
    assert beats[-1].endswith(", 2/3 objects") and not beats[0].endswith("objects")


def test_phase_probe_and_silence() -> None:
    lines: list[str] = []
    with phase(lines.append, "make", every_s=0.05, probe=lambda: "linking"):
        time.sleep(0.15)
    assert any(line.endswith("s, linking") for line in lines), lines
    with phase(None, "quiet", every_s=0.01) as p:  # no log: no thread, no line
        p.note("x")
        time.sleep(0.05)


def test_a_failing_phase_stops_its_heartbeat() -> None:
    lines: list[str] = []
    with pytest.raises(RuntimeError), phase(lines.append, "run", every_s=0.02):
        raise RuntimeError("boom")
    n = len(lines)
    time.sleep(0.1)
    assert len(lines) == n and not any("done" in line for line in lines)


def test_build_progress_reads_the_objects_make_wrote(tmp_path: Path) -> None:
    (tmp_path / "Makefile").write_text("X = 1\nSRCS = gen/a.c \\\n       gen/b.c \\\n       runtime/c.c\nINCLUDES = -I.\n")
    (tmp_path / "build" / "gen").mkdir(parents=True)
    assert build_progress(tmp_path) == "0/3 objects built, compiling gen/a.c"
    (tmp_path / "build" / "gen" / "a.o").write_bytes(b"")
    assert build_progress(tmp_path) == "1/3 objects built, compiling gen/b.c"
    (tmp_path / "build" / "gen" / "b.o").write_bytes(b"")
    (tmp_path / "build" / "runtime").mkdir()
    (tmp_path / "build" / "runtime" / "c.o").write_bytes(b"")
    assert build_progress(tmp_path) == "3/3 objects built, linking"


def test_uart_progress() -> None:
    text = "HELLO config=x\nSET name=selftest n=1000 expect=full\nSUMMARY set=selftest n=1000 mismatches=0\n" \
           "SET name=bench n=2000 expect=full\nCYC 1 2 3\nCYC 4 5\n"
    assert uart_progress(text) == "sets done: selftest; running set bench (5/2000 states)"
    assert uart_progress("") == "no set done yet"


def _bench(tmp_path: Path, capsys: pytest.CaptureFixture[str], *flags: str) -> tuple[dict[str, object], str]:
    js = tmp_path / f"bench{len(flags)}.json"
    assert main(["bench", str(SPMSM), "--emulated", "--strategies", "conventional", "--repeats", "1",
                 "--json", str(js), *flags]) == 0
    return json.loads(js.read_text()), capsys.readouterr().err


def test_emulated_bench_reports_every_phase(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                            monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(progress, "HEARTBEAT_S", 0.1)
    # a QEMU run of a cached image can end within one heartbeat (since issue 30 the fixed-point step is
    # about 4 times shorter): each run waits 0.5 s first, so its phase lasts several heartbeats
    run_qemu = emulate.run_qemu

    def slow_run(*args: object, **kw: object) -> emulate.QemuRun:
        time.sleep(0.5)
        return run_qemu(*args, **kw)  # type: ignore[arg-type]

    monkeypatch.setattr(emulate, "run_qemu", slow_run)
    loud, err = _bench(tmp_path, capsys)
    for fmt in ("float32", "fixed"):
        for what in ("writing the firmware project", "compiling and linking the image (make)",
                     "running the image in QEMU", "checking the image's digests against the reference"):
            assert f"  conventional ({fmt}): {what}" in err and f"conventional ({fmt}): {what}" in err, (fmt, what)
            assert f"  conventional ({fmt}): {what}" in err.split(f"conventional ({fmt}): {what}: done in ")[0]
    assert "spmsm_step: tracing 2000 bench states in unicorn" in err  # every bench state (issue 28)
    assert "spmsm_step: llvm-mca (Cortex-M7 model) on" in err
    assert "    ... conventional (" in err  # heartbeats (every 0.1 s here)
    quiet, err_q = _bench(tmp_path, capsys, "-q")
    assert err_q == ""
    strip = {"host_ns_per_step", "host_ns_ratio", "host_ns_median", "host_ns_spread", "host_ns_ratio_of_medians"}
    for data in (loud, quiet):  # the timings left out
        data.pop("sim_periods_per_s")
        for entry in data["strategies"].values():  # type: ignore[attr-defined]
            for k in strip:
                entry.pop(k)
        for entry in data["simulator"]["integrators"].values():  # type: ignore[index]
            entry.pop("periods_per_s")
    assert loud == quiet  # the progress lines change nothing else
