"""The cycle estimate's pipeline model and tracer against cases counted by hand (codegen.stages.cycles)."""
from __future__ import annotations

import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

from codegen.numfmt import FIXED, FLOAT32
from codegen.numfmt.opcost import FIXED_OP_COSTS, INSTRUCTION_CLASSES
from codegen.stages import cycles

from conftest import require_tool

# llvm-mca and arm-none-eabi-gcc are not optional: scripts/bootstrap.sh installs them, and a missing
# tool fails these tests (cycles.CycleError or require_tool names the Debian package) instead of
# skipping them.


@pytest.mark.parametrize("n", [4, 16])
def test_dependent_vadd_chain_is_three_cycles_each(n):
    # Cortex-M7 VADD.F32 latency 3: a chain of N dependent adds takes about 3N cycles
    c = cycles.mca_cycles(["\tvadd.f32\ts0, s0, s1"] * n)
    assert 3 * n <= c <= 3 * n + 3


def test_vsqrt_then_dependent_use():
    # VSQRT.F32 ~14 cycles, then a dependent VADD (3)
    c = cycles.mca_cycles(["\tvsqrt.f32\ts0, s1", "\tvadd.f32\ts2, s0, s1"])
    assert 14 + 3 <= c <= 14 + 3 + 2


def test_independent_operations_dual_issue():
    # two integer ALU operations (or a load and an ALU operation) per cycle when independent
    independent = [f"\tadd.w\tr{r}, r1, #{r}" for r in (0, 2, 3, 4)]
    assert cycles.mca_cycles(independent) <= 3
    assert cycles.mca_cycles(["\tadd.w\tr0, r0, #1"] * 4) >= 4
    assert cycles.mca_cycles(["\tvldr\ts0, [r0]", "\tadd.w\tr2, r1, #2", "\tvldr\ts1, [r0, #4]",
                              "\tadd.w\tr4, r1, #2"]) <= 3
    # independent FP operations issue one per cycle (the last result 3 cycles later), a chain waits
    fp = [f"\tvadd.f32\ts{d}, s2, s3" for d in (0, 4, 5, 6)]
    assert cycles.mca_cycles(fp) <= 4 + 3
    assert cycles.mca_cycles(["\tvadd.f32\ts0, s0, s3"] * 4) >= 4 * 3


def test_the_model_holds_issue_behind_vsqrt():
    # LLVM 14's in-order Cortex-M7 model writes results back in order: ten independent VADDs after a
    # VSQRT.F32 wait for it (the overlap bound lets the square-root unit overlap everything else)
    adds = [f"\tvadd.f32\ts{d}, s3, s4" for d in range(5, 15)]
    assert cycles.mca_cycles(["\tvsqrt.f32\ts0, s1", *adds]) >= cycles.mca_cycles(adds) + 12


def test_a_traced_call_costs_what_a_branch_costs():
    # the path holds the callee's instructions: a BL is the taken branch it is, not llvm-mca's
    # 100-cycle untraced call
    body = ["\tmovs\tr1, #0", "\tstr\tr1, [r0]", "\tbx\tlr"]
    raw = subprocess.run([cycles.llvm_mca(), *cycles.MCA_ARGS], input="\n".join(["\tbl\t.Lt", *body, ".Lt:"]) + "\n",
                         capture_output=True, text=True, timeout=60)
    untraced = re.search(r"^Total Cycles:\s+(\d+)", raw.stdout, re.M)
    assert untraced and int(untraced.group(1)) > 50  # what the substitution is for
    assert cycles._substitute("\tbl\t.Lt") == "\tb\t.Lt"
    assert cycles.mca_cycles(["\tbl\t.Lt", *body]) < 20


def test_objdump_forms_the_model_lacks_are_substituted():
    # IT blocks, vcmpe, compare with zero, VFP immediates, writeback with .w
    block = ["\tvcmpe.f32\ts13, s15", "\tvcmp.f32\ts11, #0", "\tvmrs\tAPSR_nzcv, fpscr", "\tit\thi",
             "\torrhi.w\tr3, r3, #8", "\tite\tge", "\tmovge\tr0, r1", "\tmovlt\tr0, r2", "\tbhi.n\t.Lt",
             "\tldrh\tr7, [r4], #2", "\tvmov.f32\ts5, #0.5"]
    # the same block in the forms the model knows, timed identically
    known = ["\tvcmp.f32\ts13, s15", "\tvcmp.f32\ts11, s11", "\tvmrs\tAPSR_nzcv, fpscr", "\tnop",
             "\torr.w\tr3, r3, #8", "\tnop", "\tmov\tr0, r1", "\tmov\tr0, r2", "\tbhi.n\t.Lt",
             "\tldrh\tr7, [r4], #2", "\tvmov.f32\ts5, #0.5"]
    assert cycles.mca_cycles(block) == cycles.mca_cycles(known) > 0


