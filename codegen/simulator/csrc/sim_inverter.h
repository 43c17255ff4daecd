/*
 * sim_inverter.h -- the inverter behaviour every topology's plant shares:
 * the non-idealities dead time and device voltage drops, on leg LEVELS
 * (two-level: 0 = lower rail, 1 = upper; T-type: -1 = N, 0 = O, +1 = P),
 * and the open inverter of a gates-off request (every switch off, the
 * phase currents in the diodes; "The open inverter" below) (hand-written
 * runtime, written once on sim_real_t: float64 on the host, float32 on
 * board, sim_real.h).
 *
 * Specification: docs/simulation.md "Inverter non-idealities" and "Fault
 * behaviour of the plant".
 *
 * Dead time (sim_inverter_dead_levels): at an edge of leg x from level a to
 * level b the switch being turned off opens at once and the one being turned
 * on closes dead_time_s later; in between the phase current i_x freewheels
 * through a diode, so the leg sits at
 *   min(a, b) if i_x > 0 (current out of the leg: drawn from the lower level),
 *   max(a, b) if i_x < 0 (current into the leg: pushed to the higher level),
 *   a         if i_x == 0,
 * with i_x taken at the edge and held for the dead time (the current moves
 * by a few mA in 1 us).  A rising edge with i_x > 0 therefore loses
 * (b - a)*dead_time volt-seconds, a falling edge with i_x < 0 gains them;
 * the other two lose nothing: the error follows the current's sign.  (Two-level:
 * the upper/lower pair; T-type: P<->O through T1/T3, O<->N through T2/T4,
 * the middle pair holding the freewheeling path.)
 *
 * Device drops (sim_inverter_drop_ab): each conducting device (IGBT or
 * diode) drops device_drop_v against the phase current, so the leg voltage
 * is u_x - n_x*V_d*sign(i_x), n_x the devices in the leg's conducting path
 * (the topology's: two-level 1; T-type 1 at P/N, 2 at O).  Evaluated at
 * every RK4 stage from the stage's currents (the drop flips with the
 * current's sign).  Its alpha-beta part (the common mode cancels):
 *   du_alpha = (2/3)*(d_a - (d_b + d_c)/2),  du_beta = (d_b - d_c)/sqrt(3).
 *
 * C99, no dynamic memory, no global state.  Not part of any cffi cdef.
 */
#ifndef SIM_INVERTER_H
#define SIM_INVERTER_H

#include "pmsm_dq.h"
#include "pmsm_rk4.h"
#include "sim_real.h"

/* sign(x) in {-1, 0, +1} */
static inline sim_real_t sim_inverter_sign(sim_real_t x)
{
    return (x > SIM_R(0.0)) ? SIM_R(1.0) : ((x < SIM_R(0.0)) ? SIM_R(-1.0) : SIM_R(0.0));
}

/* Levels of the three legs during the dead time of the edges from[] -> to[]
 * (legs without an edge: to[x]) given the phase currents i_abc[] (A). */
static inline void sim_inverter_dead_levels(const int from[3], const int to[3],
                                            const sim_real_t i_abc[3], int out[3])
{
    int x;
    for (x = 0; x < 3; ++x) {
        const int lo = from[x] < to[x] ? from[x] : to[x];
        const int hi = from[x] < to[x] ? to[x] : from[x];
        if (from[x] == to[x]) {
            out[x] = to[x];
        } else if (i_abc[x] > SIM_R(0.0)) {
            out[x] = lo;
        } else if (i_abc[x] < SIM_R(0.0)) {
            out[x] = hi;
        } else {
            out[x] = from[x];
        }
    }
}

/* 1 if any leg changes level. */
static inline int sim_inverter_edges(const int from[3], const int to[3])
{
    return from[0] != to[0] || from[1] != to[1] || from[2] != to[2];
}

/* Alpha-beta voltage of the device drops (V) at the stage currents i_d, i_q
 * and cos/sin of the stage angle; n_dev[x]: devices in leg x's path. */
