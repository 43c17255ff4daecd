"""The topologies' templates share their common code through macros, not copies.

Two step templates (or header templates) that repeat a run of 6 identical
non-blank lines (whitespace-normalised) should call a shared macro in
templates/common instead.
"""
from __future__ import annotations

from pathlib import Path

import pytest

TEMPLATES = Path(__file__).resolve().parent.parent / "templates"
TOPOLOGIES = ("twolevel", "ttype")
RUN = 6


def _lines(path: Path) -> list[str]:
    """Non-blank lines with whitespace runs collapsed."""
    return [" ".join(line.split()) for line in path.read_text().splitlines() if line.strip()]


def shared_runs(a: list[str], b: list[str], n: int = RUN) -> list[tuple[str, ...]]:
    """Every run of ``n`` consecutive lines of ``a`` that also stands in ``b``."""
    runs_b = {tuple(b[i:i + n]) for i in range(len(b) - n + 1)}
    return [tuple(a[i:i + n]) for i in range(len(a) - n + 1) if tuple(a[i:i + n]) in runs_b]


def test_shared_runs_finds_a_copy() -> None:
    block = [f"line {i}" for i in range(RUN)]
    assert shared_runs(["x", *block, "y"], ["z", *block]) == [tuple(block)]
    assert shared_runs(block[:-1], block) == []


#: the templates every topology has (the step's .c and .h): compared pairwise below
SHARED_TEMPLATES = sorted(set.intersection(*({p.name for p in (TEMPLATES / t).glob("*.j2")} for t in TOPOLOGIES)))


def test_the_topologies_share_template_names() -> None:
    assert {"mpc.c.j2", "mpc.h.j2"} <= set(SHARED_TEMPLATES)


@pytest.mark.parametrize("name", SHARED_TEMPLATES)
def test_topology_templates_share_no_block(name: str) -> None:
    paths = [TEMPLATES / t / name for t in TOPOLOGIES]
    runs = shared_runs(_lines(paths[0]), _lines(paths[1]))
    assert not runs, f"{name}: move this block into templates/common:\n" + "\n".join(runs[0])


def test_number_format_spelled_through_macros() -> None:
    """No C float spelling (type, libm call, literal filter) in the step templates or shared kernels."""
    for path in [*(TEMPLATES / t / "mpc.c.j2" for t in TOPOLOGIES), TEMPLATES / "common" / "kernels.j2"]:
        text = path.read_text()
        for word in ("float ", "sqrtf(", "fabsf(", "c_float", "0.0f", "ctype =="):
            assert word not in text, f"{path.name}: {word!r} belongs in templates/numfmt/<format>.j2"


def test_interleave_filter_takes_statements_round_robin():
    from codegen.render import environment, interleave_lines

    assert interleave_lines(["a0;\n  a1;\n", "\nb0;", "c0;\nc1;\nc2;"]) == ["a0;", "b0;", "c0;", "a1;", "c1;", "c2;"]
    assert interleave_lines([]) == []
    assert environment().filters["interleave"] is interleave_lines
