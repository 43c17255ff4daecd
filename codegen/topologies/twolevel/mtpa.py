"""MTPA flux reference of the two-level step (``controller.psi_ref = "mtpa"``), float64.

Maximum torque per ampere (docs/algorithms.md, two-level MPTC, "Flux
reference"): for a torque |T*| the current (i_d, i_q) of least magnitude
with Te = 1.5 p i_q (psi_f + (Ld - Lq) i_d) = |T*|.  With dL = Lq - Ld the
MTPA trajectory is

    i_d = -2 dL i_q^2 / (psi_f + sqrt(psi_f^2 + 4 dL^2 i_q^2))          (M1)

(the stationary point of Te along a circle |i| = const, written without
the cancellation of (psi_f - sqrt(...)) / (2 dL); dL = 0 gives i_d = 0, the
SPMSM case), and on it Te(i_q) = 1.5 p i_q (psi_f - dL i_d) grows strictly
with i_q, so i_q follows from |T*| by bisection in
[0, |T*| / (1.5 p psi_f)].  The flux reference is the stator flux there:

    psi* = sqrt((psi_f + Ld i_d)^2 + (Lq i_q)^2)                          (M2)

(SPMSM: sqrt(psi_f^2 + (Lq i_q)^2), i_q = T*/(1.5 p psi_f)).  The step reads
psi* from a table over |T*| in ``MTPA_SEGMENTS`` equal segments up to the
torque-reference guard, linearly interpolated (derive.py, reference.py).
"""
from __future__ import annotations

import numpy as np

from codegen.model import Motor

__all__ = ["MTPA_SEGMENTS", "mtpa_current", "mtpa_flux", "flux_table", "interpolation_error"]

#: segments of the psi*(|T*|) table (nodes 0 .. MTPA_SEGMENTS - 1 plus slopes; 1 KB of float32)
MTPA_SEGMENTS = 128
_BISECTIONS = 80


def mtpa_current(m: Motor, torque_nm: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """(i_d, i_q) of the MTPA point for torque |torque_nm| (float64, A): eq. (M1) and bisection on i_q."""
    t = np.abs(np.asarray(torque_nm, np.float64))
    k = 1.5 * m.pole_pairs
    d_l = m.lq_h - m.ld_h

    def i_d_of(i_q: np.ndarray) -> np.ndarray:
        return -2.0 * d_l * i_q * i_q / (m.psi_f_wb + np.sqrt(m.psi_f_wb ** 2 + 4.0 * d_l * d_l * i_q * i_q))

    lo = np.zeros_like(t)
    hi = t / (k * m.psi_f_wb)  # Te(hi) >= |T*| since psi_f - dL i_d >= psi_f
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi)
        te = k * mid * (m.psi_f_wb - d_l * i_d_of(mid))
        below = te < t
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    i_q = 0.5 * (lo + hi)
    return i_d_of(i_q), i_q


def mtpa_flux(m: Motor, torque_nm: np.ndarray | float) -> np.ndarray:
    """psi* (Wb, float64) of the MTPA point for |torque_nm|: eq. (M2)."""
    i_d, i_q = mtpa_current(m, torque_nm)
    return np.hypot(m.psi_f_wb + m.ld_h * i_d, m.lq_h * i_q)


def flux_table(m: Motor, t_max_nm: float, segments: int = MTPA_SEGMENTS) -> tuple[np.ndarray, np.ndarray, float]:
    """(nodes psi*(i dT), slopes psi*((i+1) dT) - psi*(i dT), i = 0..segments-1; 1/dT in 1/(N*m)),
    dT = t_max_nm / segments, float64.  The step interpolates psi* = node[i] + (x - i) slope[i],
    x = |T*|/dT, i = min(trunc(x), segments - 1)."""
    t = np.arange(segments + 1, dtype=np.float64) * (t_max_nm / segments)
    psi = mtpa_flux(m, t)
    return psi[:-1], np.diff(psi), segments / t_max_nm


def interpolation_error(m: Motor, t_max_nm: float, segments: int = MTPA_SEGMENTS, n: int = 20001) -> float:
    """Largest |linear interpolation - psi*| (Wb, float64) over [0, t_max_nm] (reported)."""
    nodes, slopes, inv = flux_table(m, t_max_nm, segments)
    t = np.linspace(0.0, t_max_nm, n)
    x = t * inv
    i = np.minimum(np.floor(x).astype(np.intp), segments - 1)
    approx = nodes[i] + (x - i) * slopes[i]
    return float(np.max(np.abs(approx - mtpa_flux(m, t))))