static inline void sim_inverter_drop_ab(sim_real_t drop_v, const sim_real_t n_dev[3], sim_real_t id,
                                        sim_real_t iq, sim_real_t cs, sim_real_t sn,
                                        sim_real_t *du_alpha, sim_real_t *du_beta)
{
    const sim_real_t i_al = id * cs - iq * sn;
    const sim_real_t i_be = id * sn + iq * cs;
    const sim_real_t ia = i_al;
    const sim_real_t ib = -SIM_R(0.5) * i_al + PMSM_DQ_SQRT3_HALF * i_be;
    const sim_real_t ic = -ia - ib;
    const sim_real_t da = -drop_v * n_dev[0] * sim_inverter_sign(ia);
    const sim_real_t db = -drop_v * n_dev[1] * sim_inverter_sign(ib);
    const sim_real_t dc = -drop_v * n_dev[2] * sim_inverter_sign(ic);
    *du_alpha = (SIM_R(2.0) / SIM_R(3.0)) * (da - SIM_R(0.5) * (db + dc));
    *du_beta = PMSM_DQ_SQRT3_INV * (db - dc);
}

/* The device drops of n_dev[] devices per leg added to the dq voltage (ud, uq) at the stage
 * currents (id, iq) and cos/sin of the stage angle: u_dq += Park(du_alpha, du_beta). */
static inline void sim_inverter_add_drops(sim_real_t drop_v, const sim_real_t n_dev[3], sim_real_t id,
                                          sim_real_t iq, sim_real_t cs, sim_real_t sn,
                                          sim_real_t *ud, sim_real_t *uq)
{
    sim_real_t dua, dub, dud, duq;
    sim_inverter_drop_ab(drop_v, n_dev, id, iq, cs, sn, &dua, &dub);
    pmsm_dq_park(dua, dub, cs, sn, &dud, &duq);
    *ud += dud;
    *uq += duq;
}

/* Phase currents (i_a, i_b, i_c) of a motor state, A. */
static inline void sim_inverter_phase_currents(sim_real_t id, sim_real_t iq, sim_real_t theta_e_rad,
                                               sim_real_t i_abc[3])
{
    pmsm_dq_currents(id, iq, theta_e_rad, &i_abc[0], &i_abc[1]);
    i_abc[2] = -i_abc[0] - i_abc[1];
}

/*
 * Sub-steps of a piece of length len_s of a constant-voltage interval whose
 * largest sub-step is h_max_s: ceil(len_s/h_max_s) with a relative
 * tolerance SIM_SUBSTEP_TOL (float64 1e-9; so that len_s = n*h_max_s gives
 * n), at least 1, at most SIM_SUBSTEP_MAX.
 */
static inline int sim_inverter_substeps(sim_real_t len_s, sim_real_t h_max_s)
{
    const sim_real_t nd = SIM_CEIL(len_s / h_max_s - SIM_SUBSTEP_TOL);
    return (nd < SIM_R(1.0)) ? 1 : (nd > (sim_real_t)SIM_SUBSTEP_MAX ? SIM_SUBSTEP_MAX : (int)nd);
}

