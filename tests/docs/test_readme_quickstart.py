"""The README's quick start works when followed literally: every command of its "Quick start" section
runs, in order, in a fresh copy of the repository (tests/docs/docrun.py: ``mpcgen`` resolves to the
working tree's code) and exits 0, and each file or folder it names with ``-o``, ``--json``,
``--plots`` or ``--plot`` exists afterwards.  The quick start quotes no output, so no number is
compared here (docs/own-motor.md's are: tests/docs/test_own_motor.py).

The commands not run are listed in :data:`EXCEPTIONS`, each with its reason; a line that fails when
run literally is listed in :data:`LITERAL_DEFECTS`: the test checks that it does fail and runs the
corrected form instead, until the README is corrected (then the entry must go).
"""
from __future__ import annotations

import re
import shlex
import time
from pathlib import Path

import pytest
from docrun import ROOT, Command, mpcgen_shim, parse, repo_copy, run
from docrun import environment as doc_environment

README = ROOT / "README.md"

#: commands of the quick start not run here: the start of the command -> why
EXCEPTIONS: dict[str, str] = {
    "bash scripts/main.sh": "sets the machine up (apt-get as root, a new .venv, pip install from the network) and "
                            "then generates, verifies with 10^6 states and simulates every example for several "
                            "minutes; its mpcgen commands are the kind the next block runs",
    "bash scripts/test.sh": "runs the whole test suite, this test included",
    "mpcgen tune     examples/seed000_tlevel.toml --weight controller.lambda_psi_nm_per_wb":
        "a long run: about 34 closed-loop runs, each a new controller build, 200 s on a LocalCluster of 2 workers; "
        "tests/stages/test_tune.py runs tune (Dask and --serial, bit for bit) on a short scenario",
    "mpcgen study    examples/mpcc_spmsm.toml --horizons 1-5":
        "a long run: per horizon up to 16 closed-loop runs while lambda_u is matched to one switching frequency "
        "(about 5 minutes on 2 cores); tests/stages/test_study.py runs the study on a short scenario",
    "dask scheduler": "a server on the machine the README calls HOST, running until stopped",
    "dask worker tls://HOST:8786": "joins the scheduler on HOST (a placeholder for another machine) and runs until "
                                   "stopped",
    "mpcgen sweep examples/seed001_ipmsm.toml --monte-carlo 100 --spread plant.rs_ohm=+-20 --scheduler "
    "tls://HOST:8786":
        "needs the scheduler on HOST; tests/stages/test_sweep_tls.py runs a sweep through a TLS LocalCluster and "
        "tests/stages/test_sweep.py checks that Dask gives --serial's results",
}

#: lines that fail when typed as written: the line's start -> (the exit code it gives, the form run
#: instead, why).  Each must still fail as written; once the README is corrected the entry must go.
LITERAL_DEFECTS: dict[str, tuple[int, list[str], str]] = {}

_OUTPUT_OPTIONS = ("-o", "--json", "--plots", "--plot")


def quickstart_commands() -> list[Command]:
    """The commands of the README's "## Quick start" section (up to the next level-2 heading)."""
    text = README.read_text()
    start = text.index("\n## Quick start")
    end = text.index("\n## ", start + 1)
    first_line = text.count("\n", 0, start) + 1
    commands = []
    for step in parse(text[start:end]).steps:
        for c in step.command_lines():
            commands.append(Command(c.text, c.line + first_line - 1, c.exit_code))
    return commands


def _excepted(cmd: str) -> str | None:
    return next((k for k in EXCEPTIONS if " ".join(cmd.split()).startswith(" ".join(k.split()))), None)


def _defect(cmd: str) -> str | None:
    return next((k for k in LITERAL_DEFECTS if cmd.startswith(k)), None)


def _outputs(cmd: str) -> list[str]:
    """The paths a command names as its outputs (``-o``, ``--json``, ``--plots``, ``--plot``), for each
    mpcgen command of a ``&&`` chain."""
    words = shlex.split(cmd, comments=True)
    return [words[i + 1] for i, w in enumerate(words[:-1]) if w in _OUTPUT_OPTIONS]


def test_quickstart_exceptions_and_defects_are_current():
    """Every exception and defect names a command of the quick start (a corrected README line must
    leave LITERAL_DEFECTS), and the quick start is the commands this test expects."""
    commands = [c.text for c in quickstart_commands()]
    assert len(commands) >= 20, commands
    for key in EXCEPTIONS:
        assert sum(_excepted(c) == key for c in commands) == 1, f"exception {key!r} matches no command"
    for key in LITERAL_DEFECTS:
        assert sum(c.startswith(key) for c in commands) == 1, \
            f"{key!r} is no longer in README.md: remove it from LITERAL_DEFECTS"


@pytest.mark.slow
def test_readme_quickstart_runs_as_written(tmp_path: Path):
    copy = repo_copy(tmp_path / "repo")
    env = doc_environment(copy, tmp_path / "bin", tmp_path / "cache")
    mpcgen_shim(tmp_path / "bin")
    failures: list[str] = []
    timings: list[str] = []
    t0 = time.monotonic()
    for cmd in quickstart_commands():
        if _excepted(cmd.text):
            continue
        runs = [cmd]
        defect = _defect(cmd.text)
        if defect:
            code, forms, _why = LITERAL_DEFECTS[defect]
            r = run(Command(cmd.text, cmd.line, code), copy, env)
            if r.returncode != code:
                failures.append(f"README.md:{cmd.line}: {cmd.text!r} exited {r.returncode}, LITERAL_DEFECTS says "
                                f"{code}: remove the entry if the line works now")
            runs = [Command(f, cmd.line, 0) for f in forms]
        for c in runs:
            r = run(c, copy, env)
            timings.append(f"{r.seconds:6.1f} s  {c.text[:110]}")
            if r.returncode != c.exit_code:
                failures.append(f"README.md:{c.line}: {c.text!r} exited {r.returncode}; stderr ends "
                                f"{r.stderr.strip()[-600:]!r}")
                continue
            for out in _outputs(re.sub(r"\$PWD", str(copy), c.text)):
                if not (copy / out).exists():
                    failures.append(f"README.md:{c.line}: {c.text!r} did not write {out}")
    print(f"README quick start: {len(timings)} commands in {time.monotonic() - t0:.0f} s\n" + "\n".join(timings))
    assert not failures, "\n".join(failures)