def _totals(**counts: int) -> dict[str, np.ndarray]:
    """Instruction totals of one state (classes not named: zero)."""
    return {k: np.array([float(counts.get(k, 0))]) for k in INSTRUCTION_CLASSES}


def test_op_totals_per_step_candidate_member():
    ops = {"per_step": {"add": 6, "mul": 4, "cmp": 2, "sqrt": 0, "div": 0, "load": 4, "store": 0},
           "per_candidate": {"add": 3, "mul": 2, "cmp": 1, "sqrt": 1, "div": 0, "load": 2, "store": 0},
           "per_member": {"add": 1, "cmp": 1, "sqrt": 0, "div": 0, "load": 2, "store": 0}}
    t = cycles.op_totals(ops, {"per_candidate": np.array([0, 7]), "per_member": np.array([0, 3])})
    assert list(t["add"]) == [6, 6 + 21 + 3] and list(t["mul"]) == [4, 4 + 14]
    assert list(t["sqrt"]) == [0, 7] and list(t["load"]) == [4, 4 + 14 + 6]
    # any further unit, times its own multiplicity (e.g. a division per unclamped T_N)
    ops["per_unclamped"] = {"add": 0, "cmp": 0, "sqrt": 0, "div": 1, "load": 0, "store": 0}
    t = cycles.op_totals(ops, {"per_candidate": np.array([1, 7]), "per_member": np.array([1, 3]),
                               "per_unclamped": np.array([0, 2])})
    assert list(t["div"]) == [0, 2] and list(t["add"]) == [6 + 3 + 1, 6 + 21 + 3]
    del ops["per_unclamped"]
    # a first candidate without prediction (V0 of the flux-geometry step): its counts replace one candidate's
    ops["first_candidate"] = {"add": 2, "mul": 1, "cmp": 1, "sqrt": 0, "div": 0, "load": 0, "store": 0}
    t = cycles.op_totals(ops, {"per_candidate": np.array([0, 1, 7]), "per_member": np.zeros(3)})
    assert list(t["add"]) == [6, 8, 6 + 2 + 18] and list(t["sqrt"]) == [0, 0, 6]


def test_op_totals_needs_a_multiplicity_for_every_unit():
    ops = {"per_step": {"add": 1}, "per_candidate": {"add": 1}, "per_member": {"add": 1}}
    with pytest.raises(cycles.CycleError, match="multiplicities"):
        cycles.op_totals(ops, {"per_candidate": np.array([1])})
    with pytest.raises(cycles.CycleError, match="multiplicities"):
        cycles.op_totals(ops, {"per_candidate": np.array([1]), "per_member": np.array([1]), "per_x": np.array([1])})


def test_op_totals_refuses_an_operation_no_format_costs():
    # the algorithm counts operations, never instructions: "fp" is a float32 instruction class
    ops = {"per_step": {"fp": 1}, "per_candidate": {"add": 1}}
    with pytest.raises(cycles.CycleError, match="not among"):
        cycles.op_totals(ops, {"per_candidate": np.array([1])})


