"""Python reference of the two-level MPTC step: numpy float32, vectorised.

One numpy element-wise operation per C operation, in the C's order
(numerics.md "Expression order is fixed"), over a batch of input records of
``interface.INPUT_DTYPE``.  The generated C (templates/twolevel/mpc.c.j2)
is the other, independent implementation of the same sequence; ``verify``
proves the two equal bit for bit.

Equations (mptc-two-level.md): Clarke/Park and the current-model flux
(Conventions); predictors ``flux-geometry`` and ``dq-euler`` (Predictors);
the squared, rated-normalised cost (Cost); strategies conventional, s1, s2,
s3 (Strategies); the input guard (numerics.md).
"""
from __future__ import annotations

import numpy as np

from codegen.kernels.trig import sincos_f32
from codegen.topologies.twolevel.derive import TwoLevelTables
from codegen.topologies.twolevel.records import FAULT, INPUT_DTYPE, N_VECTORS, OUTPUT_DTYPE

F = np.float32


class _K:
    """Attribute access to the float32 constants of a TwoLevelTables."""

    def __init__(self, t: TwoLevelTables) -> None:
        for c in t.consts:
            setattr(self, c.name, c.value)


def guard(t: TwoLevelTables, x: np.ndarray) -> np.ndarray:
    """Fault bits per state (numerics.md: non-finite or out-of-range inputs)."""
    k = _K(t)
    ia, ib = x["ia_a"], x["ib_a"]
    ic = -(ia + ib)
    fault = np.zeros(len(x), np.uint16)
    cur_ok = (np.abs(ia) <= k.I_TRIP_A) & (np.abs(ib) <= k.I_TRIP_A) & (np.abs(ic) <= k.I_TRIP_A)
    fault |= np.where(cur_ok, 0, FAULT["CURRENT"]).astype(np.uint16)
    fault |= np.where(x["udc_v"] >= k.UDC_MIN_V, 0, FAULT["UDC_LOW"]).astype(np.uint16)
    fault |= np.where(x["udc_v"] <= k.UDC_MAX_V, 0, FAULT["UDC_HIGH"]).astype(np.uint16)
    fault |= np.where(np.abs(x["theta_e_rad"]) <= k.ANGLE_GUARD_RAD, 0, FAULT["ANGLE"]).astype(np.uint16)
    fault |= np.where(np.abs(x["omega_e_rad_s"]) <= k.OMEGA_GUARD_RAD_S, 0, FAULT["SPEED"]).astype(np.uint16)
    fault |= np.where(np.abs(x["torque_ref_nm"]) <= k.TORQUE_REF_GUARD_NM, 0, FAULT["TORQUE_REF"]).astype(np.uint16)
    fault |= np.where(x["prev_sw"] <= 7, 0, FAULT["STATE"]).astype(np.uint16)
    return fault


def sector12(psi_alpha: np.ndarray, psi_beta: np.ndarray, k: _K) -> np.ndarray:
    """0-based 12-sector index of the flux angle by comparisons (eq. (12)).

    Upper half plane (y > 0, or y == 0 and x >= 0) is [0, 180) deg; the
    lower half is mapped onto it by (x, y) -> (-x, -y) and offset by 6.
    In the upper half: x > 0 -> sector 0 if y < x tan30, 1 if y < x tan60,
    else 2; x <= 0 -> with ax = -x: 5 if y <= ax tan30, 4 if y <= ax tan60,
    else 3.
    """
    x, y = psi_alpha, psi_beta
    upper = (y > F(0)) | ((y == F(0)) & (x >= F(0)))
    xx = np.where(upper, x, -x)
    yy = np.where(upper, y, -y)
    base = np.where(upper, 0, 6)
    t30 = xx * k.TAN30
    t60 = xx * k.TAN60
    right = np.where(yy < t30, 0, np.where(yy < t60, 1, 2))
    ax = -xx
    a30 = ax * k.TAN30
    a60 = ax * k.TAN60
    left = np.where(yy <= a30, 5, np.where(yy <= a60, 4, 3))
    return (base + np.where(xx > F(0), right, left)).astype(np.uint16)


