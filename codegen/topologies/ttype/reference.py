"""Python reference of the three-level MPDTC step, vectorised, through the number format's ops.

One ``ops`` helper per C operation, in the C's order
(numerics.md "One rounding per operation, fixed order"), over a batch of input records of
``interface.INPUT_DTYPE``.  The generated C (templates/ttype/mpc.c.j2)
is the other, independent implementation of the same sequence;
``codegen.topologies.ttype.verify`` proves the two equal bit for bit.

Step (mpdtc-three-level.md; equation numbers are seed 000's):
1. input guard (numerics.md);  Udc = uc1 + uc2, V_o = (uc1 - uc2)/2.
2. sin/cos of theta_e at k, k+1 = theta + w Ts and k+2 = theta + 2 w Ts
   (codegen.kernels.trig); Clarke/Park of the sampled currents with theta(k)
   (codegen.kernels.frames).
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
   Conventions; codegen.kernels.sector, shared with the two-level step).
5. candidates: mpdtc63 the derived Table 3 row (end state of prev_vector,
   sector of u*); mpdtc27 all 19 voltage groups of the 27 states.
   Each group is resolved to the member with the smallest predicted
   |V_o(k+2)| (ties: the earlier member).  A virtual member's T_N is the
   neutral-point deadbeat (eq. (10)-(11) corrected: every segment's charge
   counted): with i_o(x) the midpoint current of state x at k+1,
       Q(T_N) = Ts/3 (i_o(b) + i_o(c) + i_o(P)) + T_N (i_o(N) - i_o(P)),
       V_o(k+1) + Q(T_N)/(2C) = 0  ->  T_N = -(2C V_o(k+1) + Ts/3 A)/D,
   one IEEE float32 division (D == 0: T_N = T_N_min), clamped to
   [T_N_min, Ts/3].  The 8 distinct i_o values (patterns of the 0/1
   coefficients, ``ThreeLevelTables.seq_pat``) are computed once per step with the
   coefficient formula's bits and indexed per vector; 27-MPDTC (every member
   basic) also takes |V_o(k+2)| once per pattern.
6. cost (eq. (7)) of the resolved member, Euler step k+1 -> k+2 with the
   voltage rotated by theta(k+1):
       g = |T* - Te| + lambda1 |psi* - psi_s| + lambda2 |V_o(k+2)|;
   ties keep the earlier group.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from codegen.kernels import dq, frames
from codegen.kernels.batch import begin_step, run_batch
from codegen.kernels.consts import Constants
from codegen.kernels.guard import evaluate, gates_off
from codegen.kernels.sector import sector12
from codegen.kernels.trig import sincos
from codegen.numfmt import Ops
from codegen.topologies.ttype.derive import DQ, ThreeLevelTables
from codegen.topologies.ttype.records import FAULT, GUARD, INPUT, N_SEGMENTS, SAFE_STATE, output_record


def guard(t: ThreeLevelTables, x: np.ndarray) -> np.ndarray:
    """Fault bits per state (numerics.md: non-finite or out-of-range inputs)."""
    return evaluate(t.nf.ops, GUARD, FAULT, Constants(t.consts), x)


def step_batch(t: ThreeLevelTables, x: np.ndarray) -> np.ndarray:
    """Run the step on every record of ``x`` (the input record); return output records."""
    return run_batch(x, INPUT.bind(t.nf).dtype, lambda x: _step(t, x))


def deadbeat_counts(t: ThreeLevelTables, x: np.ndarray) -> dict[str, np.ndarray]:
    """Per record of ``x``: ``virtual``, the virtual members the step resolves (each a neutral-point
    deadbeat, eq. (10)-(11)), and ``unclamped``, those whose T_N = num/D lies strictly inside
    (T_N_min, Ts/3): the only ones whose T_N needs the quotient's value (a clamped T_N is
    decided by signs and compares).  For the cycle bound's division count; no output changes."""
    counts = {"virtual": np.zeros(len(x), np.intp), "unclamped": np.zeros(len(x), np.intp)}
    run_batch(np.ascontiguousarray(x), INPUT.bind(t.nf).dtype, lambda x: _step(t, x, counts))
    return counts


