"""Python reference of the three-level MPDTC step: numpy float32, vectorised.

One numpy element-wise operation per C operation, in the C's order
(numerics.md "Expression order is fixed"), over a batch of input records of
``interface.INPUT_DTYPE``.  The generated C (templates/ttype/mpc.c.j2)
is the other, independent implementation of the same sequence;
``codegen.topologies.ttype.verify`` proves the two equal bit for bit.

Step (mpdtc-three-level.md; equation numbers are seed 000's):
1. input guard (numerics.md);  Udc = uc1 + uc2, V_o = (uc1 - uc2)/2.
2. sin/cos of theta_e at k, k+1 = theta + w Ts and k+2 = theta + 2 w Ts
   (codegen.trig); Clarke/Park of the sampled currents with theta(k).
3. delay compensation (eq. (3)-(6)): forward-Euler dq step k -> k+1 under
   the applied vector's period-average voltage (rotated with theta(k)), and
   V_o(k+1) = V_o(k) + Q/(2C) with Q its net midpoint charge over the period
   (the sampled currents held over the period; for a virtual vector every
   segment counted, with its T_N = t_n_prev_s).
4. psi* by MTPA, i_q* = T*/(1.5 np psi_f), psi* = sqrt(psi_f^2 + (Ls i_q*)^2);
   deadbeat reference u* = (psi_ref_vec - psi_s(k+1))/Ts + Rs i(k+1) with
   psi_ref_vec at load angle delta* from the magnet axis at theta(k+2).
   Since sin delta* = 2 T* Ls/(3 np psi_f psi*) = Ls i_q*/psi* (always in
   [-1, 1]) and cos delta* = sqrt(1 - sin^2) = psi_f/psi*, psi_ref_vec is
   exactly (psi_f, Ls i_q*) in the dq frame at theta(k+2): the step rotates
   that, with no division, no clamp and no inverse trigonometry (the spec's
   asin / sqrt(1 - s^2) formula, algebraically identical).
   Sector of u*: 12 sectors of 30 deg by comparisons (mptc-two-level.md
   Conventions; same function as the two-level step).
5. candidates: mpdtc63 the derived Table 3 row (end state of prev_vector,
   sector of u*); mpdtc27 all 19 voltage groups of the 27 states.
   Each group is resolved to the member with the smallest predicted
   |V_o(k+2)| (ties: the earlier member).  A virtual member's T_N is the
   neutral-point deadbeat (eq. (10)-(11) corrected: every segment's charge
   counted): with i_o(x) the midpoint current of state x at k+1,
       Q(T_N) = Ts/3 (i_o(b) + i_o(c) + i_o(P)) + T_N (i_o(N) - i_o(P)),
       V_o(k+1) + Q(T_N)/(2C) = 0  ->  T_N = -(2C V_o(k+1) + Ts/3 A)/D,
   one IEEE float32 division (D == 0: T_N = T_N_min), clamped to
   [T_N_min, Ts/3].
6. cost (eq. (7)) of the resolved member, Euler step k+1 -> k+2 with the
   voltage rotated by theta(k+1):
       g = |T* - Te| + lambda1 |psi* - psi_s| + lambda2 |V_o(k+2)|;
   ties keep the earlier group.
"""
from __future__ import annotations

import numpy as np

from codegen.kernels.trig import sincos_f32
from codegen.topologies.ttype.derive import ThreeLevelTables
from codegen.topologies.ttype.records import FAULT, INPUT_DTYPE, N_MAX_EVAL, N_SEGMENTS, OUTPUT_DTYPE, SAFE_STATE
from codegen.topologies.twolevel.reference import sector12

F = np.float32
FIRST_VIRTUAL = 27
N_IDS = 63


class _K:
    """Attribute access to the float32 constants of a ThreeLevelTables."""

    def __init__(self, t: ThreeLevelTables) -> None:
        for c in t.consts:
            setattr(self, c.name, c.value)


