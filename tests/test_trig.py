"""The generated sin/cos: accuracy (a property) and determinism of the constants."""
import numpy as np

from codegen.kernels.trig import ANGLE_GUARD_RAD, sincos_coeffs, sincos_f32
from codegen.numfmt.float32 import c_float_literal, f32


def test_accuracy_over_guard_range():
    rng = np.random.default_rng(0)
    x = np.concatenate([
        rng.uniform(-ANGLE_GUARD_RAD, ANGLE_GUARD_RAD, 1_000_000),
        np.linspace(0, 2 * np.pi, 200_001),
        np.arange(-326, 327) * (np.pi / 4),
    ]).astype(np.float32)
    s, c = sincos_f32(x)
    xd = x.astype(np.float64)
    assert np.abs(s - np.sin(xd)).max() < 2e-7
    assert np.abs(c - np.cos(xd)).max() < 2e-7
    assert s.dtype == np.float32 and c.dtype == np.float32


def test_exact_values_at_zero():
    s, c = sincos_f32(np.array([0.0, -0.0], np.float32))
    assert s[0] == 0 and c[0] == 1 and c[1] == 1


def test_coefficients_are_float32_and_stable():
    k = sincos_coeffs()
    for v in (k.two_over_pi, k.pio2_hi, k.pio2_lo, *k.s, *k.c):
        assert isinstance(v, np.float32)
    # PIO2_HI has at most 15 significant bits, so n * PIO2_HI is exact for |n| <= 512
    m = int(np.float32(k.pio2_hi).view(np.uint32)) & 0x7FFFFF
    assert m & ((1 << (23 - 14)) - 1) == 0


def test_hex_literals_round_trip():
    for v in (0.1, -2.5, 1e-30, 3.4e38, 0.0):
        lit = c_float_literal(f32(v))
        assert lit.endswith("f")
        assert np.float32(float.fromhex(lit[:-1])) == f32(v)
    assert c_float_literal(f32(1.5)) == "0x1.8p+0f"
