"""Render the three-level tables into C (templates/ttype; templates only format).

Reuses ``codegen.render.environment`` and ``PROFILES``: target profiles differ
only in placement attributes and comments, the arithmetic is identical.
"""
from __future__ import annotations

from dataclasses import dataclass

from codegen.model import Model
from codegen.numfmt.float32 import FLOAT32
from codegen.render import base_context, render_files
from codegen.topologies.ttype import virtual as vv
from codegen.topologies.ttype.derive import ThreeLevelTables
from codegen.topologies.ttype.records import FAULT_BITS, INPUT, N_MAX_EVAL, N_SEGMENTS, OUTPUT, SAFE_STATE


@dataclass(frozen=True)
class _Row:
    cells: tuple[int, ...]
    label: str


def three_level_context(model: Model, t: ThreeLevelTables, target: str) -> dict:
    """Template context: values to print, already derived."""
    mg, mm = t.max_groups, t.max_members
    rows = [
        _Row(tuple(r) + (0,) * (mg - len(r)),
             f"{lab}: " + " ".join(t.group_labels[g] for g in r))
        for r, lab in zip(t.row_groups, t.row_labels)
    ]
    groups = [_Row(tuple(g) + (0,) * (mm - len(g)), lab) for g, lab in zip(t.groups, t.group_labels)]
    seq = []
    for i, s in enumerate(t.seq):
        label = vv.vector_name(i)
        if vv.is_virtual(i):
            label += " " + vv.virtual_of(i).sequence_names()
        seq.append(_Row(tuple(s), label))
    return {
        **base_context(model, target),
        "strategy": t.strategy,
        "consts": t.consts,
        "io_a": t.io_a,
        "io_b": t.io_b,
        "io_c": t.io_c,
        "ux": t.ux,
        "uy": t.uy,
        "seq": seq,
        "end_state": t.end_state,
        "n_sectors": t.n_sectors,
        "groups": groups,
        "group_n": t.group_n,
        "max_members": mm,
        "rows": rows,
        "row_n": t.row_n,
        "max_groups": mg,
        "n_segments": N_SEGMENTS,
        "n_max_eval": N_MAX_EVAL,
        "safe_state": SAFE_STATE,
        "faults": FAULT_BITS,
        "input_fields": INPUT.bind(FLOAT32).members,
        "output_fields": OUTPUT.bind(FLOAT32).members,
    }


def render_three_level(model: Model, tables: ThreeLevelTables, target: str) -> dict[str, str]:
    """File name -> text of the generated three-level controller for ``target``."""
    p = model.prefix
    return render_files({f"{p}_mpc.h": "ttype/mpc.h.j2", f"{p}_mpc.c": "ttype/mpc.c.j2",
                         "mpc_binding.h": "ttype/binding.h.j2"}, three_level_context(model, tables, target))


def render_cdef(model: Model, tables: ThreeLevelTables) -> str:
    """cffi declarations (no preprocessor lines) of the host build."""
    return render_files({"cdef": "ttype/cdef.h.j2"}, three_level_context(model, tables, "host"))["cdef"]
