/*
 * sim_exact.h -- the plant's "exact" integrator (plant.integrator = "exact"):
 * the solution of the plant's equations over one constant-voltage piece as
 * its Taylor series in time, summed to double rounding (hand-written
 * runtime, float64, host only: the firmware's on-board plant keeps RK4,
 * pmsm_rk4.h).
 *
 * Specification: docs/simulation.md "Integration".  Within a piece (a whole
 * two-level period, a T-type segment, a dead-time interval) the leg levels
 * are constant, so the stationary-frame voltage is constant (two-level) or
 * affine in the neutral-point voltage V_o (T-type: u = u0 + u1*V_o).  The
 * state x = (i_d, i_q, omega_m, theta_e[, V_o]) obeys (pmsm_dq.h,
 * <topology>_rhs.h), with c = cos(theta_e), s = sin(theta_e), w_e = p*omega_m:
 *   u_d = c*u_alpha + s*u_beta,  u_q = c*u_beta - s*u_alpha
 *   di_d/dt = (u_d - Rs*i_d + w_e*Lq*i_q)/Ld
 *   di_q/dt = (u_q - Rs*i_q - w_e*Ld*i_d - w_e*psi_f)/Lq
 *   domega_m/dt = (1.5*p*(psi_f*i_q + (Ld - Lq)*i_d*i_q) - T_L - B*omega_m)/J  (0: speed imposed)
 *   dc/dt = -w_e*s,  ds/dt = w_e*c,  dtheta_e/dt = w_e
 *   dV_o/dt = ka*i_alpha + kb*i_beta = (ka*c + kb*s)*i_d + (kb*c - ka*s)*i_q   (T-type)
 * Every right-hand side is a polynomial in the state (products of two series
 * at most), so the Taylor coefficients follow from a recurrence (the
 * "Taylor series method", automatic differentiation): with the scaled
 * coefficients X_n = x^(n)(0)*h^n/n! of each state over a piece of length h,
 * x(t) = sum_n X_n*(t/h)^n, a product z = a*b has Z_n = sum_{k=0..n} A_k*B_{n-k}
 * (Cauchy) and dx/dt = f gives X_{n+1} = h/(n+1)*F_n.  The mechanics, the
 * rotation (cos/sin of the angle, carried by the series themselves: no libm
 * inside a piece) and the neutral point are in the same series as the
 * currents: nothing is held constant over the piece.
 *
 * Truncation (the stated error): coefficients are added until two
 * consecutive ones of every state group -- currents, speed, cos/sin, V_o --
 * are at most SIM_EXACT_TOL = 2^-53 of the largest coefficient of the group
 * so far (both are summed); the series converge geometrically with ratio
 * about rho/(n+1), rho = h*(the plant's fastest rate), and a piece is first
 * cut into equal parts with rho <= 1/2 (sim_exact_rate), so the neglected
 * tail is below rho/(n+2) <= 1/6 of the last coefficient, 2e-17 of the
 * group's largest.  A part not converged within SIM_EXACT_KMAX coefficients
 * is halved (and the rest of the piece taken in parts of that length).
 * What remains is double rounding, a few ulp per piece (the tests bound it
 * against scipy's DOP853).
 *
 * Frames: for Ld != Lq the currents are the rotor frame's (the recurrence
 * above); for Ld = Lq the stationary frame's, where the neutral point's
 * terms are linear (sim_exact_part_ab), and with the speed held the
 * recurrence has no product at all (sim_exact_part_ab_held).
 *
 * Not covered here (the plants fall back to RK4 sub-steps, pmsm_rk4.h, for
 * those intervals): a device-drop sign change inside a piece (the drops are
 * held at the signs of the piece's start; if a phase current changes sign
 * by the piece's end the piece is integrated again with RK4, as the "rk4"
 * integrator does; a current through zero and back within one piece keeps
 * the start's drop) and the open inverter (gates off).
 *
 * C99, no dynamic memory, no global state.  Not part of any cffi cdef.
 */
#ifndef SIM_EXACT_H
#define SIM_EXACT_H

#include <math.h>

#include "pmsm_dq.h"
#include "sim_inverter.h"

