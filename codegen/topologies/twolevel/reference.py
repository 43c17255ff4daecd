"""Python reference of the two-level MPTC step, vectorised, through the number format's ops.

One ``ops`` helper per C operation, in the C's order (numerics.md
"One rounding per operation, fixed order"), over a batch of input records.  The generated
C (templates/twolevel/mpc.c.j2) is the other, independent implementation of
the same sequence; ``verify`` proves the two equal bit for bit.

Equations (mptc-two-level.md): Clarke/Park and the current-model flux
(Conventions; ``codegen.kernels.frames``, ``codegen.kernels.dq``);
predictors ``flux-geometry`` and ``dq-euler`` (Predictors); the flux
reference psi* (constant, or MTPA interpolated over |T*|, eq. (M1)-(M3) of
docs/algorithms.md); the squared cost, rated or reference-normalised (Cost,
eq. (C1)-(C2)); strategies conventional, s1, s2, s3 (Strategies); the input
guard (numerics.md; ``codegen.kernels.guard``).
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
from codegen.topologies.twolevel.derive import DQ, TwoLevelTables
from codegen.topologies.twolevel.records import FAULT, GUARD, INPUT, N_VECTORS, OUTPUT


def guard(t: TwoLevelTables, x: np.ndarray) -> np.ndarray:
    """Fault bits per state (numerics.md: non-finite or out-of-range inputs)."""
    return evaluate(t.nf.ops, GUARD, FAULT, Constants(t.consts), x)


def flux_reference(t: TwoLevelTables, o: Any, k: Any, tref: Any) -> tuple[Any, Any]:
    """(psi*, 1/psi*) for torque references ``tref`` through the ops ``o`` (constants ``k``).

    constant: (PSI_REF_WB, INV_PSI_REF).  mtpa (eq. (M3)): x = |T*| MTPA_INV_STEP,
    i = min(trunc(x), segments - 1), psi* = psi_tab[i] + (x - i) psi_slope[i], 1/psi* = 1/psi*
    (one division).  Also what a caller classifying d_psi = psi* - |psi| needs (the s3 condition).
    """
    if t.psi_ref == "constant":
        return k.PSI_REF_WB, k.INV_PSI_REF
    x = o.mul(o.abs(tref), k.MTPA_INV_STEP)
    i = np.minimum(np.asarray(o.trunc_int(x), np.int64), len(t.psi_tab) - 1)
    frac = o.sub(x, o.from_int(i.astype(np.int32)))
    tab, slope = o.array(t.psi_tab), o.array(t.psi_slope)
    psir = o.add(tab[i], o.mul(frac, slope[i]))
    return psir, o.div(o.const(1.0), psir)


def flux_weight(t: TwoLevelTables, o: Any, k: Any, tref: Any) -> Any:
    """Cost "reference" (eq. (C2)): w = max(|T*|, T_FLOOR) / T_N, the flux term's factor; None for "rated"."""
    if t.cost != "reference":
        return None
    a = o.abs(tref)
    return o.mul(o.where(o.gt(a, k.T_FLOOR_NM), a, k.T_FLOOR_NM), k.INV_TN)


def step_batch(t: TwoLevelTables, x: np.ndarray) -> np.ndarray:
    """Run the step on every record of ``x`` (the input record); return output records."""
    return run_batch(x, INPUT.bind(t.nf).dtype, lambda x: _step(t, x))


