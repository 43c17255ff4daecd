"""Essential operations of the two-level step, counted from its algorithm (``reference.py``), for the
cycle lower bounds of ``mpcgen bench --emulated`` (``codegen.stages.cycles.op_totals``, ``model_bound``, ``overlap_bound``).

Counts, not measurements: the FP operations that write a register (add,
sub, mul, abs, convert, select), the compares and branches, square roots,
divisions, loads (inputs, constants, table cells) and stores (outputs) the
algorithm cannot do without, per step and per evaluated candidate
(``n_eval``).  With flux-geometry and V0 first in every
row, V0's prediction is the estimate itself: its first candidate counts only
the cost.  Float32 names; a fixed-point step does the same operations on
integers.
"""
from __future__ import annotations

from typing import Any

from codegen.kernels.guard import guard_ops
from codegen.kernels.trig import SINCOS_TABLE_LOADS, sincos_ops
from codegen.topologies.twolevel.records import GUARD


def essential_ops(tables: Any) -> dict[str, dict[str, int]]:
    """``{"per_step": counts, "per_candidate": counts}`` (and ``first_candidate``), counts with keys
    ``fp``, ``cmp``, ``sqrt``, ``div``, ``load``, ``store``."""
    sincos_fp, sincos_consts = sincos_ops(tables.nf)  # one generated sin/cos in the step's format
    geo = tables.predictor == "flux-geometry"
    guard = guard_ops(GUARD)
    fp, cmp = guard["fp"] + sincos_fp + 3, guard["cmp"]  # guard, sin/cos, Clarke
    if geo:
        fp += 2 + 4 + 1 + 4 + 3  # psi_f (cos, sin), alpha-beta flux, U_dc dt, torque, |psi|^2
        fp += 4 if tables.delay_compensation else 0
    else:
        fp += 6 + 1 + 2 + 3 + 4 + 3 + 6 + 6  # Park, |V|, V cos/sin, flux, torque, |psi|^2, inverse Park, Euler bases
        fp += 8 + 3 if tables.delay_compensation else 0
    if tables.psi_ref != "constant":
        fp += 3 + 1  # flux reference from the torque reference (table slope) and its inverse
    if tables.uses_threshold:
        fp, cmp = fp + 2, cmp + 1  # |T* - Te| <= eps: difference, absolute value; compare
        if tables.n_sectors > 1:
            fp += 2  # 12-sector test: x tan30, x tan60
            cmp += 4 + (1 if tables.n_conditions == 2 else 2)  # half plane, sign of x, two angles; condition signs
    # cost (+ the reference cost's weight, + lambda_psi); then a compare
    cost_fp = 7 + (1 if tables.cost != "rated" else 0) + (1 if tables.flux_weighted else 0)
    if geo:
        per_cand_fp = 4 + 4 + 3 + cost_fp  # flux predictor, torque, |psi|^2
    else:
        per_cand_fp = 9 + 3 + 4 + 3 + cost_fp  # Euler current step, flux, torque, |psi|^2
    n_const = 14 + sincos_consts + SINCOS_TABLE_LOADS
    ops = {
        "per_step": {"fp": fp, "cmp": cmp, "sqrt": 1, "div": 0, "load": 6 + n_const + 1, "store": 14},
        "per_candidate": {"fp": per_cand_fp, "cmp": 1, "sqrt": 1, "div": 0, "load": 3, "store": 2},
    }
    if tables.v0_first:  # V0 first in every row: its Te+ and |psi+| are the estimate's, only its cost is essential
        ops["first_candidate"] = {"fp": cost_fp, "cmp": 1, "sqrt": 0, "div": 0, "load": 0, "store": 2}
    return ops
