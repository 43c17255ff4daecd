"""Essential operations of the three-level MPDTC step, counted from its algorithm (``reference.py``),
for the cycle lower bounds of ``mpcgen bench --emulated`` (``codegen.stages.cycles.op_totals``, ``model_bound``, ``overlap_bound``).

Counts, not measurements: the FP operations that write a register, the
compares and branches, square roots, divisions, loads and stores the
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
    counts, "per_unclamped": counts}``, counts with keys ``fp``, ``cmp``, ``sqrt``, ``div``, ``load``,
    ``store``."""
    sincos_fp, sincos_consts = sincos_ops(tables.nf)  # one generated sin/cos in the step's format
    basic_only = tables.n_sectors == 1  # 27-MPDTC
    guard = guard_ops(GUARD)
    fp = guard["fp"] + 3 + 3 * sincos_fp  # guard, theta(k+1), theta(k+2), three sin/cos
    fp += 3 + 6 + 1 + 2 + 6 + 8  # Clarke, Park, i_c, V cos/sin, Euler bases, Euler step (delay)
    fp += 3 + 4 + 2  # neutral-point patterns, charge, V_o(k+1)
    fp += 3 + 1 + 3  # flux, torque, |psi|^2
    fp += 2 + 3  # MTPA flux reference (iq*, psi_q*), its |.|^2
    fp += 18 + 8 + 2 + 4  # three inverse Parks, deadbeat voltage, 12-sector test (x tan30, x tan60), inverse Clarke
    cmp = guard["cmp"] + 4  # the guard's compares; the 12-sector test's: half plane, sign of x, two angles
    fp += 2 + 6 + 4  # V cos/sin (k+1), Euler bases (k+1), output segments
    if basic_only:
        fp += 8 * 4  # |V_o(k+2)| per charge pattern
    per_member_fp = 0 if basic_only else 3  # then a compare (27) / charge, V_o(k+2), |.|, then a compare (63)
    return {
        "per_step": {"fp": fp, "cmp": cmp, "sqrt": 2, "div": 0,
                     "load": 6 + 30 + sincos_consts + 3 * SINCOS_TABLE_LOADS, "store": 20},
        "per_candidate": {"fp": 8 + 3 + 1 + 3 + 8, "cmp": 1, "sqrt": 1, "div": 0, "load": 4, "store": 2},
        "per_member": {"fp": per_member_fp, "cmp": 1, "sqrt": 0, "div": 0, "load": 2, "store": 0},
        # a virtual member's deadbeat beyond a basic member's charge: A (2 adds), D, Ts/3 A and the
        # numerator, T_N D and its sum in Q (the charge Ts i_o it replaces: -1); the zero-divisor
        # test and the two clamps; two more segment patterns
        "per_virtual_member": {"fp": 2 + 1 + 2 + 2 - 1, "cmp": 3, "sqrt": 0, "div": 0, "load": 2, "store": 0},
        "per_unclamped": {"fp": 0, "cmp": 0, "sqrt": 0, "div": 1, "load": 0, "store": 0},
    }