def guard(t: ThreeLevelTables, x: np.ndarray) -> np.ndarray:
    """Fault bits per state (numerics.md: non-finite or out-of-range inputs)."""
    k = _K(t)
    ia, ib = x["ia_a"], x["ib_a"]
    ic = -(ia + ib)
    u1, u2 = x["uc1_v"], x["uc2_v"]
    pv = x["prev_vector"]
    tnp = x["t_n_prev_s"]
    fault = np.zeros(len(x), np.uint16)

    def bit(ok: np.ndarray, name: str) -> None:
        nonlocal fault
        fault |= np.where(ok, 0, FAULT[name]).astype(np.uint16)

    bit((np.abs(ia) <= k.I_TRIP_A) & (np.abs(ib) <= k.I_TRIP_A) & (np.abs(ic) <= k.I_TRIP_A), "CURRENT")
    bit((u1 >= k.UC_MIN_V) & (u2 >= k.UC_MIN_V), "UDC_LOW")
    bit((u1 <= k.UC_MAX_V) & (u2 <= k.UC_MAX_V), "UDC_HIGH")
    bit(np.abs(x["theta_e_rad"]) <= k.ANGLE_GUARD_RAD, "ANGLE")
    bit(np.abs(x["omega_e_rad_s"]) <= k.OMEGA_GUARD_RAD_S, "SPEED")
    bit(np.abs(x["torque_ref_nm"]) <= k.TORQUE_REF_GUARD_NM, "TORQUE_REF")
    bit(pv <= N_IDS - 1, "STATE")
    virt = (pv >= FIRST_VIRTUAL) & (pv <= N_IDS - 1)
    bit(~virt | ((tnp >= F(0)) & (tnp <= k.TS3_S)), "TN_PREV")
    return fault


def step_batch(t: ThreeLevelTables, x: np.ndarray) -> np.ndarray:
    """Run the step on every record of ``x`` (INPUT_DTYPE); return OUTPUT_DTYPE records."""
    x = np.asarray(x)
    if x.dtype != INPUT_DTYPE:
        raise TypeError(f"input dtype must be {INPUT_DTYPE}")
    with np.errstate(all="ignore"):
        return _step(t, x)


