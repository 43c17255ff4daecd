"""Render the three-level tables into C (templates/threelevel; templates only format).

Reuses ``codegen.render.environment`` and ``PROFILES``: target profiles differ
only in placement attributes and comments, the arithmetic is identical.
"""
from __future__ import annotations

from dataclasses import dataclass

from .. import __version__
from ..model import Model
from ..render import PROFILES, environment
from . import virtual as vv
from .derive import ThreeLevelTables
from .interface import FAULT_BITS, INPUT_FIELDS, N_MAX_EVAL, N_SEGMENTS, OUTPUT_FIELDS, SAFE_STATE


@dataclass(frozen=True)
class _Row:
    cells: tuple[int, ...]
    label: str


def three_level_context(model: Model, t: ThreeLevelTables, target: str) -> dict:
    """Template context: values to print, already derived."""
    if target not in PROFILES:
        raise ValueError(f"unknown target {target!r}; allowed: {', '.join(PROFILES)}")
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
        "model_name": model.name,
        "config_hash": model.config_hash(),
        "version": __version__,
        "prefix": model.prefix,
        "PREFIX": model.prefix.upper(),
        "strategy": t.strategy,
        "profile": PROFILES[target],
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
        "input_fields": INPUT_FIELDS,
        "output_fields": OUTPUT_FIELDS,
    }


def render_three_level(model: Model, tables: ThreeLevelTables, target: str) -> dict[str, str]:
    """File name -> text of the generated three-level controller for ``target``."""
    env = environment()
    ctx = three_level_context(model, tables, target)
    p = model.prefix
    return {
        f"{p}_mpc.h": env.get_template("threelevel/mpc.h.j2").render(ctx),
        f"{p}_mpc.c": env.get_template("threelevel/mpc.c.j2").render(ctx),
        "mpc_binding.h": env.get_template("threelevel/binding.h.j2").render(ctx),
    }


def render_cdef(model: Model, tables: ThreeLevelTables) -> str:
    """cffi declarations (no preprocessor lines) of the host build."""
    return environment().get_template("threelevel/cdef.h.j2").render(three_level_context(model, tables, "host"))
