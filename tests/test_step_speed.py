"""Issue #12 item 3 (fast Cortex-M7 steps): the speed-ups keep the bits.

The T-type step computes the 8 distinct midpoint currents once per step (a per-vector pattern table
indexes them) instead of 0/1-coefficient products per candidate: the pattern values must equal the
coefficient formula (ka i_a + kb i_b) + kc i_c bit for bit, signed zeros and non-finite currents
included.  The steps contain no struct copy and no out-of-line sin/cos; the firmware Makefile unrolls
the step's loops and keeps -ffp-contract=off.
"""
from __future__ import annotations

import re

import numpy as np
import pytest

from codegen.cli import main
from codegen.config import load_config
from codegen.kernels.consts import Constants
from codegen.topologies.ttype import vectors
from codegen.topologies.ttype.reference import _Midpoint
from codegen.topology import topology_of

from conftest import SPMSM, TTYPE


@pytest.mark.parametrize("fmt", ["float32", "fixed"])
def test_midpoint_patterns_equal_the_coefficient_formula_bit_for_bit(fmt):
    m = load_config(TTYPE, {"controller.number_format": fmt})
    t = topology_of(m).derive(m)
    o = t.nf.ops
    pat, seq_pat = t.io_pattern, t.seq_pat
    assert len(pat) == 27 and sorted(set(pat)) == list(range(8))
    assert all(len(set(seq_pat[v])) == 1 and seq_pat[v][0] == pat[v] for v in range(27))  # basic: own state
    rng = np.random.default_rng(12)
    n = 4096
    if fmt == "float32":
        special = np.array([0.0, -0.0, 1.0, -1.0, np.inf, -np.inf, 1e-45, -1e-45], np.float32)
        ia = np.concatenate([rng.normal(0, 20, n).astype(np.float32), np.repeat(special, 64)])
        ib = np.concatenate([rng.normal(0, 20, n).astype(np.float32), np.tile(special, 64)])
    else:
        lim = np.iinfo(np.int32)
        special = np.array([0, 1, -1, lim.max, lim.min], np.int32)
        ia = np.concatenate([rng.integers(lim.min, lim.max, n, dtype=np.int32), np.repeat(special, 5)])
        ib = np.concatenate([rng.integers(lim.min, lim.max, n, dtype=np.int32), np.tile(special, 5)])
    with np.errstate(invalid="ignore", over="ignore"):  # inf - inf, 0 inf: NaN on both sides
        ic = o.neg(o.add(ia, ib))
        table = _Midpoint(o, t, Constants(t.consts)).patterns(ia, ib, ic)
        coef = [[t.nf.const(float(k)) for k in s.io] for s in vectors.STATES]  # the format's 0 and 1
        ka, kb, kc = (o.array([c[j] for c in coef]) for j in range(3))
        for s in range(27):
            want = o.add(o.add(o.mul(ka[s], ia), o.mul(kb[s], ib)), o.mul(kc[s], ic))
            assert table[pat[s]].tobytes() == np.asarray(want).tobytes(), s


@pytest.mark.parametrize("path,strategy", [(TTYPE, "mpdtc27"), (TTYPE, "mpdtc63"), (SPMSM, "conventional"),
                                           (SPMSM, "s3")])
def test_step_has_no_struct_copy_and_inline_sincos(tmp_path, path, strategy):
    tables = ["--tables", "published"] if strategy == "s3" else []  # generate never trains
    assert main(["generate", str(path), "--strategy", strategy, "--target", "stm32h743", "-o", str(tmp_path),
                 "-q", *tables]) == 0
    code = re.sub(r"/\*.*?\*/", "", next(tmp_path.glob("*_mpc.c")).read_text(), flags=re.S)
    assert "zero_out" not in code and "*out =" not in code
    # one angle, three interleaved, or (float32 s1-s3) one angle's reduction and finish
    assert re.search(r"static inline void \w+_sincos(3|_reduce)?\(", code)


def _step_body(code: str, prefix: str) -> str:
    return code[code.index(f"void {prefix}_step("):]


@pytest.mark.parametrize("strategy,fmt,ahead", [("s1", "float32", True), ("s3", "float32", True),
                                                ("conventional", "float32", False), ("s1", "fixed", False)])
def test_the_held_steps_arithmetic_runs_ahead_of_the_guard_only_in_float32(tmp_path, strategy, fmt, ahead):
    """Float32 s1-s3: the sin/cos reduction, Clarke, L i and V dt come before the guard's branch (float
    arithmetic is defined for every input); the table index only after it.  Fixed point (integer
    arithmetic could overflow on an unguarded input) and conventional keep the guard first.  The s1-s3
    evaluation is a function of its own, out of line under GCC and clang, in RAM on the F28377."""
    tables = ["--tables", "published"] if strategy == "s3" else []  # generate never trains
    assert main(["generate", str(SPMSM), "--strategy", strategy, "--number-format", fmt, "--target",
                 "tms320f28377", "-o", str(tmp_path), "-q", *tables]) == 0
    code = re.sub(r"/\*.*?\*/", "", (tmp_path / "spmsm_mpc.c").read_text(), flags=re.S)
    body = _step_body(code, "spmsm")
    guard = body.index("fault = spmsm_guard(in);")
    if ahead:
        assert body.index("spmsm_sincos_reduce(in->theta_e_rad") < guard < body.index("spmsm_sincos_finish(")
        assert body.index("vdt = ") < guard
    else:
        assert body.index("spmsm_sincos(in->theta_e_rad") > guard and "_sincos_reduce" not in code
    held = strategy != "conventional"
    assert ("spmsm_evaluate(in, out, row" in body) == held
    assert ('#pragma CODE_SECTION(spmsm_evaluate, ".TI.ramfunc")' in code) == held
    if held:
        assert re.search(r"__attribute__\(\(noinline\)\)\s*#endif\s*static SPMSM_CODE void spmsm_evaluate\(", code)


def test_firmware_makefile_unrolls_the_step_and_keeps_fp_contract_off(tmp_path):
    assert main(["firmware", str(SPMSM), "--board", "qemu-m7", "-o", str(tmp_path), "-q"]) == 0
    mk = (tmp_path / "Makefile").read_text()
    assert re.search(r"^build/gen/%_mpc\.o: CFLAGS \+= \$\(STEP_CFLAGS\)$", mk, re.M)
    assert "STEP_CFLAGS = -funroll-loops" in mk and "-ffp-contract=off" in mk