/* sim_params_t.integrator */
#define SIM_INTEGRATOR_RK4 0
#define SIM_INTEGRATOR_EXACT 1

/* Most Taylor coefficients of one part of a piece. */
#define SIM_EXACT_KMAX 30
/* Two consecutive coefficients at most this much of their group's largest end the series: 2^-53, one
 * unit of double rounding (the tail beyond them, ratio <= rho/(n+2) <= 1/6, is below 2e-17 of it). */
#define SIM_EXACT_TOL 1.1102230246251565e-16
/* Largest h*rate of one part of a piece. */
#define SIM_EXACT_RHO 0.5
/* Most halvings of a part that did not converge. */
#define SIM_EXACT_MAX_HALVINGS 40
/* Most parts a piece is first cut into. */
#define SIM_EXACT_MAX_PARTS 1e6

/* 1/(n+1), n = 0..SIM_EXACT_KMAX: the recurrence's h/(n+1) without a division. */
static const double sim_exact_inv[SIM_EXACT_KMAX + 1] = {
    1.0 / 1.0, 1.0 / 2.0, 1.0 / 3.0, 1.0 / 4.0, 1.0 / 5.0, 1.0 / 6.0, 1.0 / 7.0, 1.0 / 8.0,
    1.0 / 9.0, 1.0 / 10.0, 1.0 / 11.0, 1.0 / 12.0, 1.0 / 13.0, 1.0 / 14.0, 1.0 / 15.0, 1.0 / 16.0,
    1.0 / 17.0, 1.0 / 18.0, 1.0 / 19.0, 1.0 / 20.0, 1.0 / 21.0, 1.0 / 22.0, 1.0 / 23.0, 1.0 / 24.0,
    1.0 / 25.0, 1.0 / 26.0, 1.0 / 27.0, 1.0 / 28.0, 1.0 / 29.0, 1.0 / 30.0, 1.0 / 31.0};

/* One constant-voltage piece: the motor and the inverter's stationary-frame voltage. */
typedef struct {
    pmsm_dq_rhs_t m;  /* motor equations (pmsm_dq.h) */
    double ua0, ub0;  /* u_alpha, u_beta at V_o = 0, V */
    double ua1, ub1;  /* their V_o coefficients, V/V (T-type; 0 two-level) */
    double ka, kb;    /* dV_o/dt = ka*i_alpha + kb*i_beta, V/(A*s) (T-type; 0 two-level) */
    int np;           /* 1: the state has the neutral-point voltage x[4] */
} sim_exact_t;

/* The plant's fastest rate (1/s) at state x: rotation, resistance, the electromechanical and the
 * neutral-point (LC) resonances; h*rate <= SIM_EXACT_RHO keeps every series' ratio small. */
static inline double sim_exact_rate(const sim_exact_t *c, const double *x)
{
    const pmsm_dq_rhs_t *m = &c->m;
    const double we = fabs(m->p * x[2]);
    const double lr = (m->lq_ld > m->ld_lq) ? m->lq_ld : m->ld_lq;
    const double inv_l = (m->inv_ld > m->inv_lq) ? m->inv_ld : m->inv_lq;
    double r = we * (1.0 + lr) + m->rs_ld + m->rs_lq + fabs(m->b_j);
    if (m->mech) {
        const double kflux = fabs(m->psi_f) + fabs(m->dl) * (fabs(x[0]) + fabs(x[1]));
        r += sqrt(fabs(m->kt) * m->p * fabs(m->inv_j) * kflux * kflux * inv_l);
    }
    if (c->np) {
        r += sqrt((fabs(c->ka) + fabs(c->kb)) * (fabs(c->ua1) + fabs(c->ub1)) * inv_l);
    }
    return r;
}

/* Cauchy product of order n of the scaled series a and b: sum_{k=0..n} a[k]*b[n-k]. */
static inline double sim_exact_cauchy(const double *a, const double *b, int n)
{
    double z = 0.0;
    int k;
    for (k = 0; k <= n; ++k) {
        z += a[k] * b[n - k];
    }
    return z;
}

/* The largest of m and |a| + |b|. */
static inline double sim_exact_max2(double m, double a, double b)
{
    const double v = fabs(a) + fabs(b);
    return v > m ? v : m;
}

