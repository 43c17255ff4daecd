"""The cycle bound's instructions per essential operation (codegen.numfmt.opcost): each fixed-point cost is a
sequence written out below in Thumb-2, which the Cortex-M7 model takes at least the bound of."""
from __future__ import annotations

import re

import numpy as np
import pytest

from codegen.numfmt import FORMATS
from codegen.numfmt.opcost import FIXED_OP_COSTS, FLOAT_OP_COSTS, INSTRUCTION_CLASSES, OPERATIONS
from codegen.stages import cycles

# Each fixed-point helper's shortest sequence (G = 19), as the module docstring lists it.  ``q_mul``:
# the rounding constant as the accumulator, SMLAL, the result word, the saturation test.
MUL = """
    mov.w r2, #262144
    movs r3, #0
    smlal r2, r3, r0, r1
    lsrs r2, r2, #19
    orr.w r0, r2, r3, lsl #13
    add.w r4, r3, #262144
    cmp.w r4, #524288
    bhs .Lt
"""
# ``q_div``: signs, zero and overflow tests, normalisation, halves, two digits, remainders, rounding
DIV = """
    eor.w r2, r0, r1
    eor.w r3, r0, r0, asr #31
    sub.w r3, r3, r0, asr #31
    eor.w r4, r1, r1, asr #31
    sub.w r4, r4, r1, asr #31
    cbz r4, .Lt
    cmp.w r4, r3, lsr #12
    bls .Lt
    clz r5, r4
    lsl.w r4, r4, r5
    add.w r6, r5, #19
    rsb.w r7, r6, #32
    lsr.w r8, r3, r7
    lsl.w r9, r3, r6
    lsr.w r10, r4, #16
    uxth r11, r4
    lsr.w r12, r9, #16
    uxth lr, r9
    udiv r0, r8, r10
    mls r1, r0, r10, r8
    cmp.w r0, #65536
    bhs .Lt
    mls r1, r0, r4, r1
    udiv r6, r1, r10
    mls r7, r6, r10, r1
    cmp.w r6, #65536
    bhs .Lt
    mls r7, r6, r4, r7
    subs r5, r4, r7
    cmp r7, r5
    adc r0, r6, #0
"""
# ``q_sqrt``: a <= 0, CLZ and parity, an, seed, two Newton steps, cap and correction, the last Newton
# step, the shift back, the 64-bit test
SQRT = """
    cmp r0, #0
    ble .Lt
    clz r1, r0
    bic r1, r1, #1
    lsl.w r2, r0, r1
    lsr.w r3, r2, #16
    mul r3, r3, r9
    add.w r3, r10, r3, lsr #16
    udiv r4, r2, r3
    add r3, r3, r4
    lsr.w r3, r3, #1
    udiv r4, r2, r3
    add r3, r3, r4
    lsr.w r3, r3, #1
    usat r3, #16, r3
    mul r5, r3, r3
    cmp r2, r5
    sbc r3, r3, #0
    subs r6, r2, r5
    lsl.w r6, r6, #14
    udiv r6, r6, r3
    add.w r6, r6, r3, lsl #15
    add.w r7, r1, #11
    lsr.w r7, r7, #1
    lsr.w r6, r6, r7
    umull r8, r11, r6, r6
    lsl.w r12, r0, #19
    lsr.w lr, r0, #13
    cmp r12, r8
    sbcs r4, lr, r11
    sbc r0, r6, #0
"""
ADD = """
    adds r0, r0, r1
    bvs .Lt
"""
SEQUENCES = {"add": ADD, "mul": MUL, "div": DIV, "sqrt": SQRT, "cmp": "    cmp r0, r1\n",
             "load": "    ldr r0, [r1, #4]\n", "store": "    str r0, [r1, #4]\n"}

_SHIFTED = re.compile(r",\s*(lsl|lsr|asr|ror)\b")


def _class(line: str) -> str:
    """An instruction's class by its form (``codegen.numfmt.opcost``; a USAT uses the shifter)."""
    mnemonic = line.split()[0].split(".")[0]
    if mnemonic == "udiv":
        return "udiv"
    if mnemonic in ("mul", "mls", "smull", "smlal", "umull"):
        return "mac"
    if mnemonic in ("bhs", "bls", "ble", "bvs", "cbz"):
        return "branch"
    if mnemonic in ("ldr", "str"):
        return "load" if mnemonic == "ldr" else "store"
    if mnemonic in ("lsl", "lsr", "lsls", "lsrs", "usat") or _SHIFTED.search(line):
        return "shift"
    return "alu"


def _lines(seq: str) -> list[str]:
    return [line.strip() for line in seq.strip().splitlines()]


def test_every_format_costs_every_operation():
    for nf in FORMATS.values():
        assert set(nf.op_costs) == set(OPERATIONS), nf.name
        assert all(set(c) <= set(INSTRUCTION_CLASSES) and all(n > 0 for n in c.values())
                   for c in nf.op_costs.values()), nf.name
    # float32: one instruction an operation, in the classes the float bound always counted
    assert FLOAT_OP_COSTS == {"add": {"fp": 1}, "mul": {"fp": 1}, "cmp": {"cmp": 1}, "sqrt": {"sqrt": 1},
                              "div": {"div": 1}, "load": {"load": 1}, "store": {"store": 1}}
    # fixed point: no FP instruction
    assert not any(set(c) & {"fp", "sqrt", "div"} for c in FIXED_OP_COSTS.values())


@pytest.mark.parametrize("op", OPERATIONS)
def test_fixed_cost_is_its_sequence(op):
    # the written sequence has the cost's instructions: the same multiplies, divisions and branches, the
    # same length; the cost may count as a plain ALU operation what the sequence does with the shifter
    lines = _lines(SEQUENCES[op])
    got: dict[str, int] = {}
    for line in lines:
        got[_class(line)] = got.get(_class(line), 0) + 1
    cost = FIXED_OP_COSTS[op]
    assert len(lines) == sum(cost.values())
    for cls in ("mac", "udiv", "branch", "load", "store"):
        assert got.get(cls, 0) == cost.get(cls, 0), cls
    assert got.get("shift", 0) >= cost.get("shift", 0)


@pytest.mark.parametrize("op", OPERATIONS)
def test_fixed_sequence_takes_at_least_its_bound(op):
    # llvm-mca's Cortex-M7 model on the written sequence: at least the model bound of its cost
    lines = [f"\t{line}" for line in _lines(SEQUENCES[op])]
    bound = cycles.model_bound({k: np.array([float(v)]) for k, v in FIXED_OP_COSTS[op].items()})[0]
    assert cycles.mca_cycles(lines) >= bound
