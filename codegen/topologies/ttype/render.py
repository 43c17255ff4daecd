"""Render the three-level tables into C (templates/ttype; templates only format).

Reuses ``codegen.render.environment`` and ``PROFILES``: target profiles differ
only in placement attributes and comments, the arithmetic is identical.
"""
from __future__ import annotations

from typing import Any

from codegen.model import Model
from codegen.render import TableRow, render_step, render_step_cdef, sincos_bound, step_context, table_fields
from codegen.topologies.ttype import virtual as vv
from codegen.topologies.ttype.derive import DQ, ThreeLevelTables
from codegen.topologies.ttype.programs import resolve_programs
from codegen.topologies.ttype.records import (
    FAULT_BITS,
    FIRST_VIRTUAL,
    GUARD,
    INPUT,
    N_SEGMENTS,
    SAFE_STATE,
    output_record,
)


def _distinct_patterns(case: dict[str, Any]) -> dict[str, Any]:
    """27-MPDTC's case of a group (every member basic, |V_o(k+2)| a function of its one pattern):
    a member whose pattern an earlier member has is never strictly smaller, so it is left out of
    the comparisons (NNN and PPP share pattern 000)."""
    seen: set[int] = set()
    members = []
    for mb in case["members"]:
        if mb["pat"][0] not in seen:
            seen.add(mb["pat"][0])
            members.append(mb)
    return {**case, "members": members}


def _programs_context(t: ThreeLevelTables, cases: dict[int, dict[str, Any]]) -> dict[str, Any]:
    """63-MPDTC: the resolve programs (programs.py), one generated case each, and their tables."""
    progs = resolve_programs(t)
    return {
        "row_programs": [{"index": i, "groups": [cases[g] for g in r], "n_members": sum(t.group_n[g] for g in r),
                          "label": " ".join(t.group_labels[g] for g in r)} for i, r in enumerate(progs.programs)],
        "row_prog": progs.row_program, "row_rot": progs.row_rotation,
        "vec_rot": [TableRow(r, f"sigma^{m}") for m, r in enumerate(progs.vec_rot)],
        "pat_rot": [TableRow(r, f"pi^{m}") for m, r in enumerate(progs.pat_rot)]}


def three_level_context(model: Model, t: ThreeLevelTables, target: str) -> dict[str, Any]:
    """Template context: values to print, already derived."""
    mg = t.max_groups
    seq = []
    for i, s in enumerate(t.seq):
        label = vv.vector_name(i)
        if vv.is_virtual(i):
            label += " " + vv.virtual_of(i).sequence_names()
        seq.append(TableRow(tuple(s), label))
    seq_pat = [TableRow(p, f"{r.label}: " + (" ".join(f"{x:03b}" for x in p) if vv.is_virtual(i) else f"{p[0]:03b}"))
               for i, (p, r) in enumerate(zip(t.seq_pat, seq))]
    # each group with its members and their segment patterns, known here, so the step resolves a
    # group without table lookups or branches on the kind: 63-MPDTC in the cases of its resolve
    # programs, 27-MPDTC its one row's groups in row order
    cases = {g: {"group": g, "label": t.group_labels[g],
                 "members": [{"v": v, "virtual": vv.is_virtual(v), "pat": t.seq_pat[v]}
                             for v in t.groups[g]]} for g in range(len(t.groups))}
    if t.n_sectors > 1:
        per_strategy = _programs_context(t, cases)
    else:
        per_strategy = {"row_cases": [_distinct_patterns(cases[g]) for g in t.row_groups[0]],
                        "row_members": sum(t.group_n[g] for g in t.row_groups[0]),
                        "row_label": t.row_labels[0]}
    return step_context(model, target, (INPUT, output_record(mg)), FAULT_BITS, **{
        **table_fields(t), "topology_macro": "MPC_TOPOLOGY_THREE_LEVEL", "guard": GUARD, "dq": DQ,
        "first_virtual": FIRST_VIRTUAL, "seq": seq, "seq_pat": seq_pat, **per_strategy,
        "n_rows": len(t.row_groups), "row_n": t.row_n, "max_groups": mg, "min_groups": min(t.row_n),
        "n_segments": N_SEGMENTS,
        "safe_state": SAFE_STATE, "output_last": output_record(mg).fields[-1].name,
        "sincos_bound": sincos_bound(t.nf, "ANGLE_GUARD_RAD + 2 w Ts",
                                     2.0 * float(t.nf.decode("rad/s", t.const("OMEGA_GUARD_RAD_S")))
                                     * float(t.nf.decode("s", t.const("TS_S"))))})


def render_three_level(model: Model, tables: ThreeLevelTables, target: str) -> dict[str, str]:
    """File name -> text of the generated three-level controller for ``target``."""
    return render_step(model, "ttype", three_level_context(model, tables, target))


def render_cdef(model: Model, tables: ThreeLevelTables) -> str:
    """cffi declarations (no preprocessor lines) of the host build."""
    return render_step_cdef(three_level_context(model, tables, "host"))
