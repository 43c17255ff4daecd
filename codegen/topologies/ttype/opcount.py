"""Essential operations of the three-level MPDTC step, counted from its algorithm (``reference.py``),
for the cycle lower bounds of ``mpcgen bench --emulated`` (``codegen.stages.cycles.op_totals``, ``model_bound``, ``overlap_bound``).

Counts, not measurements: the operations that write a value (products
``mul``, the others ``add``), the compares and branches, square roots, divisions, loads and stores the
algorithm cannot do without, per step, per evaluated voltage
group (``n_eval``), per resolved member (``n_members``: the redundant
states' neutral-point test), per virtual member (63-MPDTC: the
neutral-point deadbeat's sums, numerator, clamps and charge) and per
unclamped T_N (its division: a T_N clamped to T_N_min or Ts/3 is decided by
signs and compares, so only a T_N strictly inside needs the quotient).
``plugin.op_multiplicities`` gives each unit's count per state.
"""
from __future__ import annotations

from typing import Any

from codegen.kernels.guard import guard_ops
from codegen.kernels.trig import SINCOS_TABLE_LOADS, sincos_ops
from codegen.topologies.ttype.records import GUARD


def essential_ops(tables: Any) -> dict[str, dict[str, int]]:
    """``{"per_step": counts, "per_candidate": counts, "per_member": counts, "per_virtual_member":
    counts, "per_unclamped": counts}``, counts with keys ``add``, ``mul``, ``cmp``, ``sqrt``, ``div``,
    ``load``, ``store``."""
    sincos, sincos_consts = sincos_ops(tables.nf)  # one generated sin/cos in the step's format
    basic_only = tables.n_sectors == 1  # 27-MPDTC
    guard = guard_ops(GUARD)
    # guard, theta(k+1), theta(k+2) (omega Ts, two sums), three sin/cos
    add, mul = guard["add"] + 2 + 3 * sincos["add"], 1 + 3 * sincos["mul"]
    # Clarke 1 + 2, Park 4 + 2, i_c 0 + 1, V cos/sin 2 + 0, Euler bases 4 + 2, Euler step (delay) 4 + 4
    # (products + sums)
    mul += 1 + 4 + 2 + 4 + 4
    add += 2 + 2 + 1 + 2 + 4
    # neutral-point patterns 0 + 3, charge 1 + 3, V_o(k+1) 1 + 1
    mul, add = mul + 1 + 1, add + 3 + 3 + 1
    # flux 2 + 1, torque 1 + 0, |psi|^2 2 + 1
    mul, add = mul + 2 + 1 + 2, add + 1 + 1
    # MTPA flux reference (iq*, psi_q*) 2 + 0, its |.|^2 1 + 2
    mul, add = mul + 2 + 1, add + 2
    # three inverse Parks 12 + 6, deadbeat voltage 4 + 4, 12-sector test (x tan30, x tan60) 2 + 0,
    # inverse Clarke 2 + 2
    mul, add = mul + 12 + 4 + 2 + 2, add + 6 + 4 + 2
    cmp = guard["cmp"] + 4  # the guard's compares; the 12-sector test's: half plane, sign of x, two angles
    # V cos/sin (k+1) 2 + 0, Euler bases (k+1) 4 + 2, output segments 1 + 3
    mul, add = mul + 2 + 4 + 1, add + 2 + 3
    if basic_only:  # |V_o(k+2)| per charge pattern: 2 + 2 each
        mul, add = mul + 8 * 2, add + 8 * 2
    # then a compare (27) / charge, V_o(k+2), |.| (1 + 2), then a compare (63)
    member = {"add": 0, "mul": 0} if basic_only else {"add": 2, "mul": 1}
    return {
        "per_step": {"add": add, "mul": mul, "cmp": cmp, "sqrt": 2, "div": 0,
                     "load": 6 + 30 + sincos_consts + 3 * SINCOS_TABLE_LOADS, "store": 20},
        # Euler step 4 + 4, flux 2 + 1, torque 1 + 0, |psi|^2 2 + 1, cost 2 + 6 (two differences, their
        # absolute values, two weights, two sums)
        "per_candidate": {"add": 4 + 1 + 0 + 1 + 6, "mul": 4 + 2 + 1 + 2 + 2, "cmp": 1, "sqrt": 1, "div": 0,
                          "load": 4, "store": 2},
        "per_member": {**member, "cmp": 1, "sqrt": 0, "div": 0, "load": 2, "store": 0},
        # a virtual member's deadbeat beyond a basic member's charge: A (2 adds), D, Ts/3 A and the
        # numerator, T_N D and its sum in Q (the charge Ts i_o it replaces: one product less); the
        # zero-divisor test and the two clamps; two more segment patterns
        "per_virtual_member": {"add": 2 + 1 + 1 + 1, "mul": 1 + 1 - 1, "cmp": 3, "sqrt": 0, "div": 0, "load": 2,
                               "store": 0},
        "per_unclamped": {"add": 0, "mul": 0, "cmp": 0, "sqrt": 0, "div": 1, "load": 0, "store": 0},
    }
