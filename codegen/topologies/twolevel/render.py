"""Template context of the two-level step: values to print, already derived."""
from __future__ import annotations

from typing import Any

from codegen.model import Model
from codegen.render import TableRow, render_step, render_step_cdef, sincos_bound, step_context, table_fields
from codegen.topologies.twolevel.derive import DQ, TwoLevelTables
from codegen.topologies.twolevel.records import FAULT_BITS, GUARD, INPUT, N_VECTORS, OUTPUT


def _row_labels(t: TwoLevelTables) -> list[str]:
    if t.n_sectors == 1:
        return ["all candidates V0..V6"]
    names = {
        2: ["dT>0", "dT<0"],
        4: ["dT>0 dpsi>0", "dT>0 dpsi<=0", "dT<0 dpsi>0", "dT<0 dpsi<=0"],
    }[t.n_conditions]
    return [f"{names[c]}, sector {s + 1}" for c in range(t.n_conditions) for s in range(t.n_sectors)]


def two_level_context(model: Model, t: TwoLevelTables, target: str) -> dict[str, Any]:
    """Template context: values to print, already derived."""
    rows = [
        TableRow(tuple(r) + (0,) * (N_VECTORS - len(r)), f"{lab}: " + " ".join(f"V{v}" for v in r))
        for r, lab in zip(t.rows, _row_labels(t))
    ]
    return step_context(model, target, (INPUT, OUTPUT), FAULT_BITS, **{
        **table_fields(t), "topology_macro": "MPC_TOPOLOGY_TWO_LEVEL", "guard": GUARD, "dq": DQ,
        "rows_padded": rows, "row_len": t.row_len,
        "max_row_len": max(t.row_len), "min_row_len": min(t.row_len), "n_vectors": N_VECTORS,
        "v0_first": t.v0_first,
        "sincos_bound": sincos_bound(t.nf, "ANGLE_GUARD_RAD")})


def render_two_level(model: Model, t: TwoLevelTables, target: str) -> dict[str, str]:
    """File name -> text of the generated controller for ``target``."""
    return render_step(model, "twolevel", two_level_context(model, t, target))


def render_cdef(model: Model, t: TwoLevelTables) -> str:
    """cffi declarations (no preprocessor lines) of the host build."""
    return render_step_cdef(two_level_context(model, t, "host"))