class _Midpoint:
    """Neutral-point current and charge of a vector's segments (spec, eq. (2) corrected, (8)-(11))."""

    def __init__(self, o: Ops, t: ThreeLevelTables, k: Constants) -> None:
        self.o, self.k = o, k
        self.seq_pat = np.array(t.seq_pat, np.intp)

    def patterns(self, a: Any, b: Any, c: Any) -> np.ndarray:
        """The 8 distinct i_o(p) = (ka i_a + kb i_b) + kc i_c, p = 4 ka + 2 kb + kc, shape (8, n).

        The C's order: a product by 1 is the current itself (exact), one by 0 is ``0 i_x`` (a zero
        of the current's sign, as the coefficient product gives), the two sums as per state."""
        o = self.o
        z = o.const(0.0)
        za, zb, zc = o.mul(z, a), o.mul(z, b), o.mul(z, c)
        s00, s01, s10, s11 = o.add(za, zb), o.add(za, b), o.add(a, zb), o.add(a, b)
        vals = []
        for s_ab in (s00, s01, s10, s11):
            vals += [o.add(s_ab, zc), o.add(s_ab, c)]
        return np.stack([np.broadcast_to(v, np.shape(a)) for v in vals])

    @staticmethod
    def pick(table: np.ndarray, p: np.ndarray) -> Any:
        """Per lane, the entry of pattern p (table shape (8, n))."""
        return table[p, np.arange(table.shape[1])]

    def parts(self, iop: np.ndarray, v: np.ndarray) -> tuple[Any, Any, Any]:
        """(i_o(N), A = i_o(b) + i_o(c) + i_o(P), D = i_o(N) - i_o(P)) of vectors v, sequences [N, b, c, P, ...]."""
        o, sp = self.o, self.seq_pat[v]
        o_n = self.pick(iop, sp[:, 0])
        o_b = self.pick(iop, sp[:, 1])
        o_c = self.pick(iop, sp[:, 2])
        o_p = self.pick(iop, sp[:, 3])
        sa = o.add(o_b, o_c)
        sa = o.add(sa, o_p)
        return o_n, sa, o.sub(o_n, o_p)

    def charge(self, virt: np.ndarray, o_n: Any, sa: Any, d: Any, tn: Any) -> Any:
        """Q over the period: virtual Ts/3 A + T_N D, basic Ts i_o(s)."""
        o, k = self.o, self.k
        q_v = o.mul(k.TS3_S, sa)
        q_v = o.add(q_v, o.mul(tn, d))
        q_b = o.mul(k.TS_S, o_n)
        return o.where(virt, q_v, q_b)


