"""Issue 27 item 3: the 63-MPDTC step is data-driven, short enough to review and quick to compile.

The step resolves a row through its program's table entry (programs.py ``step_programs``) with
one loop over the virtual members (the neutral-point deadbeat) and one over the row's groups
(member pick, cost, ranking), each written once, not once per program: the generated file stays
within 1 500 lines in both number formats (no timing assertions: compile time and cycles are
measured, not tested)."""
from __future__ import annotations

import re

import pytest

from codegen.config import load_config
from codegen.topologies.ttype import plugin as PLUGIN
from codegen.topologies.ttype.programs import block_width, ends_alone, step_programs

from conftest import TTYPE

MAX_LINES = 1500
FORMATS = ["float32", "fixed"]


def _generate(strategy: str, fmt: str, target: str = "stm32h743") -> tuple[str, object]:
    m = load_config(TTYPE, {"controller.strategy": strategy, "controller.number_format": fmt})
    t = PLUGIN.derive(m)
    return PLUGIN.render(m, t, target)[f"{m.prefix}_mpc.c"], t


def _code(text: str) -> str:
    """The C without its comments."""
    return re.sub(r"/\*.*?\*/", "", text, flags=re.S)


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("strategy", ["mpdtc63", "mpdtc27"])
def test_the_step_is_at_most_1500_lines(strategy, fmt):
    text, _t = _generate(strategy, fmt)
    assert text.count("\n") <= MAX_LINES, f"{strategy} {fmt}: {text.count(chr(10))} lines"


@pytest.mark.parametrize("fmt", FORMATS)
def test_63_resolves_a_row_through_its_program_table(fmt):
    """No per-program code: the row selects its program's table entry (and its rotation), one
    deadbeat loop resolves the program's virtual members, one loop over the row's groups picks each
    group's member and costs it.  The deadbeat's division is written once per block width of its
    loop (float32: 3 then 2 members at a time; fixed point: one), not once per member of a program."""
    text, t = _generate("mpdtc63", fmt)
    code = _code(text)
    body = code[code.index("void tlevel_step("):]
    sp = step_programs(t)
    assert "switch (" not in body and "case " not in body
    labels = re.findall(r"\},  /\* (\d+): (.*) \*/$", text, re.M)  # one table entry a program, its groups
    assert len(sp.programs) == 57 and [int(i) for i, _ in labels] == list(range(57))
    assert [g for _, g in labels] == [" ".join(p.labels) for p in sp.programs]
    assert re.search(r"static const tlevel_program_t tlevel_programs\[57\]", code)
    assert "pg = &tlevel_programs[tlevel_row_prog[row]];" in body
    assert "tlevel_io_patterns(ia1, ib1, ic1, tlevel_row_rot[row], io);" in body
    assert "vr = tlevel_vec_rot[tlevel_row_rot[row]];" in body
    division = " / d_" if fmt == "float32" else "tlevel_q_div(num_"
    widths = [3, 2] if fmt == "float32" else [1]
    assert body.count(division) == sum(widths)
    assert len(re.findall(r"for \(; \(?iv", body)) == 1 and len(re.findall(r"for \(; \(?j", body)) == (2 if fmt == "float32" else 1)
    # every group compares its two entries' |V_o(k+2)| by their ranking keys, once per chain
    picks = re.findall(r"&gm\[[^]]+\]\[\((.*?)\) \? 1u : 0u\]", body)
    assert len(picks) == (4 + 2 + 1 if fmt == "float32" else 1)


def test_27_keeps_its_row_written_out():
    """27-MPDTC's one row stays resolved in straight-line code (its 19 groups, a compare for each
    later member of a distinct pattern), no program table."""
    text, t = _generate("mpdtc27", "float32")
    code = _code(text)
    assert "tlevel_programs" not in code and "switch (" not in code
    row = step_programs(t).programs[0]
    assert len(row.members) == 19
    later = sum(len(m) - 1 for m in row.members)
    assert later == 7 and code.count("< c_av[") == later


def test_block_width_leaves_no_member_alone():
    assert not ends_alone(4, 4) and ends_alone(5, 4) and ends_alone(3, 4) and not ends_alone(5, 3)
    assert block_width([0, 2, 3, 5], 4) == 3 and block_width([0, 2, 3, 5], 1) == 1
    assert block_width([3, 5, 7], 4) == 4  # none fits: the format's width
