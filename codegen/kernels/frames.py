"""Reference-frame transforms (mptc-two-level.md Conventions; mpdtc-three-level.md step 2).

* Clarke, amplitude invariant: i_alpha = i_a, i_beta = (i_a + 2 i_b)/sqrt(3)
  computed as t = i_b + i_b; t = i_a + t; i_beta = t * INV_SQRT3.
* third phase: i_c = -(i_a + i_b).
* Park with angle theta: d = alpha cos + beta sin, q = beta cos - alpha sin.
* inverse Park: alpha = d cos - q sin, beta = d sin + q cos.
* inverse Clarke of (alpha, beta) to phases a, b: i_a = alpha,
  i_b = sqrt(3)/2 beta - alpha/2.

One ``ops`` helper per C operation, in the order of ``kernels.j2``.
"""
from __future__ import annotations

from typing import Any

from codegen.numfmt import Ops

__all__ = ["clarke", "third_phase", "park", "inv_park", "inv_clarke"]


def clarke(ops: Ops, ia: Any, ib: Any, inv_sqrt3: Any) -> tuple[Any, Any]:
    """(i_alpha, i_beta) of the phase currents i_a, i_b (amplitude invariant)."""
    tt = ops.add(ib, ib)
    tt = ops.add(ia, tt)
    return ia, ops.mul(tt, inv_sqrt3)


def third_phase(ops: Ops, ia: Any, ib: Any) -> Any:
    """i_c = -(i_a + i_b) (no zero-sequence current)."""
    return ops.neg(ops.add(ia, ib))


def park(ops: Ops, alpha: Any, beta: Any, s: Any, c: Any) -> tuple[Any, Any]:
    """(d, q) of (alpha, beta) rotated by -theta, with s, c = sin, cos theta."""
    d = ops.add(ops.mul(alpha, c), ops.mul(beta, s))
    q = ops.sub(ops.mul(beta, c), ops.mul(alpha, s))
    return d, q


def inv_park(ops: Ops, d: Any, q: Any, s: Any, c: Any) -> tuple[Any, Any]:
    """(alpha, beta) of (d, q) rotated by +theta, with s, c = sin, cos theta."""
    alpha = ops.sub(ops.mul(d, c), ops.mul(q, s))
    beta = ops.add(ops.mul(d, s), ops.mul(q, c))
    return alpha, beta


def inv_clarke(ops: Ops, alpha: Any, beta: Any, sqrt3_2: Any, half: Any) -> tuple[Any, Any, Any]:
    """Phase currents (i_a, i_b, i_c) of (alpha, beta)."""
    ib = ops.sub(ops.mul(sqrt3_2, beta), ops.mul(half, alpha))
    return alpha, ib, third_phase(ops, alpha, ib)
