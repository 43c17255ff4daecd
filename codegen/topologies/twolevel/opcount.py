"""Essential operations of the two-level step, counted from its algorithm (``reference.py``), for the
cycle lower bounds of ``mpcgen bench --emulated`` (``codegen.stages.cycles.op_totals``, ``model_bound``, ``overlap_bound``).

Counts, not measurements: the operations that write a value, split into
products (``mul``) and the others (``add``: add, sub, abs, convert,
select), the compares and branches, square roots,
divisions, loads (inputs, constants, table cells) and stores (outputs) the
algorithm cannot do without, per step and per evaluated candidate
(``n_eval``).  With flux-geometry and V0 first in every
row, V0's prediction is the estimate itself: its first candidate counts only
the cost.  The number format turns each operation into instructions
(``NumberFormat.op_costs``, ``codegen.numfmt.opcost``): one FP instruction
each in float32, the helper's integer sequence in fixed point.
"""
from __future__ import annotations

from typing import Any

from codegen.kernels.guard import guard_ops
from codegen.kernels.trig import SINCOS_TABLE_LOADS, sincos_ops
from codegen.topologies.twolevel.records import GUARD


def essential_ops(tables: Any) -> dict[str, dict[str, int]]:
    """``{"per_step": counts, "per_candidate": counts}`` (and ``first_candidate``), counts with keys
    ``add``, ``mul``, ``cmp``, ``sqrt``, ``div``, ``load``, ``store``."""
    sincos, sincos_consts = sincos_ops(tables.nf)  # one generated sin/cos in the step's format
    geo = tables.predictor == "flux-geometry"
    guard = guard_ops(GUARD)
    # guard, sin/cos, Clarke (ib + ib, ia + .., x 1/sqrt3)
    add, mul, cmp = guard["add"] + sincos["add"] + 2, sincos["mul"] + 1, guard["cmp"]
    if geo:
        # psi_f (cos, sin): 2 products; alpha-beta flux: 2 + 2; U_dc dt: 1 product; torque: 3 products,
        # 1 difference; |psi|^2: 2 + 1
        mul += 2 + 2 + 1 + 3 + 2
        add += 2 + 1 + 1
        if tables.delay_compensation:
            mul, add = mul + 2, add + 2
    else:
        # Park 4 + 2, |V| 1, V cos/sin 2, flux 2 + 1, torque 3 + 1, |psi|^2 2 + 1, inverse Park 4 + 2,
        # Euler bases 4 + 2 (products + sums)
        mul += 4 + 1 + 2 + 2 + 3 + 2 + 4 + 4
        add += 2 + 1 + 1 + 1 + 2 + 2
        if tables.delay_compensation:  # Euler step 4 + 4, its bases 1 + 2
            mul, add = mul + 4 + 1, add + 4 + 2
    if tables.psi_ref != "constant":
        # flux reference from the torque reference (table slope: 2 products, 1 sum) and its inverse
        # (a division, counted as one product: the float32 bound counts it as one FP write)
        mul, add = mul + 2 + 1, add + 1
    if tables.uses_threshold:
        add, cmp = add + 2, cmp + 1  # |T* - Te| <= eps: difference, absolute value; compare
        if tables.n_sectors > 1:
            mul += 2  # 12-sector test: x tan30, x tan60
            cmp += 4 + (1 if tables.n_conditions == 2 else 2)  # half plane, sign of x, two angles; condition signs
    # cost: two differences, their scalings and squares, the sum (+ the reference cost's weight,
    # + lambda_psi); then a compare
    cost = {"add": 3, "mul": 4 + (1 if tables.cost != "rated" else 0) + (1 if tables.flux_weighted else 0)}
    if geo:  # flux predictor 2 + 2, torque 3 + 1, |psi|^2 2 + 1
        cand = {"add": 2 + 1 + 1 + cost["add"], "mul": 2 + 3 + 2 + cost["mul"]}
    else:  # Euler current step 4 + 5, flux 2 + 1, torque 3 + 1, |psi|^2 2 + 1
        cand = {"add": 5 + 1 + 1 + 1 + cost["add"], "mul": 4 + 2 + 3 + 2 + cost["mul"]}
    n_const = 14 + sincos_consts + SINCOS_TABLE_LOADS
    ops = {
        "per_step": {"add": add, "mul": mul, "cmp": cmp, "sqrt": 1, "div": 0, "load": 6 + n_const + 1, "store": 14},
        "per_candidate": {**cand, "cmp": 1, "sqrt": 1, "div": 0, "load": 3, "store": 2},
    }
    if tables.v0_first:  # V0 first in every row: its Te+ and |psi+| are the estimate's, only its cost is essential
        ops["first_candidate"] = {**cost, "cmp": 1, "sqrt": 0, "div": 0, "load": 0, "store": 2}
    return ops
