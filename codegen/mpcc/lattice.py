"""The float64 derivation of the long-horizon problem (docs/mpcc.md eq. (1)-(9)).

Model (surface PMSM, Ld = Lq = L, stationary frame), exact zero-order-hold discretisation::

    i(k+1) = a i(k) + b (Udc/2) K u(k) - b e(k),   a = exp(-Rs Ts / L),  b = (1 - a) / Rs      (1)

K the amplitude-invariant Clarke matrix on the per-phase positions u (phase voltage against the DC
midpoint = Udc/2 u), e = omega_e psi_f (-sin theta, cos theta) the back-EMF.  Over the horizon
(rows l = 0..N-1 predict i(k+d+l+1)), normalised by the voltage gain g b (g = Udc/2)::

    (i* - i)_l / (g b) = r'_l - sum_{j<=l} a^(l-j) K u_j = (r' - G0 U)_l                          (2)
    J / (g b)^2 = ||r' - G0 U||^2 + lambda' ||S U - E u_prev||^2,  lambda' = lambda_u/(g_nom b)^2  (3)

S the difference matrix (I on the diagonal, -I below it), E = [I 0 ... 0]^T.  With
Q = G0^T G0 + lambda' S^T S = H^T H (Cholesky, H upper triangular)::

    J / (g b)^2 = ||H U - U_bar||^2 + const,   U_bar = H U_unc = W1 r' + W2 u_prev              (4)
    W1 = H^-T G0^T,   W2 = lambda' H^-T S^T E                                                  (5)

H, W1 and W2 are computed here once and rounded once to float32 by the caller.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["CLARKE", "Lattice", "lattice", "discretise", "default_node_budget", "CLOCK_HZ"]

#: amplitude-invariant Clarke matrix on the three per-phase positions, eq. (1)
CLARKE = (2.0 / 3.0) * np.array([[1.0, -0.5, -0.5], [0.0, math.sqrt(3.0) / 2.0, -math.sqrt(3.0) / 2.0]])


def discretise(rs_ohm: float, l_h: float, ts_s: float) -> tuple[float, float]:
    """(a, b) of eq. (1): the exact ZOH discretisation of L di/dt = -Rs i + v (float64)."""
    a = math.exp(-rs_ohm * ts_s / l_h)
    return a, -math.expm1(-rs_ohm * ts_s / l_h) / rs_ohm


@dataclass(frozen=True)
class Lattice:
    """The float64 matrices of eq. (2)-(5) for horizon ``n``."""

    a: float
    b: float
    lam: float  # lambda' of eq. (3)
    g0: np.ndarray  # (2N, 3N)
    s: np.ndarray  # (3N, 3N)
    h: np.ndarray  # (3N, 3N) upper triangular
    w1: np.ndarray  # (3N, 2N)
    w2: np.ndarray  # (3N, 3)


def lattice(rs_ohm: float, l_h: float, ts_s: float, udc_nom_v: float, lambda_u: float, n: int) -> Lattice:
    """The matrices of eq. (2)-(5) (float64).  ``lambda_u`` > 0 makes Q positive definite (K has the
    common mode (1, 1, 1) in its null space, so G0^T G0 alone is singular)."""
    a, b = discretise(rs_ohm, l_h, ts_s)
    g0 = np.zeros((2 * n, 3 * n))
    for row in range(n):
        for col in range(row + 1):
            g0[2 * row:2 * row + 2, 3 * col:3 * col + 3] = a ** (row - col) * CLARKE
    s = np.eye(3 * n) - np.eye(3 * n, k=-3)
    e = np.zeros((3 * n, 3))
    e[:3] = np.eye(3)
    lam = lambda_u / (0.5 * udc_nom_v * b) ** 2
    q = g0.T @ g0 + lam * (s.T @ s)
    h = np.linalg.cholesky(q).T
    w1 = np.linalg.solve(h.T, g0.T)
    w2 = lam * np.linalg.solve(h.T, s.T @ e)
    return Lattice(a, b, lam, g0, s, h, w1, w2)


#: the clock the default node budget is calibrated for (STM32H743)
CLOCK_HZ = 480e6
#: the share of the control period the step's worst case may take (the rest: the interrupt's other
#: work, and what the cycle estimate does not model: branch penalties, caches, wait states)
PERIOD_SHARE = 0.6


def default_node_budget(dt_s: float, n: int, levels: int) -> int:
    """The node budget when ``controller.node_budget`` is not given: the nodes that fit
    ``PERIOD_SHARE`` of the period at ``CLOCK_HZ`` after the fixed part of the step, at least one dive
    (3N nodes), at most 65535 (``n_nodes`` is 16-bit).  Cortex-M7 cycles calibrated on ``mpcgen
    bench --emulated``'s estimate (docs/mpcc.md "Node budget"): fixed part 600 + 40 (N + 1) +
    6 N (2 N + 3) cycles, per node 50 + 38 N + 210 (|alphabet| - 2) cycles, about 10 % above the
    largest (cycles - fixed part) / budget traced at the budget for N = 3..6 (two-level: 146..244,
    T-type: 334..436 cycles a node)."""
    cycles = PERIOD_SHARE * dt_s * CLOCK_HZ
    fixed = 600 + 40 * (n + 1) + 6 * n * (2 * n + 3)
    per_node = 50 + 38 * n + 210 * (levels - 2)
    return int(min(65535, max(3 * n, (cycles - fixed) // per_node)))
