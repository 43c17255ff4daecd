"""The helpers every number format's reference arithmetic shares: lane-wise arrays, compares and
selections, which no format rounds (``Float32Ops`` and ``FixedOps`` add the arithmetic)."""
from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["LaneOps"]


class LaneOps:
    """Arrays of the format's storage type ``real``, compares and selections (no arithmetic)."""

    real: Any = np.float32

    def array(self, values: Any) -> np.ndarray:
        """An array of values of the format (table data already in the format)."""
        return np.asarray(values, dtype=self.real)

    def zeros(self, shape: Any) -> np.ndarray:
        """Zeros of the format."""
        return np.zeros(shape, self.real)

    def lt(self, a: Any, b: Any) -> np.ndarray:
        """a < b (False for NaN)."""
        return np.asarray(a < b)

    def le(self, a: Any, b: Any) -> np.ndarray:
        """a <= b (False for NaN)."""
        return np.asarray(a <= b)

    def gt(self, a: Any, b: Any) -> np.ndarray:
        """a > b (False for NaN)."""
        return np.asarray(a > b)

    def ge(self, a: Any, b: Any) -> np.ndarray:
        """a >= b (False for NaN)."""
        return np.asarray(a >= b)

    def eq(self, a: Any, b: Any) -> np.ndarray:
        """a == b."""
        return np.asarray(a == b)

    def ne(self, a: Any, b: Any) -> np.ndarray:
        """a != b (True for NaN)."""
        return np.asarray(a != b)

    def where(self, cond: Any, a: Any, b: Any) -> np.ndarray:
        """Per lane: a where cond, else b (a selection, no arithmetic)."""
        return np.where(cond, a, b).astype(self.real)
