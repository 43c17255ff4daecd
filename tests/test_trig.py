"""The generated sin/cos: accuracy (a property) and determinism of the constants."""
from pathlib import Path

import numpy as np

from codegen.config import load_config
from codegen.kernels.trig import (
    ANGLE_GUARD_RAD,
    cos_names,
    sin_names,
    sincos_constants,
    sincos_f32,
    sincos_ops,
    sincos_table,
    table_index_bound,
)
from codegen.numfmt.fixed import FIXED
from codegen.numfmt.float32 import FLOAT32, c_float_literal, f32
from codegen.teststates import angle_reduction_borders
from codegen.topology import topology_of

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def test_accuracy_over_guard_range():
    rng = np.random.default_rng(0)
    x = np.concatenate([
        rng.uniform(-ANGLE_GUARD_RAD, ANGLE_GUARD_RAD, 1_000_000),
        np.linspace(0, 2 * np.pi, 200_001),
        np.arange(-326, 327) * (np.pi / 4),  # the fixed-point reduction's borders (N = 4)
        angle_reduction_borders(200_000, ANGLE_GUARD_RAD, FLOAT32.sincos_form.table_n, rng),  # float32's
    ]).astype(np.float32)
    s, c = sincos_f32(x)
    xd = x.astype(np.float64)
    assert np.abs(s - np.sin(xd)).max() < 2e-7
    assert np.abs(c - np.cos(xd)).max() < 2e-7
    assert s.dtype == np.float32 and c.dtype == np.float32


def test_exact_values_at_zero():
    s, c = sincos_f32(np.array([0.0, -0.0], np.float32))
    assert s[0] == 0 and c[0] == 1 and c[1] == 1


def test_step_split_keeps_fn_hi_exact():
    """fn STEP_HI is exact in float32 for every table index the angle guard lets in."""
    k = {name: v for name, v, *_ in sincos_constants(FLOAT32)}
    hi = f32(k["SINCOS_STEP_HI"])
    assert float(hi) == k["SINCOS_STEP_HI"]  # exactly representable
    assert float(hi) + k["SINCOS_STEP_LO"] == 2 * np.pi / FLOAT32.sincos_form.table_n
    n_max = table_index_bound(FLOAT32)
    assert n_max == 10430  # 256 rad * 256 / (2 pi)
    fn = np.arange(-2 * n_max, 2 * n_max + 1, dtype=np.float64)  # twice: the T-type extrapolates past the guard
    assert np.array_equal((fn.astype(np.float32) * hi).astype(np.float64), fn * float(hi))


def test_table_and_coefficients_per_format():
    """float32: 256 entries and one term each; fixed point: the quadrant (4 entries, the next test)
    and the degree-7/8 polynomial."""
    tab = sincos_table(FLOAT32)
    assert len(tab) == 512 and all(isinstance(v, np.float32) for v in tab)
    assert (tab[0], tab[1]) == (0.0, 1.0)
    assert (sin_names(FLOAT32.sincos_form), cos_names(FLOAT32.sincos_form)) == (["SIN_S3"], ["COS_C2"])
    assert (sin_names(FIXED.sincos_form), cos_names(FIXED.sincos_form)) == (["SIN_S3", "SIN_S5", "SIN_S7"], ["COS_C2", "COS_C4", "COS_C6", "COS_C8"])
    assert table_index_bound(FIXED) == 5  # 8 rad * 4 / (2 pi)
    k = {name: v for name, v, *_ in sincos_constants(FLOAT32)}
    assert abs(k["SIN_S3"] + 1 / 6) < 1e-5 and abs(k["COS_C2"] + 0.5) < 1e-5  # near Taylor: least squares
    # essential operations of one sin/cos (the cycle bound): 19 operations (8 sums and other writes, 11
    # products) and 5 constant loads in float32 (plus the 2 table loads of each angle)
    assert sincos_ops(FLOAT32) == ({"add": 8, "mul": 11}, 5)
    # fixed point: degree-7/8 polynomials, Horner: 3 + 4 products, 2 + 3 sums, x r for sin
    assert sincos_ops(FIXED) == ({"add": 13, "mul": 16}, 10)


def test_fixed_point_quadrant_table_is_exact():
    """The fixed-point table (a derived step's, in its Q format): sin and cos of 0, pi/2, pi, 3 pi/2
    are exactly 0 and +-1, so the angle sum is the quadrant swap and sign change, exactly."""
    m = load_config(EXAMPLES / "seed001_spmsm.toml").with_controller(number_format="fixed")
    t = topology_of(m).derive(m)
    one = int(t.nf.const(1.0, ""))
    assert [int(v) for v in t.sincos_tab] == [0, one, one, 0, 0, -one, -one, 0]


def test_hex_literals_round_trip():
    for v in (0.1, -2.5, 1e-30, 3.4e38, 0.0):
        lit = c_float_literal(f32(v))
        assert lit.endswith("f")
        assert np.float32(float.fromhex(lit[:-1])) == f32(v)
    assert c_float_literal(f32(1.5)) == "0x1.8p+0f"