/* The sum of the coefficients x[0..n], the small ones first. */
static inline double sim_exact_sum(const double *x, int n)
{
    double y = 0.0;
    int k;
    for (k = n; k >= 1; --k) {
        y += x[k];
    }
    return x[0] + y;
}

/* The end of a part: the sums of the coefficients 0..top of the motor's series (and V_o's). */
static inline void sim_exact_store(const double *ID, const double *IQ, const double *W, const double *TH,
                                   const double *V, const double *C, const double *S, int top, int np,
                                   double *x, double *cs, double *sn)
{
    x[0] = sim_exact_sum(ID, top);
    x[1] = sim_exact_sum(IQ, top);
    x[2] = sim_exact_sum(W, top);
    x[3] = sim_exact_sum(TH, top);
    if (np) {
        x[4] = sim_exact_sum(V, top);
    }
    *cs = sim_exact_sum(C, top);
    *sn = sim_exact_sum(S, top);
}

/* Two consecutive coefficients n, n + 1 of every group below SIM_EXACT_TOL of its largest (mi, mw,
 * mc, mv: currents, speed, cos/sin, V_o). */
static inline int sim_exact_converged(const double *I1, const double *I2, const double *W,
                                      const double *C, const double *S, const double *V, int n,
                                      double mi, double mw, double mc, double mv)
{
    return n >= 1
           && fabs(I1[n]) + fabs(I2[n]) + fabs(I1[n + 1]) + fabs(I2[n + 1]) <= SIM_EXACT_TOL * mi
           && fabs(W[n]) + fabs(W[n + 1]) <= SIM_EXACT_TOL * mw
           && fabs(C[n]) + fabs(S[n]) + fabs(C[n + 1]) + fabs(S[n + 1]) <= SIM_EXACT_TOL * mc
           && fabs(V[n]) + fabs(V[n + 1]) <= SIM_EXACT_TOL * mv;
}

/*
 * One part of length h in the rotor frame (any Ld, Lq): the recurrence of the header comment on
 * (i_d, i_q, omega_m, cos, sin, theta_e[, V_o]).  x and (cs, sn) advanced to the part's end (the angle
 * unwrapped).  Returns 0, or -1 (nothing changed) if the series did not converge within
 * SIM_EXACT_KMAX coefficients.
 */
