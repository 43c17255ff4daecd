"""Python reference of the long-horizon step, vectorised, through the float32 format's operations.

The same operation sequence as templates/mpcc/mpc.c.j2 (docs/mpcc.md), one helper per C operation:

1. guard (``codegen.kernels.guard``), sin/cos of theta_e and of omega_e Ts (``codegen.kernels.trig``),
   Clarke (``codegen.kernels.frames``);
2. g b = Udc b/2, 1/(g b), the back-EMF factor w = omega_e b psi_f, i_q* = T* / (1.5 p psi_f);
3. the angles theta_j = theta_e + j omega_e Ts, j = 0..N+d, by rotation:
   cos_{j+1} = cos_j cos_w - sin_j sin_w, sin_{j+1} = sin_j cos_w + cos_j sin_w;
4. with delay compensation (d = 1) the current at k+1 under the applied positions u_prev:
   z = a i + g b K u_prev - b e_0 (eq. (1)), else z = i;
5. the free response and its error, l = 0..N-1 (eq. (2)): z = a z - b e_{d+l},
   r_l = i*(theta_{d+l+1}) - z, r'_l = r_l / (g b), i* = i_q* (-sin, cos);
6. U_bar = W1 r' + W2 u_prev (eq. (4)-(5)), one accumulation per row in column order;
6b. with a neutral point (eq. (14)): V_o = (uc1 - uc2)/2; with delay compensation V_o(k+1) = V_o +
   Ts/(2C) i_o(u_prev; i(k)); the phase currents of z (the current at the start of u_0's period),
   i_o(m) of each pattern m of midpoint phases (the currents of the phases in m summed in phase
   order, from 0), V_o(k+d+1)(m) = V_o(k+d) + Ts/(2C) i_o(m), P(m) = lambda_vo (V_o(k+d+1)(m)/(g b))^2;
7. the sphere decoder (``codegen.mpcc.decoder.search``) and the decision (the topology's ``decide``).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from codegen.kernels import frames
from codegen.kernels.batch import begin_step, run_batch
from codegen.kernels.guard import evaluate, gates_off
from codegen.kernels.trig import sincos
from codegen.mpcc.decoder import Problem, Result, digits_of, search
from codegen.mpcc.tables import MpccTables

__all__ = ["step_batch", "front", "problem"]


def problem(t: MpccTables) -> Problem:
    """The decoder's constants of the tables."""
    return Problem(t.matrix("h"), np.array(t.lvl, np.float32), t.horizon, t.max_step, t.node_budget,
                   t.mid_digit if t.neutral_point else None)


