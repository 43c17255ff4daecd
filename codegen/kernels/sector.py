"""12-sector index of a vector's angle by comparisons (mptc-two-level.md eq. (12)).

Sector I is [0, 30) deg.  The upper half plane (y > 0, or y == 0 and x >= 0)
is [0, 180) deg; the lower half is mapped onto it by (x, y) -> (-x, -y) and
offset by 6.  In the upper half: x > 0 -> sector 0 if y < x tan30, 1 if
y < x tan60, else 2; x <= 0 -> with ax = -x: 5 if y <= ax tan30, 4 if
y <= ax tan60, else 3.  No atan2; C: ``kernels.j2`` ``sector12_fn``.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from codegen.numfmt import Ops

__all__ = ["sector12"]


def sector12(ops: Ops, x: Any, y: Any, tan30: Any, tan60: Any) -> np.ndarray:
    """0-based 12-sector index (uint16) of the angle of (x, y)."""
    zero = ops.const(0.0)
    upper = ops.gt(y, zero) | (ops.eq(y, zero) & ops.ge(x, zero))
    xx = ops.where(upper, x, ops.neg(x))
    yy = ops.where(upper, y, ops.neg(y))
    base = np.where(upper, 0, 6)
    t30 = ops.mul(xx, tan30)
    t60 = ops.mul(xx, tan60)
    right = np.where(ops.lt(yy, t30), 0, np.where(ops.lt(yy, t60), 1, 2))
    ax = ops.neg(xx)
    a30 = ops.mul(ax, tan30)
    a60 = ops.mul(ax, tan60)
    left = np.where(ops.le(yy, a30), 5, np.where(ops.le(yy, a60), 4, 3))
    return (base + np.where(ops.gt(xx, zero), right, left)).astype(np.uint16)