/* ---------------------------------------------------------------------------
 * The open inverter: a gates-off request, every switch off (docs/simulation.md
 * "Fault behaviour of the plant").
 *
 * A leg then conducts only through its anti-parallel diodes (two-level: the
 * lower and upper diode; T-type: the outer diodes of T1 and T4, the
 * neutral-point clamp pair T2/T3 off, so the midpoint carries no current and
 * dV_o/dt = 0).  Leg potential v_x above the lower rail, each diode dropping
 * V_d (device_drop_v):
 *   LOWER  i_x > 0 (out of the leg into the motor) comes up the lower diode:
 *          v_x = -V_d;
 *   UPPER  i_x < 0 goes up the upper diode into the upper rail: v_x = Udc + V_d;
 *   FLOAT  i_x = 0, both diodes blocked: v_x is what the motor makes it, the
 *          potential that keeps di_x/dt = 0, as long as it stays within
 *          [-V_d, Udc + V_d]; beyond it the diode on that side conducts
 *          (uncontrolled rectification through the diode bridge).
 * The stator voltage of the leg potentials (isolated star point: the common
 * mode cancels, so the T-type's rails u_c1 and -u_c2 about the midpoint
 * give the same, Udc = u_c1 + u_c2 apart):
 *   u_alpha = (2/3)*(v_a - (v_b + v_c)/2),  u_beta = (v_b - v_c)/sqrt(3)
 * and the motor is pmsm_dq.h's (Ld and Lq may differ).
 *
 * One floating leg f (the two others conduct, with equal and opposite
 * currents): i_f = c_f . i_ab, c_a = (1, 0), c_b = (-1/2, sqrt(3)/2),
 * c_c = (-1/2, -sqrt(3)/2), and di_f/dt is affine in v_f:
 *   di_f/dt = A + B*v_f,
 *   A = g . (di_d/dt, di_q/dt)|v_f=0 + omega_e*(c_f,beta*i_alpha - c_f,alpha*i_beta)
 *       (di_ab/dt = invPark(di_dq/dt) + omega_e*(-i_beta, i_alpha), g = Park(c_f)),
 *   B = (2/3)*(g_d^2/Ld + g_q^2/Lq) > 0   (du_ab/dv_f = (2/3)*c_f),
 * so v_f = -A/B, evaluated at every RK4 stage (sim_open_derivs).  Every leg
 * floating (every current zero): di/dt = 0 while the open-circuit phase
 * voltages e = invPark(0, omega_e*psi_f) (u_d = 0, u_q = omega_e*psi_f: the
 * motor equations at i = di/dt = 0) stay within the DC link,
 * max e_x - min e_x <= Udc + 2*V_d; beyond it the highest phase starts
 * conducting UPPER, the lowest LOWER, the third floats.
 *
 * Modes (sim_open_classify) are fixed over each RK4 sub-step, taken from
 * the currents at its start: a leg with |i_x| <= SIM_ZERO_TOL*max|i| is at
 * zero (FLOAT if its v_f lies within the DC link, else the diode it drives
 * into), the others by the sign of their current.
 *
 * Zero crossing, without chattering: a conducting leg whose current changes
 * sign within a sub-step (LOWER: below 0; UPPER: above 0) stops at zero
 * there.  The crossing is placed at the fraction f = i0/(i0 - i1) of the
 * sub-step (linear interpolation of the leg's current between the
 * sub-step's ends), the sub-step is integrated again from its start over
 * f*h, the leg's current is set to exactly zero (sim_open_zero: the
 * orthogonal projection i_ab -= i_f*c_f, which keeps i_a + i_b + i_c = 0 --
 * the other two legs get i_x + i_f/2; with a second leg at zero, or two
 * legs crossing at once, every current is zero) and the rest (1 - f)*h is
 * integrated with the leg floating.  A floating leg's current stays zero:
 * its di/dt is 0 at every RK4 stage, and the projection at each sub-step's
 * start removes the RK4 truncation drift.  So a phase never alternates
 * between conducting and blocking: it conducts again only when its floating
 * potential leaves the DC link.
 * ------------------------------------------------------------------------- */

/* Conduction of a leg of the open inverter. */
#define SIM_OPEN_LOWER 0 /* i_x > 0 through the lower diode */
#define SIM_OPEN_UPPER 1 /* i_x < 0 through the upper diode */
#define SIM_OPEN_FLOAT 2 /* i_x = 0, both diodes blocked */
/* Most zero crossings handled within one sub-step (further ones wait for the next sub-step). */
#define SIM_OPEN_MAX_EVENTS 4

/* The open inverter and the motor over one interval; mode, n_float and fl hold one sub-step's. */
typedef struct {
    pmsm_dq_rhs_t m;    /* motor equations (pmsm_dq.h) */
    sim_real_t udc_v;   /* DC link between the rails, V */
    sim_real_t drop_v;  /* diode drop, V (0: off) */
    int nx;             /* state entries: 4 (motor), 5 (T-type: V_o held) */
    int mode[3];        /* SIM_OPEN_* of each leg */
    int n_float;        /* floating legs: 0, 1 or 3 */
    int fl;             /* the floating leg when n_float == 1 */
} sim_open_t;