static inline int sim_exact_part_dq(const sim_exact_t *c, double *x, double *cs, double *sn, double h)
{
    const pmsm_dq_rhs_t *m = &c->m;
    double ID[SIM_EXACT_KMAX + 2], IQ[SIM_EXACT_KMAX + 2], W[SIM_EXACT_KMAX + 2];
    double WE[SIM_EXACT_KMAX + 2], C[SIM_EXACT_KMAX + 2], S[SIM_EXACT_KMAX + 2];
    double TH[SIM_EXACT_KMAX + 2], V[SIM_EXACT_KMAX + 2];
    double WD[SIM_EXACT_KMAX + 2], WQ[SIM_EXACT_KMAX + 2], GA[SIM_EXACT_KMAX + 2], GB[SIM_EXACT_KMAX + 2];
    double mi, mw, mc, mv;
    const int mech = m->mech;
    const int salient = mech && m->dl != 0.0;
    const int np = c->np;
    const double kti = m->inv_j * m->kt;
    int n;

    ID[0] = x[0];
    IQ[0] = x[1];
    W[0] = x[2];
    WE[0] = m->p * x[2];
    C[0] = *cs;
    S[0] = *sn;
    TH[0] = x[3];
    V[0] = np ? x[4] : 0.0;
    mi = sim_exact_max2(0.0, ID[0], IQ[0]);
    mw = fabs(W[0]);
    mc = sim_exact_max2(0.0, C[0], S[0]);
    mv = fabs(V[0]);
    if (np) {
        WD[0] = C[0] * c->ua1 + S[0] * c->ub1;
        WQ[0] = C[0] * c->ub1 - S[0] * c->ua1;
        GA[0] = c->ka * C[0] + c->kb * S[0];
        GB[0] = c->kb * C[0] - c->ka * S[0];
    }

    for (n = 0; n < SIM_EXACT_KMAX; ++n) {
        const double hn = h * sim_exact_inv[n];
        double we_s, we_c, we_id, we_iq, ud, uq;
        if (mech) { /* the speed is a series too */
            we_s = sim_exact_cauchy(WE, S, n);
            we_c = sim_exact_cauchy(WE, C, n);
            we_id = sim_exact_cauchy(WE, ID, n);
            we_iq = sim_exact_cauchy(WE, IQ, n);
        } else { /* held: w_e constant */
            we_s = WE[0] * S[n];
            we_c = WE[0] * C[n];
            we_id = WE[0] * ID[n];
            we_iq = WE[0] * IQ[n];
        }
        /* u_d = c*u_alpha + s*u_beta, u_q = c*u_beta - s*u_alpha, u = u0 + u1*V_o */
        ud = C[n] * c->ua0 + S[n] * c->ub0;
        uq = C[n] * c->ub0 - S[n] * c->ua0;
        if (np) {
            ud += sim_exact_cauchy(WD, V, n);
            uq += sim_exact_cauchy(WQ, V, n);
            V[n + 1] = hn * (sim_exact_cauchy(GA, ID, n) + sim_exact_cauchy(GB, IQ, n));
        } else {
            V[n + 1] = 0.0;
        }
        ID[n + 1] = hn * (m->inv_ld * ud - m->rs_ld * ID[n] + m->lq_ld * we_iq);
        IQ[n + 1] = hn * (m->inv_lq * uq - m->rs_lq * IQ[n] - m->ld_lq * we_id - m->psif_lq * WE[n]);
        if (mech) {
            const double te = m->psi_f * IQ[n] + (salient ? m->dl * sim_exact_cauchy(ID, IQ, n) : 0.0);
            W[n + 1] = hn * (kti * te - (n == 0 ? m->load_j : 0.0) - m->b_j * W[n]);
        } else {
            W[n + 1] = 0.0;
        }
        WE[n + 1] = m->p * W[n + 1];
        C[n + 1] = -hn * we_s;
        S[n + 1] = hn * we_c;
        TH[n + 1] = hn * WE[n];
        if (np) {
            WD[n + 1] = C[n + 1] * c->ua1 + S[n + 1] * c->ub1;
            WQ[n + 1] = C[n + 1] * c->ub1 - S[n + 1] * c->ua1;
            GA[n + 1] = c->ka * C[n + 1] + c->kb * S[n + 1];
            GB[n + 1] = c->kb * C[n + 1] - c->ka * S[n + 1];
        }
        mi = sim_exact_max2(mi, ID[n + 1], IQ[n + 1]);
        mw = fabs(W[n + 1]) > mw ? fabs(W[n + 1]) : mw;
        mc = sim_exact_max2(mc, C[n + 1], S[n + 1]);
        mv = fabs(V[n + 1]) > mv ? fabs(V[n + 1]) : mv;
        if (sim_exact_converged(ID, IQ, W, C, S, V, n, mi, mw, mc, mv)) {
            sim_exact_store(ID, IQ, W, TH, V, C, S, n + 1, np, x, cs, sn);
            return 0;
        }
    }
    return -1;
}

/*
 * One part of length h in the stationary frame, for Ld = Lq = L (the dq recurrence's products with
 * V_o vanish there): with i_alpha + j*i_beta = (i_d + j*i_q)*(c + j*s),
 *   L*di_alpha/dt = u_alpha - Rs*i_alpha + psi_f*w_e*s,  L*di_beta/dt = u_beta - Rs*i_beta - psi_f*w_e*c
 *   (the magnet's back-EMF psi_f*d(c, s)/dt; the same products w_e*s, w_e*c as the rotation's),
 *   dV_o/dt = ka*i_alpha + kb*i_beta,  Te = 1.5*p*psi_f*i_q,  i_q = c*i_beta - s*i_alpha.
 * x (rotor frame on entry and on return) and (cs, sn) advanced to the part's end.  Returns 0, or -1
 * (nothing changed) if the series did not converge within SIM_EXACT_KMAX coefficients.
 */
