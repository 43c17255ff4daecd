"""Run the commands of a markdown document literally and compare what they print with what it quotes.

The document's conventions (docs/own-motor.md states them for its readers):

* A fenced ```` ```sh ```` block holds commands, run in order in a copy of the
  repository (:func:`repo_copy`), each with ``bash -c`` from the copy's top
  folder, with ``mpcgen`` on PATH resolving to the working tree's code
  (:func:`mpcgen_shim`).  A command is one line (a trailing ``\\`` joins the
  next, a here-document ``<<'EOF'`` runs to its ``EOF`` line); comment lines
  are skipped.  A command must exit 0, unless its line ends in a comment
  naming the code it must exit with: ``# ... exit code 2``.
* A fenced ```` ```text ```` block separated from the command block before it
  by blank lines only quotes the output (stdout and stderr) of that block's
  commands.  Every quoted line, in order, must match a line the commands
  printed (stdout first, then stderr, each searched forward from its last
  match); the output may have lines the quote leaves out.  A quoted line
  ``...`` marks left-out lines and matches nothing; ``...`` inside a line
  matches any text.
* Within a quoted line the text between numbers must match exactly (runs of
  spaces match runs of spaces of any length).  The numbers are compared by the
  tolerance rule of :func:`number_matches`:

  - a number written without a decimal point or exponent (a count, a
    decision, an exit code, an instruction count, a sample count) must be
    equal;
  - a number with a decimal point or exponent (a physical figure) must be
    within 5 % of the printed value or within one unit of its last quoted
    digit, whichever is larger;
  - a number marked ``~`` (``~47.4``) was measured on the clock of the machine
    that ran it (states/s, ns/step, wall seconds and their ratios): a number
    must be printed there, its value is not compared.
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

#: a number as the tools print it: optional sign, thousands separators, decimals, exponent; not part of
#: a word (``s1``, ``float32``, ``0x3c000000`` are text)
NUMBER = r"[-+]?(?:\d{1,3}(?:,\d{3})+|\d+)(?:\.\d+)?(?:[eE][-+]?\d+)?"
_NUMBER_IN_TEXT = re.compile(rf"(?<![\w.])(~?)({NUMBER})(?![\w])")
#: relative tolerance of a physical (decimal) figure
REL_TOL = 0.05
_FENCE = re.compile(r"^```([\w-]*)[^\n]*\n(.*?)^```[ \t]*$", re.M | re.S)
_EXIT = re.compile(r"#.*\bexit code (\d+)\s*$")
_HEREDOC = re.compile(r"<<-?\s*'?\"?(\w+)'?\"?")


@dataclass
class Block:
    """One fenced block: its language, text and the line of its opening fence (1-based)."""

    lang: str
    text: str
    line: int
    start: int
    end: int


@dataclass
class Step:
    """A command block and the output block quoted after it (None: no quoted output)."""

    commands: Block
    output: Block | None = None

    def command_lines(self) -> list[Command]:
        return split_commands(self.commands.text, self.commands.line)


@dataclass
class Command:
    """One shell command of a block and the exit code it must give."""

    text: str
    line: int
    exit_code: int = 0


@dataclass
class Result:
    """What one command did."""

    command: Command
    returncode: int
    stdout: str
    stderr: str
    seconds: float


@dataclass
class Doc:
    """The blocks of a markdown text, paired into steps."""

    blocks: list[Block]
    steps: list[Step] = field(default_factory=list)


def blocks(markdown: str) -> list[Block]:
    """Every fenced block of ``markdown``, in order."""
    out = []
    for m in _FENCE.finditer(markdown):
        out.append(Block(m.group(1), m.group(2), markdown.count("\n", 0, m.start()) + 1, m.start(), m.end()))
    return out


def parse(markdown: str) -> Doc:
    """The ``sh`` blocks of ``markdown``, each with the ``text`` block right after it (blank lines only
    between them), if any."""
    bl = blocks(markdown)
    doc = Doc(bl)
    for i, b in enumerate(bl):
        if b.lang != "sh":
            continue
        step = Step(b)
        if i + 1 < len(bl) and bl[i + 1].lang == "text" and not markdown[b.end:bl[i + 1].start].strip():
            step.output = bl[i + 1]
        doc.steps.append(step)
    return doc


def split_commands(text: str, first_line: int = 1) -> list[Command]:
    """The commands of a ``sh`` block: ``\\``-continued lines joined, here-documents kept with their
    command, comment-only and blank lines dropped; each with its required exit code."""
    lines = text.splitlines()
    out: list[Command] = []
    i = 0
    while i < len(lines):
        line, start = lines[i], i
        i += 1
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        while line.endswith("\\") and i < len(lines):
            line = line[:-1] + " " + lines[i].strip()
            i += 1
        m = _EXIT.search(line)
        code = int(m.group(1)) if m else 0
        doc = _HEREDOC.search(line)
        if doc:
            body = []
            while i < len(lines) and lines[i].strip() != doc.group(1):
                body.append(lines[i])
                i += 1
            i += 1
            line = "\n".join([line, *body, doc.group(1)])
        out.append(Command(line, first_line + 1 + start, code))
    return out


# ----------------------------------------------------------------------------- running

def repo_copy(dest: Path) -> Path:
    """The working tree's files (tracked and untracked, not ignored: ``git ls-files -co
    --exclude-standard``, so uncommitted changes are in) copied to ``dest``."""
    files = subprocess.run(["git", "-C", str(ROOT), "ls-files", "-co", "--exclude-standard", "-z"],
                           capture_output=True, check=True).stdout.decode().split("\0")
    for name in filter(None, files):
        src = ROOT / name
        if src.is_file():
            (dest / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest / name)
    return dest


def mpcgen_shim(bin_dir: Path) -> Path:
    """A ``mpcgen`` executable in ``bin_dir`` running ``python -m codegen.cli`` of this interpreter
    (the code is the copy's: PYTHONPATH points at it, :func:`environment`)."""
    bin_dir.mkdir(parents=True, exist_ok=True)
    shim = bin_dir / "mpcgen"
    shim.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m codegen.cli "$@"\n')
    shim.chmod(0o755)
    return shim


def environment(copy: Path, bin_dir: Path, cache: Path) -> dict[str, str]:
    """The commands' environment: ``mpcgen`` from ``bin_dir`` first on PATH, the copy's code on
    PYTHONPATH, the build cache ``MPCGEN_CACHE`` (the caller's, else ``cache``)."""
    env = dict(os.environ)
    env["PATH"] = f"{bin_dir}{os.pathsep}{env.get('PATH', '')}"
    env["PYTHONPATH"] = str(copy)
    env.setdefault("MPCGEN_CACHE", str(cache))
    env.pop("PYTHONSTARTUP", None)
    return env


def run(cmd: Command, cwd: Path, env: dict[str, str], timeout_s: float = 600.0) -> Result:
    """Run one command with bash in ``cwd``."""
    t0 = time.monotonic()
    r = subprocess.run(["bash", "-o", "pipefail", "-c", cmd.text], cwd=cwd, env=env, capture_output=True,
                       text=True, timeout=timeout_s)
    return Result(cmd, r.returncode, r.stdout, r.stderr, time.monotonic() - t0)


# ----------------------------------------------------------------------------- comparing

def number_matches(quoted: str, printed: str) -> bool:
    """The tolerance rule: a number without decimal point or exponent must be equal; one with them
    within :data:`REL_TOL` of the printed value or one unit of its last quoted digit."""
    q, p = float(quoted.replace(",", "")), float(printed.replace(",", ""))
    mantissa, _, exponent = quoted.lower().replace(",", "").partition("e")
    if "." not in mantissa and not exponent:
        return q == p
    decimals = len(mantissa.partition(".")[2])
    unit = 10.0 ** (-decimals + (int(exponent) if exponent else 0))
    return abs(q - p) <= max(REL_TOL * abs(p), unit * (1 + 1e-9))


@dataclass
class Pattern:
    """A quoted line as a regular expression with one group per number; ``timing[i]`` for a ``~`` one."""

    line: str
    regex: re.Pattern[str]
    numbers: list[str]
    timing: list[bool]


def pattern(quoted: str) -> Pattern:
    """The regular expression of one quoted line (see the module docstring)."""
    text = quoted.strip()
    parts: list[str] = []
    numbers: list[str] = []
    timing: list[bool] = []
    pos = 0

    def literal(s: str) -> str:
        out = []
        for tok in re.split(r"(\s*\.\.\.\s*|\s+)", s):
            out.append(".*?" if "..." in tok else r"\s+" if tok.isspace() else re.escape(tok))
        return "".join(out)

    for m in _NUMBER_IN_TEXT.finditer(text):
        parts.append(literal(text[pos:m.start()]))
        parts.append(f"({NUMBER})(?!\\d)")
        timing.append(m.group(1) == "~")
        numbers.append(m.group(2))
        pos = m.end()
    parts.append(literal(text[pos:]))
    return Pattern(quoted, re.compile(r"\s*" + "".join(parts) + r"\s*"), numbers, timing)


def line_mismatch(p: Pattern, printed: str) -> str | None:
    """None if ``printed`` matches the quoted line ``p``, else why not."""
    m = p.regex.fullmatch(printed)
    if not m:
        return "text differs"
    bad = [f"{q} (printed {g})" for q, g, t in zip(p.numbers, m.groups(), p.timing) if not t
           and not number_matches(q, g)]
    return f"numbers differ: {', '.join(bad)}" if bad else None


def compare(quoted: str, stdout: str, stderr: str) -> list[str]:
    """Problems of a quoted output against what was printed (empty: it matches)."""
    streams = {"stdout": stdout.splitlines(), "stderr": stderr.splitlines()}
    at = {"stdout": 0, "stderr": 0}
    problems = []
    for q in quoted.splitlines():
        if not q.strip() or q.strip() == "...":
            continue
        p = pattern(q)
        found = False
        near: list[str] = []
        for name, lines in streams.items():
            for k in range(at[name], len(lines)):
                why = line_mismatch(p, lines[k])
                if why is None:
                    at[name] = k + 1
                    found = True
                    break
                if why != "text differs":
                    near.append(f"{name}: {lines[k].strip()!r}: {why}")
            if found:
                break
        if not found:
            problems.append(f"quoted line not printed: {q.strip()!r}" + (f"; nearest: {near[0]}" if near else ""))
    return problems