/* The inverter part of c (the motor part: pmsm_dq_rhs_setup(&c->m, ...)); nx: 4 or 5 state entries. */
static inline void sim_open_setup(sim_open_t *c, sim_real_t udc_v, sim_real_t drop_v, int nx)
{
    int k;
    c->udc_v = udc_v;
    c->drop_v = drop_v;
    c->nx = nx;
    for (k = 0; k < 3; ++k) {
        c->mode[k] = SIM_OPEN_FLOAT;
    }
    c->n_float = 3;
    c->fl = 0;
}

/* c_x, the unit vector of phase x in alpha-beta: i_x = c_x . i_ab (amplitude-invariant Clarke). */
static inline void sim_open_axis(int leg, sim_real_t *c_alpha, sim_real_t *c_beta)
{
    *c_alpha = (leg == 0) ? SIM_R(1.0) : -SIM_R(0.5);
    *c_beta = (leg == 0) ? SIM_R(0.0) : ((leg == 1) ? PMSM_DQ_SQRT3_HALF : -PMSM_DQ_SQRT3_HALF);
}

/* Motor derivatives (dx[0..3]) at the stage angle (cs, sn) with the conducting legs at their diode
 * potentials (LOWER -V_d, UPPER Udc + V_d) and the floating leg, if one, at v_f = -A/B (di_f/dt = 0);
 * *v_fl receives v_f (0 without a floating leg). */
static inline void sim_open_derivs(const sim_open_t *c, const sim_real_t *x, sim_real_t cs, sim_real_t sn,
                                   sim_real_t *dx, sim_real_t *v_fl)
{
    sim_real_t v[3], ud, uq;
    int k;
    for (k = 0; k < 3; ++k) {
        v[k] = (c->mode[k] == SIM_OPEN_UPPER) ? c->udc_v + c->drop_v
               : ((c->mode[k] == SIM_OPEN_LOWER) ? -c->drop_v : SIM_R(0.0));
    }
    /* u_alpha = (2/3)*(v_a - (v_b + v_c)/2), u_beta = (v_b - v_c)/sqrt(3); Park; the motor */
    pmsm_dq_park((SIM_R(2.0) / SIM_R(3.0)) * (v[0] - SIM_R(0.5) * (v[1] + v[2])),
                 PMSM_DQ_SQRT3_INV * (v[1] - v[2]), cs, sn, &ud, &uq);
    pmsm_dq_derivs(&c->m, x[0], x[1], x[2], ud, uq, &dx[0], &dx[1], &dx[2], &dx[3]);
    *v_fl = SIM_R(0.0);
    if (c->n_float == 1) {
        sim_real_t ca, cb, gd, gq, a, b;
        const sim_real_t i_al = x[0] * cs - x[1] * sn;
        const sim_real_t i_be = x[0] * sn + x[1] * cs;
        sim_open_axis(c->fl, &ca, &cb);
        pmsm_dq_park(ca, cb, cs, sn, &gd, &gq); /* g = Park(c_f) */
        /* A = g . di_dq/dt (at v_f = 0) + omega_e*(c_beta*i_alpha - c_alpha*i_beta), omega_e = dx[3] */
        a = gd * dx[0] + gq * dx[1] + dx[3] * (cb * i_al - ca * i_be);
        /* B = (2/3)*(g_d^2/Ld + g_q^2/Lq) */
        b = (SIM_R(2.0) / SIM_R(3.0)) * (gd * gd * c->m.inv_ld + gq * gq * c->m.inv_lq);
        *v_fl = -a / b;
        /* di_dq/dt += v_f * d(di_dq/dt)/dv_f = v_f*(2/3)*(g_d/Ld, g_q/Lq) */
        dx[0] += *v_fl * (SIM_R(2.0) / SIM_R(3.0)) * gd * c->m.inv_ld;
        dx[1] += *v_fl * (SIM_R(2.0) / SIM_R(3.0)) * gq * c->m.inv_lq;
    }
}

/* f(x) of the open inverter at the stage angle (pmsm_rk4.h): the motor with the leg potentials of
 * sim_open_derivs; every leg floating: di_d/dt = di_q/dt = 0; V_o (nx = 5) held: no midpoint current. */