def test_instruction_totals_per_number_format():
    t = {k: np.array([float(n)]) for k, n in
         {"add": 10, "mul": 6, "cmp": 3, "sqrt": 1, "div": 2, "load": 5, "store": 4}.items()}
    # float32: one instruction an operation; an add and a product are both FP writes
    f = cycles.instruction_totals(t, FLOAT32.op_costs)
    assert (f["fp"][0], f["cmp"][0], f["sqrt"][0], f["div"][0], f["load"][0], f["store"][0]) == (16, 3, 1, 2, 5, 4)
    assert all(f[k][0] == 0 for k in ("alu", "shift", "mac", "udiv", "branch"))
    # fixed point: each operation its helper's integer sequence, no FP instruction at all
    x = cycles.instruction_totals(t, FIXED.op_costs)
    assert x["fp"][0] == x["cmp"][0] == x["sqrt"][0] == x["div"][0] == 0
    costs = FIXED_OP_COSTS
    for cls in ("alu", "shift", "mac", "udiv", "branch"):
        assert x[cls][0] == sum(int(t[op][0]) * costs[op].get(cls, 0) for op in t), cls
    assert x["mac"][0] == 6 * 1 + 2 * 4 + 1 * 3 and x["udiv"][0] == 2 * 2 + 1 * 3
    with pytest.raises(cycles.CycleError, match="no cost"):
        cycles.instruction_totals(t, {k: v for k, v in FIXED_OP_COSTS.items() if k != "div"})
    with pytest.raises(cycles.CycleError, match="no issue rule"):
        cycles.instruction_totals(t, {**FIXED_OP_COSTS, "div": {"vdivx": 1}})


def test_overlap_bound_lets_every_unit_overlap():
    assert cycles.overlap_bound(_totals(fp=10, cmp=2, load=4))[0] == 12  # FP issue
    assert cycles.overlap_bound(_totals(fp=40, sqrt=7))[0] == 14 * 7  # the square-root unit
    assert cycles.overlap_bound(_totals(fp=5, load=20, store=4))[0] == 24  # memory
    # integer units: two a cycle, one shifter operation, multiply, branch a cycle, the divider
    assert cycles.overlap_bound(_totals(alu=30, shift=4, load=2))[0] == 18
    assert cycles.overlap_bound(_totals(alu=2, shift=9, mac=3))[0] == 9
    assert cycles.overlap_bound(_totals(alu=4, udiv=3))[0] == 18


def test_an_estimate_below_its_bound_is_an_error():
    cycles.check_bound("x_step", np.array([100.0, 90.0]), np.array([80.0, 90.0]))  # at the bound: fine
    with pytest.raises(cycles.CycleError, match="1 of 2 states"):
        cycles.check_bound("x_step", np.array([100.0, 89.0]), np.array([80.0, 90.0]))


def test_model_bound_adds_what_the_model_cannot_overlap():
    # FP writes alone, 13 cycles a square root, compares + memory two a cycle (one store a cycle)
    assert cycles.model_bound(_totals(fp=10, sqrt=2, cmp=3, load=5, store=2))[0] == 10 + 26 + 5
    assert cycles.model_bound(_totals(fp=1, store=6, load=2))[0] == 1 + 6
    # integer: 6 cycles a UDIV, alone; the rest two a cycle, one shifter operation, one multiply, one
    # branch, one store a cycle
    assert cycles.model_bound(_totals(alu=10, shift=2, mac=1, udiv=2, load=3))[0] == 12 + 8
    assert cycles.model_bound(_totals(alu=1, shift=7, mac=1))[0] == 7
    assert cycles.model_bound(_totals(alu=1, mac=5, branch=2))[0] == 5
    assert cycles.model_bound(_totals(alu=1, branch=4, store=1))[0] == 4


def test_the_fixed_point_bound_counts_integer_instructions():
    # the same operations bound far higher in fixed point than one instruction each: a product is an
    # SMLAL, its two words shifted together and a saturation test
    t = {k: np.array([float(n)]) for k, n in
         {"add": 20, "mul": 20, "cmp": 4, "sqrt": 1, "div": 0, "load": 10, "store": 6}.items()}
    fixed = cycles.model_bound(cycles.instruction_totals(t, FIXED.op_costs))[0]
    as_one_instruction = cycles.overlap_bound(cycles.instruction_totals(t, FLOAT32.op_costs))[0]
    assert fixed > 2 * as_one_instruction


# The model's issue rules the bound rests on, each counted by hand.

def test_the_model_issues_an_fp_write_alone():
    # a VADD never shares its cycle: not with an integer add, a load, a store; two loads do
    for other in ("\tadd.w\tr1, r2, #3", "\tvldr\ts5, [r0]", "\tldr\tr1, [r0]", "\tvstr\ts6, [r0]"):
        pair = [f"\tvadd.f32\ts{d}, s30, s31" if k % 2 == 0 else other for k, d in enumerate(range(8))]
        assert cycles.mca_cycles(pair) >= 8, other
    assert cycles.mca_cycles([f"\tvldr\ts{d}, [r0, #{4 * d}]" for d in range(8)]) <= 5