def prev_digits(t: MpccTables, state: np.ndarray) -> np.ndarray:
    """(n, 3) digits of switching states (phase a most significant, base |alphabet|)."""
    b = t.n_levels
    s = np.asarray(state, np.int64)
    return np.stack([(s // (b * b)) % b, (s // b) % b, s % b], axis=1)


def front(t: MpccTables, o: Any, k: Any, inp: dict[str, np.ndarray]) -> dict[str, Any]:
    """Steps 1-6 of the module doc on the (guard-passing) inputs ``inp``: U_bar and the estimates."""
    n_h, d = t.horizon, t.delay
    ia, ib, th, om, tref = (inp[f] for f in ("ia_a", "ib_a", "theta_e_rad", "omega_e_rad_s", "torque_ref_nm"))
    form = t.nf.sincos_form
    s, c = sincos(o, th, k, t.sincos_tab, form)
    wts = o.mul(om, k.TS_S)
    sw, cw = sincos(o, wts, k, t.sincos_tab, form)
    i_alpha, i_beta = frames.clarke(o, ia, ib, k.INV_SQRT3)
    udc = inp[t.adapter.udc_fields[0]]
    for name in t.adapter.udc_fields[1:]:
        udc = o.add(udc, inp[name])
    gb = o.mul(udc, k.HALF_B)
    inv_gb = o.div(o.const(1.0), gb)
    w = o.mul(om, k.B_PSI)
    iq = o.mul(tref, k.INV_KT)
    ss, cc = [s], [c]
    for _ in range(n_h + d):
        cn = o.sub(o.mul(cc[-1], cw), o.mul(ss[-1], sw))
        sn = o.add(o.mul(ss[-1], cw), o.mul(cc[-1], sw))
        ss.append(sn)
        cc.append(cn)
    lvl = np.array(t.lvl, np.float32)
    pd = prev_digits(t, inp[t.adapter.prev_field])
    pa, pb, pc = lvl[pd[:, 0]], lvl[pd[:, 1]], lvl[pd[:, 2]]
    za, zb = i_alpha, i_beta
    if d:
        kua = o.add(o.add(o.mul(k.K_AA, pa), o.mul(k.K_AB, pb)), o.mul(k.K_AB, pc))
        kub = o.add(o.mul(k.K_BB, pb), o.mul(k.K_BC, pc))
        za = o.add(o.add(o.mul(k.A_I, za), o.mul(gb, kua)), o.mul(w, s))
        zb = o.sub(o.add(o.mul(k.A_I, zb), o.mul(gb, kub)), o.mul(w, c))
    # estimates at k+d: Te = 1.5 p psi_f i_q, |psi| = |L i + psi_f (cos, sin)|
    iq_est = o.sub(o.mul(zb, cc[d]), o.mul(za, ss[d]))
    te = o.mul(k.TE_K, iq_est)
    psa = o.add(o.mul(k.LS_H, za), o.mul(k.PSI_F_WB, cc[d]))
    psb = o.add(o.mul(k.LS_H, zb), o.mul(k.PSI_F_WB, ss[d]))
    mag = o.sqrt(o.add(o.mul(psa, psa), o.mul(psb, psb)))
    z0 = (za, zb)
    est = {"te_est_nm": te, "psi_est_wb": mag, "i_alpha_a": za, "i_beta_a": zb, "sin_theta": s, "cos_theta": c}
    r: list[Any] = []
    for l_ in range(n_h):
        j = d + l_
        za = o.add(o.mul(k.A_I, za), o.mul(w, ss[j]))
        zb = o.sub(o.mul(k.A_I, zb), o.mul(w, cc[j]))
        ra = o.neg(o.add(za, o.mul(iq, ss[j + 1])))
        rb = o.sub(o.mul(iq, cc[j + 1]), zb)
        r += [o.mul(ra, inv_gb), o.mul(rb, inv_gb)]
    w1, w2 = t.matrix("w1"), t.matrix("w2")
    ubar = np.empty((len(ia), t.n_vars), np.float32)
    for i in range(t.n_vars):
        acc = o.mul(w1[i, 0], r[0])
        for jj in range(1, 2 * n_h):
            acc = o.add(acc, o.mul(w1[i, jj], r[jj]))
        for p, pos in enumerate((pa, pb, pc)):
            acc = o.add(acc, o.mul(w2[i, p], pos))
        ubar[:, i] = acc
    pen = None
    if t.neutral_point:
        pen, est["vo_pred_v"] = _neutral_point(t, o, k, inp, pd, ia, ib, z0, inv_gb)
    return {"ubar": ubar, "prev": pd, "iq": iq, "est": est, "pen": pen}


def _midpoint_currents(o: Any, phases: tuple[Any, Any, Any]) -> list[Any]:
    """i_o(m) = sum of the phase currents at the midpoint, m = 4 [a] + 2 [b] + [c], phase order, from 0."""
    out = []
    for m in range(8):
        acc = o.const(0.0)
        for bit, cur in zip((4, 2, 1), phases):
            if m & bit:
                acc = o.add(acc, cur)
        out.append(np.broadcast_to(acc, np.shape(phases[0])))
    return out


def _neutral_point(t: MpccTables, o: Any, k: Any, inp: dict[str, np.ndarray], pd: np.ndarray, ia: Any, ib: Any,
                   z0: tuple[Any, Any], inv_gb: Any) -> tuple[np.ndarray, Any]:
    """(the penalties P(m) (n, 8) of eq. (14), V_o(k+d) at the start of u_0's period)."""
    assert t.adapter.neutral_point is not None
    uc1, uc2 = (inp[f] for f in t.adapter.neutral_point)
    vo = o.mul(o.sub(uc1, uc2), k.HALF)
    mid = t.mid_digit
    if t.delay:  # the applied positions' charge over the current period, the sampled currents held
        io0 = _midpoint_currents(o, (ia, ib, frames.third_phase(o, ia, ib)))
        m0 = 4 * (pd[:, 0] == mid) + 2 * (pd[:, 1] == mid) + (pd[:, 2] == mid)
        io_prev = np.stack(io0)[m0, np.arange(len(m0))]
        vo = o.add(vo, o.mul(k.K_VO_TS, io_prev))
    io1 = _midpoint_currents(o, frames.inv_clarke(o, z0[0], z0[1], k.SQRT3_2, k.HALF))
    pen = np.empty((len(pd), 8), np.float32)
    for m in range(8):
        v = o.add(vo, o.mul(k.K_VO_TS, io1[m]))
        v = o.mul(v, inv_gb)
        pen[:, m] = o.mul(k.LAMBDA_VO, o.mul(v, v))
    return pen, vo


def step_batch(t: MpccTables, x: np.ndarray) -> np.ndarray:
    """Run the step on every record of ``x`` (the topology's input record); return output records."""
    return run_batch(x, t.adapter.input_record.bind(t.nf).dtype, lambda x: _step(t, x))


def solve(t: MpccTables, x: np.ndarray) -> tuple[np.ndarray, dict[str, Any], Result]:
    """(guard-passing mask, the front end's values, the decoder's result) of every record of ``x``
    (lanes that fail the guard are left out of the last two)."""
    a = t.adapter
    out_rec = a.output_record(t.horizon)
    f = begin_step(t.nf, t.consts, x, evaluate(t.nf.ops, a.guard, a.fault, _k(t), x), a.input_record, out_rec)
    ok = f.ok
    inp = {name: v[ok] for name, v in f.inp.items()}
    fr = front(t, f.o, f.k, inp)
    return ok, fr, search(problem(t), fr["ubar"], fr["prev"], fr["pen"])


def _k(t: MpccTables) -> Any:
    from codegen.kernels.consts import Constants

    return Constants(t.consts)


def _step(t: MpccTables, x: np.ndarray) -> np.ndarray:
    a = t.adapter
    f = begin_step(t.nf, t.consts, x, evaluate(t.nf.ops, a.guard, a.fault, _k(t), x), a.input_record,
                   a.output_record(t.horizon))
    out, ok = f.out, f.ok
    a.safe(t, out)
    out["fault"] = f.fault
    if ok.any():
        sub = out[ok]
        inp = {name: v[ok] for name, v in f.inp.items()}
        fr = front(t, f.o, f.k, inp)
        res = search(problem(t), fr["ubar"], fr["prev"], fr["pen"])
        for name, v in fr["est"].items():
            sub[name] = v
        sub["ubar"] = fr["ubar"]
        dg = digits_of(res.best, t.n_levels, t.n_vars)
        b = t.n_levels
        seq = dg[:, 0::3] * b * b + dg[:, 1::3] * b + dg[:, 2::3]
        sub["seq"] = (seq[:, 0] if t.horizon == 1 else seq).astype(np.uint16)
        sub["cost_best"] = res.cost
        sub["n_nodes"] = res.nodes.astype(np.uint16)
        sub["n_eval"] = res.evals.astype(np.uint16)
        sub["budget_hit"] = res.hit.astype(np.uint16)
        sub["fault"] = 0
        a.decide(t, f.o, f.k, sub, seq[:, 0], inp)
        out[ok] = sub
    out["gates_off"] = gates_off(f.o, f.fault, x["omega_e_rad_s"], t.fault_action, f.k)
    return out
