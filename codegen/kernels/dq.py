"""The PMSM dq model: current-model flux and the forward-Euler current step.

Current-model flux (mptc-two-level.md Conventions):
    psi_d = L_d i_d + psi_f,  psi_q = L_q i_q,  |psi| = sqrt(psi_d^2 + psi_q^2).
With L_d = L_q = L (surface PMSM) the same flux in alpha-beta needs no Park transform:
    psi_alpha = L i_alpha + psi_f cos theta,  psi_beta = L i_beta + psi_f sin theta.

Forward Euler of the dq current equations over one period dt
(mptc-two-level.md Predictors "dq-euler"; mpdtc-three-level.md eq. (3)-(6)
with L_d = L_q = L_s), split into the part that does not depend on the
voltage (the bases) and the voltage's part (the advance):
    bd = i_d + A_d (w L_q i_q - R_s i_d)
    bq = i_q - A_q (R_s i_q + w L_d i_d + w psi_f)
    u_d = vc ux + vs uy,  u_q = vc uy - vs ux   ((vc, vs) = |V| (cos, sin) theta)
    i_d+ = bd + A_d u_d,  i_q+ = bq + A_q u_q
with A_d = dt/L_d, A_q = dt/L_q.  The constants are passed in, so the
two-level (LD_H, LQ_H, A_D, A_Q) and the T-type (LS_H, A_S) share the kernel.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from codegen.kernels.consts import Constants
from codegen.numfmt import Ops

__all__ = ["DqModel", "flux", "flux_alpha_beta", "magnitude", "torque", "bases", "advance"]


@dataclass(frozen=True)
class DqModel:
    """The constants of the dq model: their names (templates), or values in the step's number format."""

    l_d: Any
    l_q: Any
    psi_f: Any
    rs: Any = None
    a_d: Any = None
    a_q: Any = None

    def resolve(self, k: Constants) -> DqModel:
        """The model of constant names -> the model of their values (a name the step lacks: None)."""
        return DqModel(*(getattr(k, n, None) if isinstance(n, str) else n
                         for n in (self.l_d, self.l_q, self.psi_f, self.rs, self.a_d, self.a_q)))


def flux(ops: Ops, m: DqModel, i_d: Any, i_q: Any) -> tuple[Any, Any]:
    """(psi_d, psi_q) = (L_d i_d + psi_f, L_q i_q)."""
    psi_d = ops.mul(m.l_d, i_d)
    psi_d = ops.add(psi_d, m.psi_f)
    return psi_d, ops.mul(m.l_q, i_q)


def flux_alpha_beta(ops: Ops, m: DqModel, i_alpha: Any, i_beta: Any, psif_c: Any, psif_s: Any) -> tuple[Any, Any]:
    """(psi_alpha, psi_beta) = (L i_alpha + psi_f cos, L i_beta + psi_f sin) of a surface PMSM
    (L = ``m.l_d`` = ``m.l_q``; ``psif_c``, ``psif_s`` = psi_f (cos, sin) theta): the current-model
    flux without the Park transform and its inverse."""
    psi_a = ops.add(ops.mul(m.l_d, i_alpha), psif_c)
    psi_b = ops.add(ops.mul(m.l_d, i_beta), psif_s)
    return psi_a, psi_b


def magnitude(ops: Ops, a: Any, b: Any) -> Any:
    """sqrt(a a + b b)."""
    return ops.sqrt(ops.add(ops.mul(a, a), ops.mul(b, b)))


def bases(ops: Ops, m: DqModel, w: Any, i_d: Any, i_q: Any) -> tuple[Any, Any]:
    """(bd, bq): the Euler step without the voltage."""
    bd = ops.mul(w, m.l_q)
    bd = ops.mul(bd, i_q)
    bd = ops.sub(bd, ops.mul(m.rs, i_d))
    bd = ops.mul(m.a_d, bd)
    bd = ops.add(i_d, bd)
    bq = ops.mul(m.rs, i_q)
    t = ops.mul(w, m.l_d)
    t = ops.mul(t, i_d)
    bq = ops.add(bq, t)
    bq = ops.add(bq, ops.mul(w, m.psi_f))
    bq = ops.mul(m.a_q, bq)
    bq = ops.sub(i_q, bq)
    return bd, bq


def advance(ops: Ops, m: DqModel, bd: Any, bq: Any, vc: Any, vs: Any, ux: Any, uy: Any) -> tuple[Any, Any]:
    """(i_d+, i_q+) under the voltage (ux, uy) (alpha-beta, per unit of |V|)."""
    ud = ops.add(ops.mul(vc, ux), ops.mul(vs, uy))
    uq = ops.sub(ops.mul(vc, uy), ops.mul(vs, ux))
    return ops.add(bd, ops.mul(m.a_d, ud)), ops.add(bq, ops.mul(m.a_q, uq))


def torque(ops: Ops, k_te: Any, psi_d: Any, psi_q: Any, i_d: Any, i_q: Any) -> Any:
    """Te = K (psi_d i_q - psi_q i_d), K = 1.5 p (mptc-two-level.md Conventions)."""
    te = ops.sub(ops.mul(psi_d, i_q), ops.mul(psi_q, i_d))
    return ops.mul(k_te, te)