def _step(t: TwoLevelTables, x: np.ndarray) -> np.ndarray:
    # faulted lanes compute on zeros (their outputs are overwritten below)
    f = begin_step(t.nf, t.consts, x, guard(t, x), INPUT, OUTPUT)
    o, k, n, out, fault, ok, zf, inp = f.o, f.k, f.n, f.out, f.fault, f.ok, f.zero, f.inp
    ia, ib, th, om = inp["ia_a"], inp["ib_a"], inp["theta_e_rad"], inp["omega_e_rad_s"]
    udc, tref, prev_sw = inp["udc_v"], inp["torque_ref_nm"], inp["prev_sw"]

    s, c = sincos(o, th, k, t.sincos_tab, t.nf.sincos_form)
    i_alpha, i_beta = frames.clarke(o, ia, ib, k.INV_SQRT3)
    model = DQ.resolve(k)

    ux = o.array(t.ux)
    uy = o.array(t.uy)
    sw_to_vec = np.array(t.sw_to_vec, np.intp)
    pv = sw_to_vec[prev_sw]

    predict: Any
    if t.predictor == "flux-geometry":
        psif_c = o.mul(k.PSI_F_WB, c)
        psif_s = o.mul(k.PSI_F_WB, s)
        psi_a, psi_b = dq.flux_alpha_beta(o, model, i_alpha, i_beta, psif_c, psif_s)
        vdt = o.mul(udc, k.VDT_K)
        if t.delay_compensation:  # predict k+1 under the vector applied now
            psi_a = o.add(psi_a, o.mul(vdt, ux[pv]))
            psi_b = o.add(psi_b, o.mul(vdt, uy[pv]))

        def geo_torque(pa: Any, pb: Any) -> Any:
            # Te = 3p/(2Ld) (psi_f_vec x psi)
            te1 = o.sub(o.mul(psif_c, pb), o.mul(psif_s, pa))
            return o.mul(k.TE_GEO_K, te1)

        te = geo_torque(psi_a, psi_b)
        mag = dq.magnitude(o, psi_a, psi_b)

        def predict(v: np.ndarray) -> tuple[Any, Any]:
            pa = o.add(psi_a, o.mul(vdt, ux[v]))
            pb = o.add(psi_b, o.mul(vdt, uy[v]))
            return geo_torque(pa, pb), dq.magnitude(o, pa, pb)
    else:
        vmag = o.mul(udc, k.VMAG_K)
        vc = o.mul(vmag, c)
        vs = o.mul(vmag, s)
        i_d0, i_q0 = frames.park(o, i_alpha, i_beta, s, c)
        if t.delay_compensation:
            bd, bq = dq.bases(o, model, om, i_d0, i_q0)
            i_d0, i_q0 = dq.advance(o, model, bd, bq, vc, vs, ux[pv], uy[pv])
        psi_d0, psi_q0 = dq.flux(o, model, i_d0, i_q0)
        te = dq.torque(o, k.TE_K, psi_d0, psi_q0, i_d0, i_q0)
        mag = dq.magnitude(o, psi_d0, psi_q0)
        psi_a, psi_b = frames.inv_park(o, psi_d0, psi_q0, s, c)
        bd, bq = dq.bases(o, model, om, i_d0, i_q0)

        def predict(v: np.ndarray) -> tuple[Any, Any]:
            id1, iq1 = dq.advance(o, model, bd, bq, vc, vs, ux[v], uy[v])
            pd, pq = dq.flux(o, model, id1, iq1)
            return dq.torque(o, k.TE_K, pd, pq, id1, iq1), dq.magnitude(o, pd, pq)

    # flux reference and the cost's flux weight (per step)
    psir, inv_psir = flux_reference(t, o, k, tref)
    wn = flux_weight(t, o, k, tref)

    # candidate row: threshold (s1-s3), condition and sector (s2, s3)
    row = np.zeros(n, np.intp)
    hold = np.zeros(n, bool)
    sector = np.zeros(n, np.uint16)
    cond = np.zeros(n, np.uint16)
    if t.uses_threshold:
        d_t = o.sub(tref, te)
        hold = o.le(o.abs(d_t), k.EPS_T_NM)
        if t.n_sectors > 1:
            sec = sector12(o, psi_a, psi_b, k.TAN30, k.TAN60).astype(np.intp)
            if t.n_sectors == 6:
                sec = sec >> 1
                cnd = np.where(o.gt(d_t, zf), 0, 1)
            else:
                d_psi = o.sub(psir, mag)
                cnd = np.where(o.gt(d_t, zf), 0, 2) + np.where(o.gt(d_psi, zf), 0, 1)
            row = cnd * t.n_sectors + sec
            sector = np.where(hold, 0, sec + 1).astype(np.uint16)
            cond = np.where(hold, 0, cnd + 1).astype(np.uint16)

    maxlen = max(t.row_len)
    rows = np.zeros((len(t.rows), maxlen), np.intp)
    for r, cells in enumerate(t.rows):
        rows[r, : len(cells)] = cells
    row_n = np.array(t.row_len, np.intp)[row]
    row_n = np.where(hold, 0, row_n)

    best = o.zeros(n)
    best_v = np.zeros(n, np.intp)
    costs = o.zeros((n, N_VECTORS))
    cand = np.zeros((n, N_VECTORS), np.uint16)
    for j in range(maxlen):
        active = j < row_n
        v = rows[row, j]
        te1, m1 = predict(v)
        # g = ((Te+ - T*)/T_N)^2 + lambda_psi (w (|psi+| - psi*)/psi*)^2, w = 1 (rated) or T_n/T_N
        # (reference); lambda_psi = 1: no multiplication
        e_t = o.sub(te1, tref)
        e_t = o.mul(e_t, k.INV_TN)
        g = o.mul(e_t, e_t)
        e_p = o.sub(m1, psir)
        e_p = o.mul(e_p, inv_psir)
        if wn is not None:
            e_p = o.mul(e_p, wn)
        e_p = o.mul(e_p, e_p)
        if t.flux_weighted:
            e_p = o.mul(e_p, k.LAMBDA_PSI)
        g = o.add(g, e_p)
        take = active & ((j == 0) | o.rank_lt(g, best))
        best = o.where(take, g, best)
        best_v = np.where(take, v, best_v)
        costs[:, j] = o.where(active, g, zf)
        cand[:, j] = np.where(active, v, 0)

    zero_sw = np.array(t.zero_sw, np.uint16)
    vec_to_sw = np.array(t.vec_to_sw, np.uint16)
    sw = np.where(best_v == 0, zero_sw[prev_sw], vec_to_sw[best_v]).astype(np.uint16)

    for name, value in {
        "te_est_nm": te, "psi_est_wb": mag, "psi_alpha_wb": psi_a, "psi_beta_wb": psi_b, "sin_theta": s,
        "cos_theta": c, "cost_best": best, "costs": costs, "sw": sw, "vector": best_v.astype(np.uint16),
        "n_eval": row_n.astype(np.uint16), "sector": sector, "condition": cond, "cand": cand
    }.items():
        out[name] = value
    # safe decision on a tripped guard: everything zero but the fault bits
    bad = ~ok
    if bad.any():
        out[bad] = OUTPUT.bind(f.nf).zeros(1)
        out["fault"] = fault
    # what the caller does with the power stage (controller.fault_action; 0 without a fault)
    out["gates_off"] = gates_off(o, fault, x["omega_e_rad_s"], t.fault_action, k)
    return out