static inline void sim_open_rhs(const void *ctx, const sim_real_t *x, sim_real_t cs, sim_real_t sn,
                                sim_real_t *dx)
{
    const sim_open_t *c = (const sim_open_t *)ctx;
    sim_real_t v_fl;
    int k;
    sim_open_derivs(c, x, cs, sn, dx, &v_fl);
    if (c->n_float == 3) {
        dx[0] = SIM_R(0.0);
        dx[1] = SIM_R(0.0);
    }
    for (k = 4; k < c->nx; ++k) {
        dx[k] = SIM_R(0.0);
    }
}

/* Phase leg's current set to zero, in the dq state x (leg < 0: every current): i_dq -= (g . i_dq)*g,
 * g = Park(c_leg) -- the orthogonal projection i_ab -= i_leg*c_leg in the rotor frame. */
static inline void sim_open_zero(sim_real_t *x, int leg)
{
    sim_real_t ca, cb, gd, gq, i_leg;
    if (leg < 0) {
        x[0] = SIM_R(0.0);
        x[1] = SIM_R(0.0);
        return;
    }
    sim_open_axis(leg, &ca, &cb);
    pmsm_dq_park(ca, cb, SIM_COS(x[3]), SIM_SIN(x[3]), &gd, &gq);
    i_leg = gd * x[0] + gq * x[1];
    x[0] -= i_leg * gd;
    x[1] -= i_leg * gq;
}

/* Every current zero: every leg floats, unless the open-circuit line voltage exceeds the DC link
 * (max e_x - min e_x > Udc + 2*V_d, e = invPark(0, omega_e*psi_f), inverse Clarke): then the highest
 * phase conducts UPPER, the lowest LOWER, the third floats. */
static inline void sim_open_from_rest(sim_open_t *c, const sim_real_t *x)
{
    const sim_real_t wpsi = c->m.p * x[2] * c->m.psi_f;
    const sim_real_t e_al = -wpsi * SIM_SIN(x[3]);
    const sim_real_t e_be = wpsi * SIM_COS(x[3]);
    sim_real_t e[3];
    int k, hi = 0, lo = 0;
    e[0] = e_al;
    e[1] = -SIM_R(0.5) * e_al + PMSM_DQ_SQRT3_HALF * e_be;
    e[2] = -e[0] - e[1];
    for (k = 0; k < 3; ++k) {
        c->mode[k] = SIM_OPEN_FLOAT;
        hi = (e[k] > e[hi]) ? k : hi;
        lo = (e[k] < e[lo]) ? k : lo;
    }
    c->n_float = 3;
    if (e[hi] - e[lo] > c->udc_v + SIM_R(2.0) * c->drop_v) {
        c->mode[hi] = SIM_OPEN_UPPER;
        c->mode[lo] = SIM_OPEN_LOWER;
        c->n_float = 1;
        c->fl = 3 - hi - lo;
    }
}

/* The modes of the sub-step starting at x (see the section comment); a leg found at zero that floats
 * has its current set to exactly zero in x. */
static inline void sim_open_classify(sim_open_t *c, sim_real_t *x)
{
    sim_real_t i[3], imax = SIM_R(0.0);
    int k, n_zero = 0, zero_leg = 0;
    sim_inverter_phase_currents(x[0], x[1], x[3], i);
    for (k = 0; k < 3; ++k) {
        imax = (SIM_FABS(i[k]) > imax) ? SIM_FABS(i[k]) : imax;
    }
    c->n_float = 0;
    for (k = 0; k < 3; ++k) {
        c->mode[k] = (i[k] > SIM_R(0.0)) ? SIM_OPEN_LOWER : SIM_OPEN_UPPER;
        if (SIM_FABS(i[k]) <= SIM_ZERO_TOL * imax) {
            ++n_zero;
            zero_leg = k;
        }
    }
    if (n_zero >= 2) { /* two at zero: the third too (they sum to zero) */
        sim_open_zero(x, -1);
        sim_open_from_rest(c, x);
    } else if (n_zero == 1) {
        /* the floating potential that holds it at zero, against the DC link */
        sim_real_t dx[PMSM_RK4_MAX], v_fl;
        c->mode[zero_leg] = SIM_OPEN_FLOAT;
        c->n_float = 1;
        c->fl = zero_leg;
        sim_open_derivs(c, x, SIM_COS(x[3]), SIM_SIN(x[3]), dx, &v_fl);
        if (v_fl < -c->drop_v) {
            c->mode[zero_leg] = SIM_OPEN_LOWER; /* pulled below the lower rail: the lower diode conducts */
            c->n_float = 0;
        } else if (v_fl > c->udc_v + c->drop_v) {
            c->mode[zero_leg] = SIM_OPEN_UPPER; /* pushed above the upper rail: the upper diode conducts */
            c->n_float = 0;
        } else {
            sim_open_zero(x, zero_leg);
        }
    }
}

