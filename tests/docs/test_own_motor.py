"""docs/own-motor.md works when followed literally: every command block runs, in order, in a fresh copy
of the repository, and every output it quotes is what the commands print, within the tolerance rule
the guide states (tests/docs/docrun.py: equal for numbers without a decimal point, 5 % or one unit of
the last digit for the others, ``~`` numbers (timed on the writer's machine) only present).

No block of the guide is left out: it needs no board (the firmware runs in QEMU) and no run longer
than a few seconds on the build cache (``MPCGEN_CACHE``): 40 s in all, 70 s from an empty cache.
"""
from __future__ import annotations

import time
from pathlib import Path

import pytest
from docrun import ROOT, compare, mpcgen_shim, parse, repo_copy, run
from docrun import environment as doc_environment

GUIDE = ROOT / "docs" / "own-motor.md"
#: the config the guide prints in full (section 2) and ships
SERVO = ROOT / "examples" / "servo400w.toml"
#: commands of the guide not run here, command text -> reason (none: the guide says which would be)
EXCEPTIONS: dict[str, str] = {}


def test_guide_blocks_are_commands_outputs_or_the_config():
    """Every fenced block is a command block, the output quoted after one, or the shipped config: no
    output quote without its commands, no block the test would not look at."""
    doc = parse(GUIDE.read_text())
    outputs = {id(s.output) for s in doc.steps if s.output is not None}
    for b in doc.blocks:
        if b.lang == "text":
            assert id(b) in outputs, f"docs/own-motor.md:{b.line}: a text block that follows no sh block"
        else:
            assert b.lang in ("sh", "toml"), f"docs/own-motor.md:{b.line}: block of language {b.lang!r}"
    configs = [b for b in doc.blocks if b.lang == "toml"]
    assert len(configs) == 1 and configs[0].text == SERVO.read_text(), \
        "the config printed in docs/own-motor.md section 2 is not examples/servo400w.toml"
    assert len(doc.steps) >= 15 and sum(s.output is not None for s in doc.steps) >= 13
    commands = [c.text for s in doc.steps for c in s.command_lines()]
    for cmd in EXCEPTIONS:
        assert cmd in commands, f"exception {cmd!r} is not a command of the guide any more"


@pytest.mark.slow
def test_own_motor_guide_runs_as_written(tmp_path: Path):
    copy = repo_copy(tmp_path / "repo")
    env = doc_environment(copy, tmp_path / "bin", tmp_path / "cache")
    mpcgen_shim(tmp_path / "bin")
    failures: list[str] = []
    timings: list[str] = []
    t0 = time.monotonic()
    for step in parse(GUIDE.read_text()).steps:
        stdout, stderr = [], []
        for cmd in step.command_lines():
            if cmd.text in EXCEPTIONS:
                continue
            r = run(cmd, copy, env)
            timings.append(f"{r.seconds:6.1f} s  {cmd.text.splitlines()[0][:100]}")
            stdout.append(r.stdout)
            stderr.append(r.stderr)
            if r.returncode != cmd.exit_code:
                failures.append(f"docs/own-motor.md:{cmd.line}: {cmd.text.splitlines()[0]!r} exited "
                                f"{r.returncode}, the guide says {cmd.exit_code}; stderr ends "
                                f"{r.stderr.strip()[-600:]!r}")
        if step.output is not None:
            for problem in compare(step.output.text, "".join(stdout), "".join(stderr)):
                failures.append(f"docs/own-motor.md:{step.output.line}: {problem}")
    print(f"own-motor.md: {len(timings)} commands in {time.monotonic() - t0:.0f} s\n" + "\n".join(timings))
    assert not failures, "\n".join(failures)