def _step(t: ThreeLevelTables, x: np.ndarray, counts: dict[str, np.ndarray] | None = None) -> np.ndarray:
    # faulted lanes compute on zeros (their outputs are overwritten below)
    f = begin_step(t.nf, t.consts, x, guard(t, x), INPUT, output_record(t.max_groups))
    o, k, n, out, fault, ok, zf, inp = f.o, f.k, f.n, f.out, f.fault, f.ok, f.zero, f.inp
    ia, ib, th, om = inp["ia_a"], inp["ib_a"], inp["theta_e_rad"], inp["omega_e_rad_s"]
    uc1, uc2, tref = inp["uc1_v"], inp["uc2_v"], inp["torque_ref_nm"]
    pv, tnp = inp["prev_vector"], inp["t_n_prev_s"]

    mid = _Midpoint(o, t, k)
    ux = o.array(t.ux)
    uy = o.array(t.uy)
    is_virt = np.array(t.is_virtual, bool)
    seq = np.array(t.seq, np.intp)
    end_state = np.array(t.end_state, np.intp)
    model = DQ.resolve(k)

    udc = o.add(uc1, uc2)
    vo = o.sub(uc1, uc2)
    vo = o.mul(vo, k.HALF)
    tk = o.mul(om, k.TS_S)
    th1 = o.add(th, tk)
    th2 = o.add(th1, tk)
    form = f.nf.sincos_form
    s0, c0 = sincos(o, th, k, t.sincos_tab, form)
    s1, c1 = sincos(o, th1, k, t.sincos_tab, form)
    s2, c2 = sincos(o, th2, k, t.sincos_tab, form)
    # Clarke, Park with theta(k)
    i_alpha, i_beta = frames.clarke(o, ia, ib, k.INV_SQRT3)
    i_d, i_q = frames.park(o, i_alpha, i_beta, s0, c0)
    ic = frames.third_phase(o, ia, ib)

    # delay compensation: k -> k+1 under the applied vector
    vc0 = o.mul(udc, c0)
    vs0 = o.mul(udc, s0)
    bd0, bq0 = dq.bases(o, model, om, i_d, i_q)
    i_d1, i_q1 = dq.advance(o, model, bd0, bq0, vc0, vs0, ux[pv], uy[pv])
    io0 = mid.patterns(ia, ib, ic)
    o_n, sa, d = mid.parts(io0, pv)
    q = mid.charge(is_virt[pv], o_n, sa, d, tnp)
    vo1 = o.add(vo, o.mul(k.K_VO, q))

    pd1, pq1 = dq.flux(o, model, i_d1, i_q1)
    te = o.mul(k.TE_PSI, i_q1)
    mag = dq.magnitude(o, pd1, pq1)
    # MTPA flux reference
    iqr = o.mul(tref, k.INV_TE_PSI)
    pqr = o.mul(k.LS_H, iqr)
    psir = o.sqrt(o.add(k.PSI_F_SQ, o.mul(pqr, pqr)))
    # deadbeat reference voltage (eq. (12)-(15))
    p1a, p1b = frames.inv_park(o, pd1, pq1, s1, c1)
    i1a, i1b = frames.inv_park(o, i_d1, i_q1, s1, c1)
    pra, prb = frames.inv_park(o, k.PSI_F_WB, pqr, s2, c2)
    ua = o.sub(pra, p1a)
    ua = o.mul(ua, k.INV_TS)
    ua = o.add(ua, o.mul(k.RS_OHM, i1a))
    ub = o.sub(prb, p1b)
    ub = o.mul(ub, k.INV_TS)
    ub = o.add(ub, o.mul(k.RS_OHM, i1b))
    sec = sector12(o, ua, ub, k.TAN30, k.TAN60).astype(np.intp)
    # phase currents at k+1 (inverse Clarke)
    ia1, ib1, ic1 = frames.inv_clarke(o, i1a, i1b, k.SQRT3_2, k.HALF)
    io1 = mid.patterns(ia1, ib1, ic1)
    if t.n_sectors == 1:  # 27-MPDTC, every member basic: |V_o(k+2)| = |V_o(k+1) + K_VO Ts i_o(p)| per pattern
        av_pat = np.stack([o.abs(o.add(vo1, o.mul(k.K_VO, o.mul(k.TS_S, io1[p])))) for p in range(8)])
    vc1 = o.mul(udc, c1)
    vs1 = o.mul(udc, s1)
    bd1, bq1 = dq.bases(o, model, om, i_d1, i_q1)

    if t.n_sectors == 1:
        row = np.zeros(n, np.intp)
    else:
        row = end_state[pv] * t.n_sectors + sec
    rows = t.rows_padded()
    groups = t.groups_padded()
    row_n = np.array(t.row_n, np.intp)[row]
    group_n = np.array(t.group_n, np.intp)

    best = o.zeros(n)
    best_v = np.zeros(n, np.intp)
    best_tn = o.zeros(n)
    neg_two_c_vo1 = o.neg(o.mul(vo1, k.TWO_C))  # once a step, like the C
    costs = o.zeros((n, t.max_groups))
    cand = np.zeros((n, t.max_groups), np.uint16)
    n_members = np.zeros(n, np.intp)
    for j in range(t.max_groups):
        active = j < row_n
        g = rows[row, j]
        gn = group_n[g]
        n_members += np.where(active, gn, 0)
        m_av = o.zeros(n)
        m_v = np.zeros(n, np.intp)
        m_tn = o.zeros(n)
        for mi in range(t.max_members):
            m_act = mi < gn
            if not m_act.any():  # no lane's group has this many members (27-MPDTC: most groups)
                continue
            v = groups[g, mi]
            virt = is_virt[v]
            if t.n_sectors == 1:  # the pattern's |V_o(k+2)|, T_N = 0
                av = mid.pick(av_pat, mid.seq_pat[v, 0])
                tn = o.zeros(n)
            elif virt.any():
                o_n, sa, d = mid.parts(io1, v)
                # neutral-point deadbeat T_N = -(2C V_o(k+1) + Ts/3 A)/D, clamped to [T_N_min, Ts/3];
                # the numerator as (-2C V_o(k+1)) - Ts/3 A, the same value (rounding is symmetric)
                num = o.sub(neg_two_c_vo1, o.mul(k.TS3_S, sa))
                quotient = o.div(num, d)
                tn = o.where(o.ne(d, zf), quotient, k.TN_MIN_S)
                tn = o.where(o.lt(tn, k.TN_MIN_S), k.TN_MIN_S, tn)
                tn = o.where(o.gt(tn, k.TS3_S), k.TS3_S, tn)
                if counts is not None:  # deadbeat_counts: the lanes resolving this virtual member
                    lane = active & m_act & virt & ok
                    counts["virtual"] += lane
                    counts["unclamped"] += lane & o.ne(d, zf) & o.lt(k.TN_MIN_S, quotient) & o.lt(quotient, k.TS3_S)
                q = mid.charge(virt, o_n, sa, d, tn)
                tn = o.where(virt, tn, zf)
            else:  # basic members only: the charge Ts i_o(s) of mid.charge, T_N = 0
                o_n = mid.pick(io1, mid.seq_pat[v, 0])
                q = o.mul(k.TS_S, o_n)
                tn = o.zeros(n)
            if t.n_sectors != 1:
                vo2 = o.add(vo1, o.mul(k.K_VO, q))
                av = o.abs(vo2)
            # the smaller |V_o(k+2)|, compared by the costs' ranking keys (numerics.md "Ranking"; the same
            # order as < for every value >= +0, and one definition for any input)
            take = m_act & ((mi == 0) | o.rank_lt(av, m_av))
            m_av = o.where(take, av, m_av)
            m_v = np.where(take, v, m_v)
            m_tn = o.where(take, tn, m_tn)
        id2, iq2 = dq.advance(o, model, bd1, bq1, vc1, vs1, ux[m_v], uy[m_v])
        pd, pq = dq.flux(o, model, id2, iq2)
        te2 = o.mul(k.TE_PSI, iq2)
        m2 = dq.magnitude(o, pd, pq)
        # cost eq. (7): g = |T* - Te| + lambda1 |psi* - psi_s| + lambda2 |V_o(k+2)|
        e_t = o.sub(tref, te2)
        e_t = o.abs(e_t)
        e_p = o.sub(psir, m2)
        e_p = o.abs(e_p)
        e_p = o.mul(k.LAMBDA_PSI, e_p)
        e_v = o.mul(k.LAMBDA_VO, m_av)
        gc = o.add(e_t, e_p)
        gc = o.add(gc, e_v)
        take = active & ((j == 0) | o.rank_lt(gc, best))
        best = o.where(take, gc, best)
        best_v = np.where(take, m_v, best_v)
        best_tn = o.where(take, m_tn, best_tn)
        costs[:, j] = o.where(active, gc, zf)
        cand[:, j] = np.where(active, m_v, 0)

    bvirt = is_virt[best_v]
    states = np.where(bvirt[:, None], seq[best_v], best_v[:, None]).astype(np.uint16)
    half_tn = o.mul(best_tn, k.HALF)
    tp = o.sub(k.TS3_S, best_tn)
    seg = o.zeros((n, N_SEGMENTS))
    z = o.zeros(n)
    for i, val in enumerate((half_tn, k.TS6_S, k.TS6_S, tp, k.TS6_S, k.TS6_S, half_tn)):
        seg[:, i] = o.where(bvirt, val, k.TS_S if i == 0 else z)

    for name, value in {
        "te_est_nm": te, "psi_est_wb": mag, "psi_ref_wb": psir, "vo_v": vo, "vo_pred_v": vo1, "u_ref_alpha_v": ua,
        "u_ref_beta_v": ub, "t_n_s": best_tn, "cost_best": best, "costs": costs, "seg_s": seg,
        "states": states, "vector": best_v.astype(np.uint16), "n_eval": row_n.astype(np.uint16),
        "n_groups": row_n.astype(np.uint16), "n_members": n_members.astype(np.uint16),
        "sector": (sec + 1).astype(np.uint16), "cand": cand
    }.items():
        out[name] = value
    bad = ~ok
    if bad.any():
        safe = output_record(t.max_groups).bind(f.nf).zeros(1)
        safe["states"] = SAFE_STATE
        safe["vector"] = SAFE_STATE
        safe["seg_s"][0, 0] = k.TS_S
        out[bad] = safe
        out["fault"] = fault
    # what the caller does with the power stage (controller.fault_action; 0 without a fault)
    out["gates_off"] = gates_off(o, fault, x["omega_e_rad_s"], t.fault_action, k)
    return out