def test_the_model_pairs_a_compare():
    # a VCMP writes no register: it pairs with an integer operation
    block = ["\tvcmp.f32\ts0, s1", "\tadd.w\tr1, r2, #3"] * 4
    assert cycles.mca_cycles(block) <= 5


def test_the_model_holds_issue_13_cycles_a_square_root():
    # back to back, or followed by independent VMULs: 13 cycles each square root
    sq = [f"\tvsqrt.f32\ts{d}, s{d + 16}" for d in range(4)]
    assert 4 * 13 <= cycles.mca_cycles(sq) <= 4 * 13 + 4
    muls = [f"\tvmul.f32\ts{d}, s30, s29" for d in range(4, 14)]
    assert cycles.mca_cycles([sq[0], *muls]) >= 13 + 10


@pytest.mark.parametrize("seed", range(6))
def test_model_bound_is_a_bound_of_the_model(seed):
    # any order of independent operations of the counted kinds takes at least the model bound
    rng = np.random.default_rng(seed)
    counts = {"fp": int(rng.integers(5, 40)), "cmp": int(rng.integers(0, 12)), "sqrt": int(rng.integers(0, 4)),
              "div": int(rng.integers(0, 2)), "load": int(rng.integers(0, 30)), "store": int(rng.integers(0, 12))}
    forms = {"fp": "\tvmul.f32\ts{d}, s30, s29", "cmp": "\tvcmp.f32\ts28, s29", "sqrt": "\tvsqrt.f32\ts{d}, s29",
             "div": "\tvdiv.f32\ts{d}, s30, s29", "load": "\tvldr\ts{d}, [r0, #4]", "store": "\tstr\tr1, [r2, #8]"}
    kinds = [k for k, n in counts.items() for _ in range(n)]
    rng.shuffle(kinds)
    block = [forms[k].format(d=i % 24) for i, k in enumerate(kinds)]
    assert cycles.mca_cycles(block) >= cycles.model_bound(_totals(**counts))[0]


def test_the_model_holds_issue_6_cycles_a_udiv():
    # a UDIV issues alone and holds issue for 6 cycles: nothing pairs with it, before or after
    div = [f"\tudiv\tr{d}, r9, r10" for d in range(4)]
    assert 4 * 6 <= cycles.mca_cycles(div) <= 4 * 6 + 3
    adds = [f"\tadd.w\tr{d}, r11, r12" for d in range(4, 8)]
    assert cycles.mca_cycles([div[0], *adds]) >= 6 + 2
    assert cycles.mca_cycles([adds[0], div[0]]) >= 1 + 6


def test_the_model_integer_units():
    # plain ALU operations dual-issue; the shifter (a shift, an operand shifted by an immediate), the MAC
    # unit (MUL, MLS, SMULL, SMLAL, UMULL), stores and branches one a cycle each
    alu = [f"\tadd.w\tr{d}, r9, r10" for d in range(8)]
    assert cycles.mca_cycles(alu) <= 5
    for form in ("\tlsl.w\tr{d}, r9, #3", "\torr.w\tr{d}, r9, r10, lsl #13", "\tmul\tr{d}, r9, r10",
                 "\tsmull\tr{d}, r12, r9, r10", "\tmls\tr{d}, r9, r10, r11", "\tstr\tr{d}, [r9, #4]"):
        assert cycles.mca_cycles([form.format(d=d) for d in range(8)]) >= 8, form
    assert cycles.mca_cycles(["\tbne\t.Lt"] * 8) >= 8
    # ... but each pairs with an operation of another kind: SMLAL with an ALU operation, a shift with a load
    smlal_add = [f"\tsmlal\tr0, r1, r2, r3\n\tadd.w\tr{4 + d}, r9, r10" for d in range(4)]
    assert cycles.mca_cycles(smlal_add) <= 7
    lsl_ldr = [f"\tlsl.w\tr{d}, r9, #2\n\tldr\tr{4 + d}, [r10]" for d in range(4)]
    assert cycles.mca_cycles(lsl_ldr) <= 6