def _step(t: ThreeLevelTables, x: np.ndarray) -> np.ndarray:
    k = _K(t)
    n = len(x)
    out = np.zeros(n, OUTPUT_DTYPE)
    fault = guard(t, x)
    ok = fault == 0
    zf = F(0)
    ia = np.where(ok, x["ia_a"], zf)
    ib = np.where(ok, x["ib_a"], zf)
    th = np.where(ok, x["theta_e_rad"], zf)
    om = np.where(ok, x["omega_e_rad_s"], zf)
    uc1 = np.where(ok, x["uc1_v"], zf)
    uc2 = np.where(ok, x["uc2_v"], zf)
    tref = np.where(ok, x["torque_ref_nm"], zf)
    pv = np.where(ok, x["prev_vector"], 0).astype(np.intp)
    tnp = np.where(ok, x["t_n_prev_s"], zf)

    ka = np.array(t.io_a, F)
    kb = np.array(t.io_b, F)
    kc = np.array(t.io_c, F)
    ux = np.array(t.ux, F)
    uy = np.array(t.uy, F)
    is_virt = np.array(t.is_virtual, bool)
    seq = np.array(t.seq, np.intp)
    end_state = np.array(t.end_state, np.intp)

    def io(s: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
        # i_o = sum_x (1 - |S_x|) i_x  (spec, correcting eq. (2))
        r = ka[s] * a + kb[s] * b
        return r + kc[s] * c

    def bases(i_d0: np.ndarray, i_q0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        # bd = i_d + Ts/Ls (w Ls i_q - Rs i_d);  bq = i_q - Ts/Ls (Rs i_q + w Ls i_d + w psi_f)
        bd = om * k.LS_H
        bd = bd * i_q0
        bd = bd - k.RS_OHM * i_d0
        bd = k.A_S * bd
        bd = i_d0 + bd
        bq = k.RS_OHM * i_q0
        w = om * k.LS_H
        w = w * i_d0
        bq = bq + w
        bq = bq + om * k.PSI_F_WB
        bq = k.A_S * bq
        bq = i_q0 - bq
        return bd, bq

    def advance(bd, bq, vc, vs, v):
        ud = vc * ux[v] + vs * uy[v]
        uq = vc * uy[v] - vs * ux[v]
        return bd + k.A_S * ud, bq + k.A_S * uq

    udc = uc1 + uc2
    vo = uc1 - uc2
    vo = vo * k.HALF
    tk = om * k.TS_S
    th1 = th + tk
    th2 = th1 + tk
    s0, c0 = sincos_f32(th)
    s1, c1 = sincos_f32(th1)
    s2, c2 = sincos_f32(th2)
    # Clarke, Park with theta(k)
    tt = ib + ib
    tt = ia + tt
    i_beta = tt * k.INV_SQRT3
    i_alpha = ia
    i_d = i_alpha * c0 + i_beta * s0
    i_q = i_beta * c0 - i_alpha * s0
    ic = -(ia + ib)

    # delay compensation: k -> k+1 under the applied vector
    vc0 = udc * c0
    vs0 = udc * s0
    bd0, bq0 = bases(i_d, i_q)
    i_d1, i_q1 = advance(bd0, bq0, vc0, vs0, pv)
    pvv = is_virt[pv]
    sq = seq[pv]
    o_n = io(sq[:, 0], ia, ib, ic)
    o_b = io(sq[:, 1], ia, ib, ic)
    o_c = io(sq[:, 2], ia, ib, ic)
    o_p = io(sq[:, 3], ia, ib, ic)
    a = o_b + o_c
    a = a + o_p
    d = o_n - o_p
    q_v = k.TS3_S * a
    q_v = q_v + tnp * d
    q_b = k.TS_S * o_n
    q = np.where(pvv, q_v, q_b)
    vo1 = vo + k.K_VO * q

    pd1 = k.LS_H * i_d1
    pd1 = pd1 + k.PSI_F_WB
    pq1 = k.LS_H * i_q1
    te = k.TE_PSI * i_q1
    mag = np.sqrt(pd1 * pd1 + pq1 * pq1)
    # MTPA flux reference
    iqr = tref * k.INV_TE_PSI
    pqr = k.LS_H * iqr
    psir = np.sqrt(k.PSI_F_SQ + pqr * pqr)
    # deadbeat reference voltage (eq. (12)-(15))
    p1a = pd1 * c1 - pq1 * s1
    p1b = pd1 * s1 + pq1 * c1
    i1a = i_d1 * c1 - i_q1 * s1
    i1b = i_d1 * s1 + i_q1 * c1
    pra = k.PSI_F_WB * c2 - pqr * s2
    prb = k.PSI_F_WB * s2 + pqr * c2
    ua = pra - p1a
    ua = ua * k.INV_TS
    ua = ua + k.RS_OHM * i1a
    ub = prb - p1b
    ub = ub * k.INV_TS
    ub = ub + k.RS_OHM * i1b
    sec = sector12(ua, ub, k).astype(np.intp)
    # phase currents at k+1 (inverse Clarke)
    ia1 = i1a
    ib1 = k.SQRT3_2 * i1b - k.HALF * i1a
    ic1 = -(ia1 + ib1)
    vc1 = udc * c1
    vs1 = udc * s1
    bd1, bq1 = bases(i_d1, i_q1)

    if t.n_sectors == 1:
        row = np.zeros(n, np.intp)
    else:
        row = end_state[pv] * t.n_sectors + sec
    rows = t.rows_padded()
    groups = t.groups_padded()
    row_n = np.array(t.row_n, np.intp)[row]
    group_n = np.array(t.group_n, np.intp)

    best = np.zeros(n, F)
    best_v = np.zeros(n, np.intp)
    best_tn = np.zeros(n, F)
    costs = np.zeros((n, N_MAX_EVAL), F)
    cand = np.zeros((n, N_MAX_EVAL), np.uint16)
    n_members = np.zeros(n, np.intp)
    for j in range(t.max_groups):
        active = j < row_n
        g = rows[row, j]
        gn = group_n[g]
        n_members += np.where(active, gn, 0)
        m_av = np.zeros(n, F)
        m_v = np.zeros(n, np.intp)
        m_tn = np.zeros(n, F)
        for mi in range(t.max_members):
            m_act = mi < gn
            v = groups[g, mi]
            sq = seq[v]
            o_n = io(sq[:, 0], ia1, ib1, ic1)
            o_b = io(sq[:, 1], ia1, ib1, ic1)
            o_c = io(sq[:, 2], ia1, ib1, ic1)
            o_p = io(sq[:, 3], ia1, ib1, ic1)
            a = o_b + o_c
            a = a + o_p
            d = o_n - o_p
            num = vo1 * k.TWO_C
            num = num + k.TS3_S * a
            num = -num
            tn = np.where(d != F(0), num / d, k.TN_MIN_S)
            tn = np.where(tn < k.TN_MIN_S, k.TN_MIN_S, tn)
            tn = np.where(tn > k.TS3_S, k.TS3_S, tn)
            q_v = k.TS3_S * a
            q_v = q_v + tn * d
            q_b = k.TS_S * o_n
            virt = is_virt[v]
            q = np.where(virt, q_v, q_b)
            tn = np.where(virt, tn, F(0))
            vo2 = vo1 + k.K_VO * q
            av = np.abs(vo2)
            take = m_act & ((mi == 0) | (av < m_av))
            m_av = np.where(take, av, m_av)
            m_v = np.where(take, v, m_v)
            m_tn = np.where(take, tn, m_tn)
        id2, iq2 = advance(bd1, bq1, vc1, vs1, m_v)
        pd = k.LS_H * id2
        pd = pd + k.PSI_F_WB
        pq = k.LS_H * iq2
        te2 = k.TE_PSI * iq2
        m2 = np.sqrt(pd * pd + pq * pq)
        e_t = tref - te2
        e_t = np.abs(e_t)
        e_p = psir - m2
        e_p = np.abs(e_p)
        e_p = k.LAMBDA_PSI * e_p
        e_v = k.LAMBDA_VO * m_av
        gc = e_t + e_p
        gc = gc + e_v
        take = active & ((j == 0) | (gc < best))
        best = np.where(take, gc, best)
        best_v = np.where(take, m_v, best_v)
        best_tn = np.where(take, m_tn, best_tn)
        costs[:, j] = np.where(active, gc, F(0))
        cand[:, j] = np.where(active, m_v, 0)

    bvirt = is_virt[best_v]
    states = np.where(bvirt[:, None], seq[best_v], best_v[:, None]).astype(np.uint16)
    half_tn = best_tn * k.HALF
    tp = k.TS3_S - best_tn
    seg = np.zeros((n, N_SEGMENTS), F)
    z = np.zeros(n, F)
    for i, val in enumerate((half_tn, k.TS6_S, k.TS6_S, tp, k.TS6_S, k.TS6_S, half_tn)):
        seg[:, i] = np.where(bvirt, val, k.TS_S if i == 0 else z)

    out["te_est_nm"] = te
    out["psi_est_wb"] = mag
    out["psi_ref_wb"] = psir
    out["vo_v"] = vo
    out["vo_pred_v"] = vo1
    out["u_ref_alpha_v"] = ua
    out["u_ref_beta_v"] = ub
    out["t_n_s"] = best_tn
    out["cost_best"] = best
    out["costs"] = costs
    out["seg_s"] = seg
    out["states"] = states
    out["vector"] = best_v.astype(np.uint16)
    out["n_eval"] = row_n.astype(np.uint16)
    out["n_groups"] = row_n.astype(np.uint16)
    out["n_members"] = n_members.astype(np.uint16)
    out["sector"] = (sec + 1).astype(np.uint16)
    out["cand"] = cand
    bad = ~ok
    if bad.any():
        safe = np.zeros(1, OUTPUT_DTYPE)
        safe["states"] = SAFE_STATE
        safe["vector"] = SAFE_STATE
        safe["seg_s"][0, 0] = k.TS_S
        out[bad] = safe
        out["fault"] = fault
    return out
