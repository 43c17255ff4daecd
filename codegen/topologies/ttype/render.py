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
from codegen.topologies.ttype.programs import FIRST_VIRTUAL_SLOT, GROUP_WIDTH, block_width, ends_alone, step_programs
from codegen.topologies.ttype.records import (
    FAULT_BITS,
    FIRST_VIRTUAL,
    GUARD,
    INPUT,
    N_SEGMENTS,
    SAFE_STATE,
    output_record,
)


def _programs_context(t: ThreeLevelTables, interleave: int) -> dict[str, Any]:
    """63-MPDTC: the resolve programs as the step's table (programs.py ``step_programs``), padded to
    the C arrays' sizes (a program's virtual members to the most any program has, its groups to the
    longest row, a group's entries to ``GROUP_WIDTH`` by its first; padding is never read), and the
    virtual members' loop width (``block_width``) and whether a member can remain alone at its end
    (the loop's one-by-one tail)."""
    sp = step_programs(t)
    nv, mg = sp.max_virtual, t.max_groups
    vw = block_width([len(p.virt_pat) for p in sp.programs], interleave)
    pad = [((0, 0),) * GROUP_WIDTH] * mg
    progs = [{"label": " ".join(p.labels), "n_virt": len(p.virt_pat), "n_members": p.n_members,
              "virt": list(p.virt_pat) + [(0,) * 4] * (nv - len(p.virt_pat)),
              "members": ([m + (m[0],) * (GROUP_WIDTH - len(m)) for m in p.members] + pad)[:mg]}
             for p in sp.programs]
    return {"programs": progs, "max_virtual": nv, "group_width": GROUP_WIDTH, "first_virtual_slot": FIRST_VIRTUAL_SLOT,
            "virt_width": vw, "virt_alone": any(ends_alone(len(p.virt_pat), vw) for p in sp.programs) or vw == 1,
            "row_prog": sp.row_program, "row_rot": sp.row_rotation,
            "vec_rot": [TableRow(r, f"sigma^{m}") for m, r in enumerate(sp.vec_rot)],
            "pat_rot": [TableRow(r, f"pi^{m}") for m, r in enumerate(sp.pat_rot)]}


def _row_context(t: ThreeLevelTables) -> dict[str, Any]:
    """27-MPDTC: its one row's groups, written out in the step: each group's entries (vector,
    pattern) in member order, a member with an earlier member's pattern left out (programs.py)."""
    row = step_programs(t).programs[0]
    return {"row_cases": [{"label": label, "members": m} for label, m in zip(row.labels, row.members)],
            "row_members": row.n_members, "row_label": t.row_labels[0], "max_virtual": 0}


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
    interleave = t.nf.template_values()["interleave"]
    assert isinstance(interleave, int)
    per_strategy = _programs_context(t, interleave) if t.n_sectors > 1 else _row_context(t)
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
