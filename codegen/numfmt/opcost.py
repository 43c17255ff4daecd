"""What one essential operation of the algorithm costs in each number format, in instructions: the cycle bound's
per-format table (``mpcgen bench --emulated``, ``codegen.stages.cycles.instruction_totals``).

The topologies count the operations their algorithm cannot do without
(``codegen/topologies/*/opcount.py``: ``add``, ``mul``, ``cmp``, ``sqrt``,
``div``, ``load``, ``store``); a number format says which instructions each
one takes at least, by instruction class; the cycle model
(``codegen.stages.cycles``) gives each class its issue rule on the core.

Instruction classes: ``fp`` an FP instruction that writes a register
(VADD, VMUL, VSEL, ...), ``cmp`` a compare or branch of the float step (VCMP,
Bcc: they write no FP register), ``sqrt``/``div`` VSQRT/VDIV, ``load``,
``store``; integer: ``alu`` a plain data-processing instruction (ADD, SUB,
MOV, CMP, CLZ, UXTH, an IT), ``shift`` one that uses the shifter (LSL, LSR,
ASR, or an operand shifted by an immediate: ``ORR r, a, b, LSL #n``),
``mac`` a multiply (MUL, MLS, SMULL, SMLAL, UMULL), ``udiv`` UDIV,
``branch`` a conditional branch.

**float32**: one instruction an operation.

**fixed** (``templates/numfmt/fixed.j2``, numerics.md "Fixed-point path"):
each operation the shortest sequence its helper's result needs on
ARMv7-M, every instruction put in the least constrained class it could
belong to (an instruction that may be a plain ALU operation counts as one),
so the sum is a lower bound for any compiled form of the helper:

* ``add`` (every operation of the algorithm that writes a value and is no
  product: add, sub, abs, neg, select, convert): ADDS and the branch on
  overflow (BVS) to the saturation; a select is at least an IT and a MOV,
  an absolute value a compare and a conditional negation;
* ``mul``: the round-half-up constant as the accumulator (two MOVs), one
  SMLAL, the result's word from the two words of the product (LSR of the
  low word, ORR of the high word shifted left: two shifter operations) and
  the saturation test, whether the high word lies in [-2^(G-1), 2^(G-1))
  (ADD of 2^(G-1), CMP with 2^G, a branch);
* ``div`` (``q_div``): the signs (EOR; two absolute values, two
  instructions each), the zero-divisor test (CBZ) and the overflow test (CMP
  of the divisor with |a| shifted: one shifter operation, a branch), the
  normalisation (CLZ; the divisor shifted; the numerator |a| 2^(G+s) as two
  words: ADD, RSB and two shifts), the 16-bit halves of divisor and
  numerator (two shifts, two UXTH), per digit one UDIV, its remainder (MLS)
  and the correction test (CMP, a branch), the partial and the final
  remainder (MLS each), then the rounding (SUB, CMP, ADD);
* ``sqrt`` (``q_sqrt``): the test a <= 0 (a compare and a branch), CLZ and
  its parity (two ALU operations), the normalised an = a << m (a shift), the
  seed (a shift, a multiply, the add of the product shifted), two Newton steps (UDIV, ADD and
  LSR each), the cap and the correction (a multiply for y*y, three ALU
  operations: USAT, CMP, SBC), the last Newton step on an 2^30 (SUB of s*s,
  which y*y gives, LSL, UDIV and the shifted add), the shift back (ADD, LSR
  and the shift by register) and the 64-bit test (UMULL of t*t, a shift for
  each word of a 2^G, CMP, SBCS and the conditional subtraction);
* ``cmp``: one CMP (the branch or select on it is another operation's);
  ``load``, ``store``: one LDR, STR.

``tests/numfmt/test_opcost.py`` writes each fixed-point sequence out as
Thumb-2 instructions and checks its classes against llvm-mca's Cortex-M7
model (``codegen.stages.cycles``: the resources each instruction uses).
"""
from __future__ import annotations

__all__ = ["OPERATIONS", "INSTRUCTION_CLASSES", "FLOAT_OP_COSTS", "FIXED_OP_COSTS"]

#: the essential operations the topologies count (``Topology.essential_ops``)
OPERATIONS = ("add", "mul", "cmp", "sqrt", "div", "load", "store")
#: the instruction classes a cost names (``codegen.stages.cycles`` gives each its issue rule)
INSTRUCTION_CLASSES = ("fp", "cmp", "sqrt", "div", "load", "store", "alu", "shift", "mac", "udiv", "branch")

#: a float format: one instruction an operation (an add or a product is one FP write)
FLOAT_OP_COSTS: dict[str, dict[str, int]] = {
    "add": {"fp": 1}, "mul": {"fp": 1}, "cmp": {"cmp": 1}, "sqrt": {"sqrt": 1}, "div": {"div": 1},
    "load": {"load": 1}, "store": {"store": 1},
}

#: fixed point: the shortest integer sequence of each operation's helper (module docstring)
FIXED_OP_COSTS: dict[str, dict[str, int]] = {
    "add": {"alu": 1, "branch": 1},
    "mul": {"alu": 4, "mac": 1, "shift": 2, "branch": 1},
    "div": {"alu": 15, "shift": 6, "mac": 4, "udiv": 2, "branch": 4},
    "sqrt": {"alu": 13, "shift": 11, "mac": 3, "udiv": 3, "branch": 1},
    "cmp": {"alu": 1},
    "load": {"load": 1},
    "store": {"store": 1},
}
