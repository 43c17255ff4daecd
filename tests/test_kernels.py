"""The shared controller kernels (codegen/kernels) against hand cases."""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.kernels import dq, frames
from codegen.kernels.consts import Const, Constants
from codegen.kernels.guard import (
    COMMON_FAULTS,
    AbsAtMost,
    AllAtLeast,
    AllAtMost,
    IndexAtMost,
    PhaseCurrents,
    RealInRangeWhen,
    evaluate,
    fault_bits,
)
from codegen.kernels.sector import sector12
from codegen.numfmt import FLOAT32

O = FLOAT32.ops
TAN30 = O.const(math.tan(math.pi / 6))
TAN60 = O.const(math.tan(math.pi / 3))


def _sector(deg: float, r: float = 1.0) -> int:
    x = O.array([r * math.cos(math.radians(deg))])
    y = O.array([r * math.sin(math.radians(deg))])
    return int(sector12(O, x, y, TAN30, TAN60)[0])


@pytest.mark.parametrize("k", range(12))
def test_sector12_inside_each_sector(k: int) -> None:
    assert _sector(30 * k + 15) == k


def test_sector12_axes_and_origin() -> None:
    x = O.array([1, 0, -1, 0, 0, -0.0])
    y = O.array([0, 1, 0, -1, 0, 0])
    # +x starts sector 0; +y (90 deg) starts sector 3; -x (180 deg) starts 6; -y (270 deg) starts 9;
    # the origin (either zero sign) falls to the left half's lowest test: sector 5
    assert sector12(O, x, y, TAN30, TAN60).tolist() == [0, 3, 6, 9, 5, 5]


def test_sector12_on_the_30_degree_borders() -> None:
    """On a border (y == x tan30 exactly) the upper sector is taken, left and right of the y axis alike."""
    x = O.array([1, 1, -1, -1, -1, 1])
    y = O.array([TAN30, TAN60, TAN30, TAN60, -TAN30, -TAN30])
    # 30 deg -> 1, 60 deg -> 2, 150 deg -> 5 (y <= ax tan30), 120 deg -> 4, 210 deg -> 6 + 1, 330 deg -> 6 + 5
    assert sector12(O, x, y, TAN30, TAN60).tolist() == [1, 2, 5, 4, 7, 11]
    # just below each border stays in the lower sector
    below = np.nextafter(y[:2], np.float32(-np.inf))
    assert sector12(O, x[:2], below, TAN30, TAN60).tolist() == [0, 1]


def test_sector12_nan_is_a_sector() -> None:
    s = sector12(O, O.array([np.nan]), O.array([np.nan]), TAN30, TAN60)
    assert 0 <= int(s[0]) < 12


def test_fault_bits_common_then_extra() -> None:
    bits = fault_bits({"UDC_LOW": "l", "UDC_HIGH": "h", "STATE": "s", "X": "x"}, extra=("X",))
    assert [n for n, _, _ in bits] == [*COMMON_FAULTS, "X"]
    assert [b for _, b, _ in bits] == [1 << i for i in range(len(COMMON_FAULTS) + 1)]


GUARD = (
    PhaseCurrents("CURRENT", "ia", "ib", "I_MAX"),
    AllAtLeast("UDC_LOW", ("u1", "u2"), "U_MIN"),
    AllAtMost("UDC_HIGH", ("u1", "u2"), "U_MAX"),
    AbsAtMost("ANGLE", "th", "TH_MAX"),
    IndexAtMost("STATE", "idx", 9),
    RealInRangeWhen("SPEED", "t", None, "T_MAX", "idx", 5, 9),
)
BITS = {"CURRENT": 1, "UDC_LOW": 2, "UDC_HIGH": 4, "ANGLE": 8, "STATE": 16, "SPEED": 32}
K = Constants([Const(n, O.const(v), "", "") for n, v in
               (("I_MAX", 10), ("U_MIN", 100), ("U_MAX", 200), ("TH_MAX", 4), ("T_MAX", 1))])
DT = np.dtype([("ia", np.float32), ("ib", np.float32), ("u1", np.float32), ("u2", np.float32),
               ("th", np.float32), ("idx", np.uint16), ("t", np.float32)])
OK = {"ia": 1.0, "ib": 2.0, "u1": 150.0, "u2": 150.0, "th": 0.0, "idx": 0, "t": 5.0}


@pytest.mark.parametrize("change,fault", [
    ({}, 0),
    ({"ia": 10.0, "ib": 0.0}, 0),  # limits are inclusive
    ({"ia": 6.0, "ib": 5.0}, 1),  # |i_c| = 11
    ({"ia": np.nan}, 1),
    ({"u2": 99.0}, 2),
    ({"u1": 201.0}, 4),
    ({"u1": np.nan}, 2 | 4),
    ({"th": -4.5}, 8),
    ({"th": np.inf}, 8),
    ({"idx": 10}, 16),
    ({"idx": 4, "t": 5.0}, 0),  # t only checked for idx in [5, 9]
    ({"idx": 5, "t": 1.0}, 0),
    ({"idx": 9, "t": -0.5}, 32),
    ({"idx": 7, "t": np.nan}, 32),
    ({"idx": 10, "t": 5.0}, 16),  # beyond the range: STATE, not SPEED
])
def test_guard_hand_cases(change: dict, fault: int) -> None:
    x = np.zeros(1, DT)
    for name, v in {**OK, **change}.items():
        x[name] = v
    assert int(evaluate(O, GUARD, BITS, K, x)[0]) == fault


def test_frames_and_dq_match_the_formulas() -> None:
    rng = np.random.default_rng(1)
    ia, ib, th = (O.array(rng.uniform(-5, 5, 100)) for _ in range(3))
    s, c = O.array(np.sin(th)), O.array(np.cos(th))
    al, be = frames.clarke(O, ia, ib, O.const(1 / math.sqrt(3)))
    np.testing.assert_allclose(be, (ia + 2.0 * ib) / math.sqrt(3), rtol=1e-5, atol=1e-5)
    d, q = frames.park(O, al, be, s, c)
    a2, b2 = frames.inv_park(O, d, q, s, c)
    np.testing.assert_allclose(a2, al, atol=1e-5)
    np.testing.assert_allclose(b2, be, atol=1e-5)
    pa, pb, pc = frames.inv_clarke(O, al, be, O.const(math.sqrt(3) / 2), O.const(0.5))
    np.testing.assert_allclose(pb, ib, atol=1e-5)
    np.testing.assert_allclose(pc, -(ia + ib), atol=1e-5)
    m = dq.DqModel(O.const(2e-3), O.const(3e-3), O.const(0.1), O.const(0.5), O.const(0.05), O.const(0.03))
    psi_d, psi_q = dq.flux(O, m, d, q)
    np.testing.assert_allclose(psi_d, 2e-3 * d + 0.1, rtol=1e-6)
    w = O.const(300.0)
    bd, bq = dq.bases(O, m, w, d, q)
    np.testing.assert_allclose(bd, d + 0.05 * (300 * 3e-3 * q - 0.5 * d), rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(bq, q - 0.03 * (0.5 * q + 300 * 2e-3 * d + 300 * 0.1), rtol=1e-5, atol=1e-5)


def test_dq_model_resolves_names() -> None:
    k = Constants([Const("L", O.const(1.0), "", ""), Const("P", O.const(2.0), "", "")])
    m = dq.DqModel("L", "L", "P", "R").resolve(k)
    assert (m.l_d, m.l_q, m.psi_f, m.rs, m.a_d) == (1.0, 1.0, 2.0, None, None)