static inline int sim_exact_part_ab(const sim_exact_t *c, double *x, double *cs, double *sn, double h)
{
    const pmsm_dq_rhs_t *m = &c->m;
    double A[SIM_EXACT_KMAX + 2], B[SIM_EXACT_KMAX + 2], W[SIM_EXACT_KMAX + 2];
    double WE[SIM_EXACT_KMAX + 2], C[SIM_EXACT_KMAX + 2], S[SIM_EXACT_KMAX + 2];
    double TH[SIM_EXACT_KMAX + 2], V[SIM_EXACT_KMAX + 2];
    double mi, mw, mc, mv, ia, ib;
    const int mech = m->mech;
    const int np = c->np;
    const double ktf = m->inv_j * m->kt * m->psi_f;
    int n;

    C[0] = *cs;
    S[0] = *sn;
    A[0] = x[0] * C[0] - x[1] * S[0];
    B[0] = x[0] * S[0] + x[1] * C[0];
    W[0] = x[2];
    WE[0] = m->p * x[2];
    TH[0] = x[3];
    V[0] = np ? x[4] : 0.0;
    mi = sim_exact_max2(0.0, A[0], B[0]);
    mw = fabs(W[0]);
    mc = sim_exact_max2(0.0, C[0], S[0]);
    mv = fabs(V[0]);

    for (n = 0; n < SIM_EXACT_KMAX; ++n) {
        const double hn = h * sim_exact_inv[n];
        double we_s, we_c, ua, ub;
        if (mech) {
            we_s = sim_exact_cauchy(WE, S, n);
            we_c = sim_exact_cauchy(WE, C, n);
        } else {
            we_s = WE[0] * S[n];
            we_c = WE[0] * C[n];
        }
        /* u = u0 + u1*V_o: u0 is constant (order 0 only) */
        ua = (n == 0 ? c->ua0 : 0.0);
        ub = (n == 0 ? c->ub0 : 0.0);
        if (np) {
            ua += c->ua1 * V[n];
            ub += c->ub1 * V[n];
            V[n + 1] = hn * (c->ka * A[n] + c->kb * B[n]);
        } else {
            V[n + 1] = 0.0;
        }
        A[n + 1] = hn * (m->inv_ld * ua - m->rs_ld * A[n] + m->psif_lq * we_s);
        B[n + 1] = hn * (m->inv_ld * ub - m->rs_ld * B[n] - m->psif_lq * we_c);
        if (mech) {
            const double iq = sim_exact_cauchy(C, B, n) - sim_exact_cauchy(S, A, n);
            W[n + 1] = hn * (ktf * iq - (n == 0 ? m->load_j : 0.0) - m->b_j * W[n]);
        } else {
            W[n + 1] = 0.0;
        }
        WE[n + 1] = m->p * W[n + 1];
        C[n + 1] = -hn * we_s;
        S[n + 1] = hn * we_c;
        TH[n + 1] = hn * WE[n];
        mi = sim_exact_max2(mi, A[n + 1], B[n + 1]);
        mw = fabs(W[n + 1]) > mw ? fabs(W[n + 1]) : mw;
        mc = sim_exact_max2(mc, C[n + 1], S[n + 1]);
        mv = fabs(V[n + 1]) > mv ? fabs(V[n + 1]) : mv;
        if (sim_exact_converged(A, B, W, C, S, V, n, mi, mw, mc, mv)) {
            sim_exact_store(A, B, W, TH, V, C, S, n + 1, np, x, cs, sn);
            /* back to the rotor frame at the end's angle: i_d = c*i_alpha + s*i_beta, i_q = c*i_beta - s*i_alpha */
            ia = x[0];
            ib = x[1];
            x[0] = *cs * ia + *sn * ib;
            x[1] = *cs * ib - *sn * ia;
            return 0;
        }
    }
    return -1;
}

/*
 * sim_exact_part_ab with the speed held (speed imposed): omega_m constant, the angle theta_e + w_e*h at
 * the end; the same recurrence without the speed's series (the order-0 voltage term peeled off the
 * loop).
 */
