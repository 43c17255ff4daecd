"""The fixed-point operations: each is the exact rounding and saturation it documents (Python
integers as the oracle), the unit parser, and the scaling's encode rule."""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.numfmt.fixed import FixedOps, isqrt64
from codegen.numfmt.scaling import INT32_MAX, INT32_MIN, Scaling
from codegen.numfmt.units import parse_unit

G = 20
OPS = FixedOps(Scaling(G, (0, 0, 0), "global"))
RNG = np.random.default_rng(7)
EDGES = np.array([0, 1, -1, 2, -2, 3, -3, (1 << (G - 1)), -(1 << (G - 1)), (1 << G), -(1 << G),
                  INT32_MAX, INT32_MIN, INT32_MAX - 1, INT32_MIN + 1], np.int64)


def _operands(n: int = 20_000) -> tuple[np.ndarray, np.ndarray]:
    a = np.concatenate([RNG.integers(INT32_MIN, INT32_MAX, n, endpoint=True), np.repeat(EDGES, len(EDGES))])
    b = np.concatenate([RNG.integers(INT32_MIN, INT32_MAX, n, endpoint=True), np.tile(EDGES, len(EDGES))])
    return a.astype(np.int32), b.astype(np.int32)


def _sat(v: int) -> int:
    return max(INT32_MIN, min(INT32_MAX, v))


def test_mul_rounds_half_up_and_saturates():
    a, b = _operands()
    got = OPS.mul(a, b)
    for x, y, r in zip(a.tolist(), b.tolist(), got.tolist()):
        assert r == _sat(math.floor((x * y + (1 << (G - 1))) / (1 << G))) if abs(x * y) < 2**52 else \
            r == _sat((x * y + (1 << (G - 1))) >> G)


def test_div_rounds_half_up_and_saturates():
    a, b = _operands(5000)
    got = OPS.div(a, b)
    for x, y, r in zip(a.tolist(), b.tolist(), got.tolist()):
        if y == 0:
            assert r == 0
        else:
            n, d = (x << G, y) if y > 0 else (-(x << G), -y)
            assert r == _sat((2 * n + d) // (2 * d))


def test_add_sub_neg_abs_saturate():
    a, b = _operands(5000)
    for x, y, s, d, ng, ab in zip(a.tolist(), b.tolist(), OPS.add(a, b).tolist(), OPS.sub(a, b).tolist(),
                                  OPS.neg(a).tolist(), OPS.abs(a).tolist()):
        assert (s, d, ng, ab) == (_sat(x + y), _sat(x - y), _sat(-x), _sat(abs(x)))


def test_sqrt_is_the_exact_floor():
    a, _ = _operands(5000)
    for x, r in zip(a.tolist(), OPS.sqrt(a).tolist()):
        assert r == (math.isqrt(x << G) if x > 0 else 0)
    big = np.array([2**62 - 1, 2**62 - 2**31, (2**31 - 1) ** 2, (2**31 - 1) ** 2 - 1], np.int64)
    assert isqrt64(big).tolist() == [math.isqrt(int(v)) for v in big]


def test_trunc_int_and_from_int():
    a, _ = _operands(5000)
    for x, r in zip(a.tolist(), OPS.trunc_int(a).tolist()):
        assert r == int(x / (1 << G)) if abs(x) < 2**52 else r == (abs(x) >> G) * (1 if x >= 0 else -1)
    n = np.array([0, 1, -1, 2047, -2048, 2048, -2049, 100000], np.int32)
    assert OPS.from_int(n).tolist() == [_sat(v << G) for v in n.tolist()]


def test_encode_rounds_half_up_saturates_and_maps_nan_to_zero():
    sc = Scaling(G, (0, 0, 0), "global")
    x = np.array([0.5 / 2**G, -0.5 / 2**G, 1.5 / 2**G, -1.5 / 2**G, 1e30, -1e30, np.inf, -np.inf, np.nan, 1.0])
    assert sc.encode("A", x).tolist() == [1, 0, 2, -1, INT32_MAX, INT32_MIN, INT32_MAX, INT32_MIN, 0, 1 << G]
    assert sc.decode("A", sc.encode("A", 1.25)).tolist() == 1.25


@pytest.mark.parametrize("unit,dims", [
    ("", (0, 0, 0)), ("rad/s", (0, 0, -1)), ("Wb", (1, 0, 1)), ("N*m", (1, 1, 1)), ("A/(N*m)", (-1, 0, -1)),
    ("N*m*s/rad", (1, 1, 2)), ("Wb^2", (2, 0, 2)), ("V/C", (1, -1, -1)), ("s/H", (-1, 1, 0)), ("F", (-1, 1, 1)),
    ("ohm", (1, -1, 0)), ("1/(N*m)", (-1, -1, -1)),
])
def test_units_reduce_to_volt_ampere_second(unit, dims):
    assert parse_unit(unit) == dims


def test_unknown_unit_is_an_error():
    with pytest.raises(ValueError, match="unknown unit 'furlong'"):
        parse_unit("furlong/s")


def test_per_unit_formats_are_consistent():
    """A product's Q format is the sum of its factors' per-unit exponents: current x flux = torque."""
    sc = Scaling(24, (9, 5, -13), "per-signal")
    assert sc.exp("A") + sc.exp("Wb") == sc.exp("N*m")
    assert sc.q("V") == 24 - 9 and sc.describe("V") == "Q16.15"