/* The earliest zero crossing of a conducting leg's current over a sub-step from currents i0 to i1: its
 * fraction f = i0/(i0 - i1) in (0, 1) of the sub-step, *leg the leg to zero there (-1: every current,
 * when two legs cross at once (within SIM_ZERO_TOL of f) or a leg already floats); 1 if none. */
static inline sim_real_t sim_open_crossing(const sim_open_t *c, const sim_real_t i0[3],
                                           const sim_real_t i1[3], int *leg)
{
    sim_real_t fk[3], f = SIM_R(1.0);
    int k, n = 0;
    for (k = 0; k < 3; ++k) {
        const sim_real_t s = (c->mode[k] == SIM_OPEN_LOWER) ? SIM_R(1.0) : SIM_R(-1.0);
        fk[k] = SIM_R(1.0);
        if (c->mode[k] != SIM_OPEN_FLOAT && s * i0[k] > SIM_R(0.0) && s * i1[k] < SIM_R(0.0)) {
            fk[k] = i0[k] / (i0[k] - i1[k]);
            f = (fk[k] < f) ? fk[k] : f;
        }
    }
    *leg = -1;
    for (k = 0; k < 3; ++k) {
        if (fk[k] < SIM_R(1.0) && fk[k] <= f + SIM_ZERO_TOL) {
            ++n;
            *leg = k;
        }
    }
    if (n > 1 || c->n_float == 1) {
        *leg = -1;
    }
    return f;
}

/*
 * Integrate x = (i_d, i_q, omega_m, theta_e[, V_o]) over dt_s with the open inverter c, in `substeps`
 * equal sub-steps h (the angle unwrapped: the caller wraps): per sub-step the modes at its start, one
 * RK4 step (pmsm_rk4.h), and at a zero crossing inside it the step up to the crossing, the current set
 * to zero and the rest of the sub-step (see the section comment).
 */
static inline void sim_open_interval(sim_open_t *c, sim_real_t *x, sim_real_t dt_s, int substeps)
{
    const sim_real_t h = dt_s / (sim_real_t)substeps;
    int n, k;
    for (n = 0; n < substeps; ++n) {
        sim_real_t left = h;
        int events = 0;
        while (left > SIM_R(0.0)) {
            sim_real_t x0[PMSM_RK4_MAX], i0[3], i1[3], f = SIM_R(1.0);
            int leg = -1;
            sim_open_classify(c, x);
            sim_inverter_phase_currents(x[0], x[1], x[3], i0);
            for (k = 0; k < c->nx; ++k) {
                x0[k] = x[k];
            }
            /* every leg floating: no Park rotation needed (u and di/dt are zero) */
            pmsm_rk4_integrate(sim_open_rhs, c, c->n_float != 3, x, c->nx, left, 1);
            if (c->n_float != 3 && events < SIM_OPEN_MAX_EVENTS) {
                sim_inverter_phase_currents(x[0], x[1], x[3], i1);
                f = sim_open_crossing(c, i0, i1, &leg);
            }
            if (f < SIM_R(1.0)) {
                /* a crossing at f*left: the step again up to it, that current to zero, then the rest */
                const sim_real_t part = f * left;
                for (k = 0; k < c->nx; ++k) {
                    x[k] = x0[k];
                }
                pmsm_rk4_integrate(sim_open_rhs, c, 1, x, c->nx, part, 1);
                sim_open_zero(x, leg);
                left -= part;
                ++events;
            } else {
                left = SIM_R(0.0);
            }
        }
    }
}

#endif /* SIM_INVERTER_H */