static inline int sim_exact_part_ab_held(const sim_exact_t *c, double *x, double *cs, double *sn,
                                         double h)
{
    const pmsm_dq_rhs_t *m = &c->m;
    double A[SIM_EXACT_KMAX + 2], B[SIM_EXACT_KMAX + 2], C[SIM_EXACT_KMAX + 2];
    double S[SIM_EXACT_KMAX + 2], V[SIM_EXACT_KMAX + 2];
    double mi, mc, mv, ia, ib, we_s, we_c;
    const double we = m->p * x[2];
    const double il = m->inv_ld, rl = m->rs_ld, pl = m->psif_lq;
    const double ua1 = c->ua1 * il, ub1 = c->ub1 * il;
    const int np = c->np;
    int n;

    C[0] = *cs;
    S[0] = *sn;
    A[0] = x[0] * C[0] - x[1] * S[0];
    B[0] = x[0] * S[0] + x[1] * C[0];
    V[0] = np ? x[4] : 0.0;
    /* order 0 -> 1: the constant voltage u0 enters here only */
    we_s = we * S[0];
    we_c = we * C[0];
    A[1] = h * (il * (c->ua0 + c->ua1 * V[0]) - rl * A[0] + pl * we_s);
    B[1] = h * (il * (c->ub0 + c->ub1 * V[0]) - rl * B[0] - pl * we_c);
    V[1] = np ? h * (c->ka * A[0] + c->kb * B[0]) : 0.0;
    C[1] = -h * we_s;
    S[1] = h * we_c;
    mi = sim_exact_max2(sim_exact_max2(0.0, A[0], B[0]), A[1], B[1]);
    mc = sim_exact_max2(sim_exact_max2(0.0, C[0], S[0]), C[1], S[1]);
    mv = fabs(V[0]) > fabs(V[1]) ? fabs(V[0]) : fabs(V[1]);
    for (n = 1; n < SIM_EXACT_KMAX; ++n) {
        const double hn = h * sim_exact_inv[n];
        we_s = we * S[n];
        we_c = we * C[n];
        A[n + 1] = hn * (ua1 * V[n] - rl * A[n] + pl * we_s);
        B[n + 1] = hn * (ub1 * V[n] - rl * B[n] - pl * we_c);
        V[n + 1] = np ? hn * (c->ka * A[n] + c->kb * B[n]) : 0.0;
        C[n + 1] = -hn * we_s;
        S[n + 1] = hn * we_c;
        mi = sim_exact_max2(mi, A[n + 1], B[n + 1]);
        mc = sim_exact_max2(mc, C[n + 1], S[n + 1]);
        mv = fabs(V[n + 1]) > mv ? fabs(V[n + 1]) : mv;
        if (fabs(A[n]) + fabs(B[n]) + fabs(A[n + 1]) + fabs(B[n + 1]) <= SIM_EXACT_TOL * mi
            && fabs(C[n]) + fabs(S[n]) + fabs(C[n + 1]) + fabs(S[n + 1]) <= SIM_EXACT_TOL * mc
            && fabs(V[n]) + fabs(V[n + 1]) <= SIM_EXACT_TOL * mv) {
            ia = sim_exact_sum(A, n + 1);
            ib = sim_exact_sum(B, n + 1);
            if (np) {
                x[4] = sim_exact_sum(V, n + 1);
            }
            *cs = sim_exact_sum(C, n + 1);
            *sn = sim_exact_sum(S, n + 1);
            x[0] = *cs * ia + *sn * ib;
            x[1] = *cs * ib - *sn * ia;
            x[3] = x[3] + h * we;
            return 0;
        }
    }
    return -1;
}

/* One part of length h: the stationary frame for Ld = Lq (the speed held or not), else the rotor
 * frame. */
static inline int sim_exact_part(const sim_exact_t *c, double *x, double *cs, double *sn, double h)
{
    if (c->m.dl != 0.0) {
        return sim_exact_part_dq(c, x, cs, sn, h);
    }
    return c->m.mech ? sim_exact_part_ab(c, x, cs, sn, h) : sim_exact_part_ab_held(c, x, cs, sn, h);
}

/*
 * Integrate x = (i_d, i_q, omega_m, theta_e[, V_o]) over len_s with the piece c (see the header
 * comment): parts of equal length with h*rate <= SIM_EXACT_RHO, each summed to SIM_EXACT_TOL; a part
 * that does not converge is halved.  cs, sn: cos and sin of x[3] on entry (the caller's, e.g. from the
 * previous piece), those of the new angle on return.  The angle is not wrapped.
 */