@pytest.mark.parametrize("seed", range(6))
def test_integer_model_bound_is_a_bound_of_the_model(seed):
    # any order of independent integer instructions of the counted classes takes at least the model bound
    rng = np.random.default_rng(100 + seed)
    counts = {"alu": int(rng.integers(5, 40)), "shift": int(rng.integers(0, 20)), "mac": int(rng.integers(0, 12)),
              "udiv": int(rng.integers(0, 3)), "branch": int(rng.integers(0, 8)), "load": int(rng.integers(0, 20)),
              "store": int(rng.integers(0, 10))}
    forms = {"alu": "\tadd.w\tr{d}, r9, r10", "shift": "\torr.w\tr{d}, r9, r10, lsr #19",
             "mac": "\tsmull\tr{d}, r11, r9, r10", "udiv": "\tudiv\tr{d}, r9, r10", "branch": "\tbne\t.Lt",
             "load": "\tldr\tr{d}, [r12, #4]", "store": "\tstr\tr9, [r12, #8]"}
    kinds = [k for k, n in counts.items() for _ in range(n)]
    rng.shuffle(kinds)
    block = [forms[k].format(d=i % 8) for i, k in enumerate(kinds)]
    assert cycles.mca_cycles(block) >= cycles.model_bound(_totals(**counts))[0]


SOURCE = """
float chain(const float *in, float *out)
{
    float x = in[0];
    int n = (int)in[3];
    for (int i = 0; i < n; ++i) { x = x * in[1] + in[2]; }
    x = __builtin_sqrtf(x);
    out[0] = x;
    return x;
}
void _start(void) { for (;;) {} }
"""


def test_trace_a_small_function(tmp_path: Path):
    require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi")
    src = tmp_path / "f.c"
    src.write_text(SOURCE)
    elf = tmp_path / "f.elf"
    subprocess.run(["arm-none-eabi-gcc", "-mcpu=cortex-m7", "-mthumb", "-mfpu=fpv5-d16", "-mfloat-abi=hard", "-O2",
                    "-ffp-contract=off", "-fno-math-errno", "-nostdlib", "-Wl,-Ttext=0x100", "-Wl,-Tdata=0x20000000",
                    str(src), "-o", str(elf)], check=True)
    states = np.array([[2.0, 1.5, 0.25, 3.0], [2.0, 1.5, 0.25, 8.0]], dtype=np.float32)
    tracer = cycles.StepTracer(elf, "chain")
    blocks, out = tracer.run(states[0].tobytes(), 4)
    expected = np.zeros((2, 1), np.float32)  # the function's result for each state, as the tracer must read it
    for row, n in enumerate((3, 8)):
        x = np.float32(2.0)
        for _ in range(n):
            x = np.float32(np.float32(x * np.float32(1.5)) + np.float32(0.25))
        expected[row, 0] = np.sqrt(x)
    assert np.frombuffer(out, np.float32)[0] == expected[0, 0]
    est = cycles.estimate_cycles(elf, "chain", states, expected)
    assert est.states == 2 and est.paths == 2  # 3 and 8 loop iterations
    # five more dependent multiply-add pairs (3 + 3 cycles each) on the longer path
    assert est.cycles[1] - est.cycles[0] >= 5 * 6
    # at least the square root and the chain: 14 + 3 x 6
    assert est.cycles[0] >= 14 + 3 * 6


def test_traced_outputs_compare_fields_not_padding():
    # an output record with tail padding (u16 fields after a float): the padding is not data, a field is
    dt = np.dtype({"names": ["x", "n"], "formats": [np.float32, np.uint16], "offsets": [0, 4], "itemsize": 8})
    want = np.zeros(1, dt)
    want["x"], want["n"] = 1.5, 7
    raw = bytearray(want.tobytes())
    raw[6:8] = b"\x63\x41"  # garbage in the padding
    assert cycles._same_fields(bytes(raw), want[0])
    raw[4] ^= 1  # n differs
    assert not cycles._same_fields(bytes(raw), want[0])
    neg_zero = want.copy()
    neg_zero["x"] = -0.0
    assert not cycles._same_fields(np.zeros(1, dt).tobytes(), neg_zero[0])  # bits, not values
    # an array without fields is compared whole
    assert cycles._same_fields(np.float32([2.0]).tobytes(), np.float32([2.0]))
    assert not cycles._same_fields(np.float32([2.0]).tobytes(), np.float32([3.0]))