def step_batch(t: TwoLevelTables, x: np.ndarray) -> np.ndarray:
    """Run the step on every record of ``x`` (INPUT_DTYPE); return OUTPUT_DTYPE records."""
    x = np.asarray(x)
    if x.dtype != INPUT_DTYPE:
        raise TypeError(f"input dtype must be {INPUT_DTYPE}")
    with np.errstate(all="ignore"):
        return _step(t, x)


def _step(t: TwoLevelTables, x: np.ndarray) -> np.ndarray:
    k = _K(t)
    n = len(x)
    out = np.zeros(n, OUTPUT_DTYPE)
    fault = guard(t, x)
    ok = fault == 0
    # faulted lanes compute on zeros (their outputs are overwritten below)
    zf = F(0)
    ia = np.where(ok, x["ia_a"], zf)
    ib = np.where(ok, x["ib_a"], zf)
    th = np.where(ok, x["theta_e_rad"], zf)
    om = np.where(ok, x["omega_e_rad_s"], zf)
    udc = np.where(ok, x["udc_v"], zf)
    tref = np.where(ok, x["torque_ref_nm"], zf)
    prev_sw = np.where(ok, x["prev_sw"], 0).astype(np.intp)

    s, c = sincos_f32(th)
    # Clarke (amplitude invariant): i_alpha = i_a, i_beta = (i_a + 2 i_b)/sqrt(3)
    tt = ib + ib
    tt = ia + tt
    i_beta = tt * k.INV_SQRT3
    i_alpha = ia
    # Park with theta_e
    i_d = i_alpha * c + i_beta * s
    i_q = i_beta * c - i_alpha * s
    # current-model flux
    psi_d = k.LD_H * i_d
    psi_d = psi_d + k.PSI_F_WB
    psi_q = k.LQ_H * i_q

    ux = np.array(t.ux, F)
    uy = np.array(t.uy, F)
    sw_to_vec = np.array(t.sw_to_vec, np.intp)
    pv = sw_to_vec[prev_sw]

    if t.predictor == "flux-geometry":
        psi_a = psi_d * c - psi_q * s
        psi_b = psi_d * s + psi_q * c
        psif_c = k.PSI_F_WB * c
        psif_s = k.PSI_F_WB * s
        vdt = udc * k.VDT_K
        if t.delay_compensation:  # predict k+1 under the vector applied now
            psi_a = psi_a + vdt * ux[pv]
            psi_b = psi_b + vdt * uy[pv]
        te = psif_c * psi_b - psif_s * psi_a
        te = k.TE_GEO_K * te
        mag = np.sqrt(psi_a * psi_a + psi_b * psi_b)

        def predict(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            pa = psi_a + vdt * ux[v]
            pb = psi_b + vdt * uy[v]
            te1 = psif_c * pb - psif_s * pa
            te1 = k.TE_GEO_K * te1
            m1 = np.sqrt(pa * pa + pb * pb)
            return te1, m1
    else:
        vmag = udc * k.VMAG_K
        vc = vmag * c
        vs = vmag * s

        def bases(i_d0: np.ndarray, i_q0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            # i_d + dt/Ld (w Lq i_q - Rs i_d);  i_q - dt/Lq (Rs i_q + w Ld i_d + w psi_f)
            bd = om * k.LQ_H
            bd = bd * i_q0
            bd = bd - k.RS_OHM * i_d0
            bd = k.A_D * bd
            bd = i_d0 + bd
            bq = k.RS_OHM * i_q0
            w = om * k.LD_H
            w = w * i_d0
            bq = bq + w
            bq = bq + om * k.PSI_F_WB
            bq = k.A_Q * bq
            bq = i_q0 - bq
            return bd, bq

        def advance(bd: np.ndarray, bq: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            ud = vc * ux[v] + vs * uy[v]
            uq = vc * uy[v] - vs * ux[v]
            return bd + k.A_D * ud, bq + k.A_Q * uq

        i_d0, i_q0 = i_d, i_q
        if t.delay_compensation:
            bd, bq = bases(i_d, i_q)
            i_d0, i_q0 = advance(bd, bq, pv)
        psi_d0 = k.LD_H * i_d0
        psi_d0 = psi_d0 + k.PSI_F_WB
        psi_q0 = k.LQ_H * i_q0
        te = psi_d0 * i_q0 - psi_q0 * i_d0
        te = k.TE_K * te
        mag = np.sqrt(psi_d0 * psi_d0 + psi_q0 * psi_q0)
        psi_a = psi_d0 * c - psi_q0 * s
        psi_b = psi_d0 * s + psi_q0 * c
        bd, bq = bases(i_d0, i_q0)

        def predict(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            id1, iq1 = advance(bd, bq, v)
            pd = k.LD_H * id1
            pd = pd + k.PSI_F_WB
            pq = k.LQ_H * iq1
            te1 = pd * iq1 - pq * id1
            te1 = k.TE_K * te1
            m1 = np.sqrt(pd * pd + pq * pq)
            return te1, m1

    # candidate row: threshold (s1-s3), condition and sector (s2, s3)
    row = np.zeros(n, np.intp)
    hold = np.zeros(n, bool)
    sector = np.zeros(n, np.uint16)
    cond = np.zeros(n, np.uint16)
    if t.uses_threshold:
        d_t = tref - te
        hold = np.abs(d_t) <= k.EPS_T_NM
        if t.n_sectors > 1:
            sec = sector12(psi_a, psi_b, k).astype(np.intp)
            if t.n_sectors == 6:
                sec = sec >> 1
                cnd = np.where(d_t > F(0), 0, 1)
            else:
                d_psi = k.PSI_REF_WB - mag
                cnd = np.where(d_t > F(0), 0, 2) + np.where(d_psi > F(0), 0, 1)
            row = cnd * t.n_sectors + sec
            sector = np.where(hold, 0, sec + 1).astype(np.uint16)
            cond = np.where(hold, 0, cnd + 1).astype(np.uint16)

    maxlen = max(t.row_len)
    rows = np.zeros((len(t.rows), maxlen), np.intp)
    for r, cells in enumerate(t.rows):
        rows[r, : len(cells)] = cells
    row_n = np.array(t.row_len, np.intp)[row]
    row_n = np.where(hold, 0, row_n)

    best = np.zeros(n, F)
    best_v = np.zeros(n, np.intp)
    costs = np.zeros((n, N_VECTORS), F)
    cand = np.zeros((n, N_VECTORS), np.uint16)
    for j in range(maxlen):
        active = j < row_n
        v = rows[row, j]
        te1, m1 = predict(v)
        e_t = te1 - tref
        e_t = e_t * k.INV_TN
        g = e_t * e_t
        e_p = m1 - k.PSI_REF_WB
        e_p = e_p * k.INV_PSI_REF
        e_p = e_p * e_p
        g = g + e_p
        take = active & ((j == 0) | (g < best))
        best = np.where(take, g, best)
        best_v = np.where(take, v, best_v)
        costs[:, j] = np.where(active, g, F(0))
        cand[:, j] = np.where(active, v, 0)

    zero_sw = np.array(t.zero_sw, np.uint16)
    vec_to_sw = np.array(t.vec_to_sw, np.uint16)
    sw = np.where(best_v == 0, zero_sw[prev_sw], vec_to_sw[best_v]).astype(np.uint16)

    out["te_est_nm"] = te
    out["psi_est_wb"] = mag
    out["psi_alpha_wb"] = psi_a
    out["psi_beta_wb"] = psi_b
    out["sin_theta"] = s
    out["cos_theta"] = c
    out["cost_best"] = best
    out["costs"] = costs
    out["sw"] = sw
    out["vector"] = best_v.astype(np.uint16)
    out["n_eval"] = row_n.astype(np.uint16)
    out["sector"] = sector
    out["condition"] = cond
    out["cand"] = cand
    # safe decision on a tripped guard: everything zero but the fault bits
    bad = ~ok
    if bad.any():
        out[bad] = np.zeros(1, OUTPUT_DTYPE)
        out["fault"] = fault
    return out