static inline void sim_exact_interval(const sim_exact_t *c, double *x, double *cs, double *sn,
                                      double len_s)
{
    const double rate = sim_exact_rate(c, x);
    double nd = ceil(len_s * rate / SIM_EXACT_RHO);
    double h, left = len_s;
    int halvings = 0;
    if (!(nd >= 1.0)) {
        nd = 1.0; /* (also a NaN rate: the part does not converge, the state becomes NaN) */
    } else if (nd > SIM_EXACT_MAX_PARTS) {
        nd = SIM_EXACT_MAX_PARTS; /* an infinite or absurd rate: the halvings take over */
    }
    h = len_s / nd;
    while (left > 0.0) {
        const double part = (left < h * (1.0 + 1e-12)) ? left : h;
        if (sim_exact_part(c, x, cs, sn, part) == 0) {
            left -= part;
        } else if (halvings < SIM_EXACT_MAX_HALVINGS) {
            h *= 0.5;
            ++halvings;
        } else { /* no convergence at any part length: a non-finite (diverged) state; say so */
            int k;
            for (k = 0; k < (c->np ? 5 : 4); ++k) {
                x[k] = nan("");
            }
            left = 0.0;
        }
    }
}

/* cos and sin of an angle kept from the end of the previous piece of a period (a piece ends with
 * them: its series of cos and sin), so that a period's pieces take one libm pair between them. */
typedef struct {
    double theta, cs, sn; /* the angle (as stored in the state) and its cos, sin */
    int valid;            /* 0: nothing kept */
} sim_exact_angle_t;

/* cos and sin of the angle x3, to start sim_exact_interval: the kept ones if a (may be NULL) holds
 * x3's, else libm's. */
static inline void sim_exact_cos_sin(const sim_exact_angle_t *a, double x3, double *cs, double *sn)
{
    if (a != NULL && a->valid && a->theta == x3) {
        *cs = a->cs;
        *sn = a->sn;
    } else {
        *cs = cos(x3);
        *sn = sin(x3);
    }
}

/* Keep cos and sin of the angle x3 in a (may be NULL). */
static inline void sim_exact_keep(sim_exact_angle_t *a, double x3, double cs, double sn)
{
    if (a != NULL) {
        a->theta = x3;
        a->cs = cs;
        a->sn = sn;
        a->valid = 1;
    }
}

/* One interval of e over dt_s with the device drops, if on (drop_v > 0, n_dev devices in each leg's
 * path), held at the phase currents' signs at its start (x[0], x[1] the dq currents, x[3] the angle,
 * n_x states): 0, or -1 with x restored when a sign changed by the end (the caller integrates the
 * interval with RK4 instead).  cos/sin of the angle: from ang at the start (may be NULL), of the end
 * in *cs, *sn. */
static inline int sim_exact_held_drops(sim_exact_t *e, double *x, int n_x, double drop_v, const double n_dev[3],
                                       const sim_exact_angle_t *ang, double dt_s, double *cs, double *sn)
{
    double x0[PMSM_RK4_MAX], i0[3];
    int k, leg;

    sim_exact_cos_sin(ang, x[3], cs, sn);
    if (drop_v > 0.0) {
        double dua, dub;
        sim_inverter_drop_ab(drop_v, n_dev, x[0], x[1], *cs, *sn, &dua, &dub);
        e->ua0 += dua;
        e->ub0 += dub;
        sim_inverter_phase_currents(x[0], x[1], x[3], i0);
        for (k = 0; k < n_x; ++k) {
            x0[k] = x[k];
        }
    }
    sim_exact_interval(e, x, cs, sn, dt_s);
    if (drop_v > 0.0) {
        double i1[3];
        sim_inverter_phase_currents(x[0], x[1], x[3], i1);
        for (leg = 0; leg < 3; ++leg) {
            if (sim_inverter_sign(i1[leg]) != sim_inverter_sign(i0[leg])) {
                for (k = 0; k < n_x; ++k) {
                    x[k] = x0[k];
                }
                return -1;
            }
        }
    }
    return 0;
}

#endif /* SIM_EXACT_H */
