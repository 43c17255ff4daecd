/*
 * plant3l.c -- T-type three-level inverter + PMSM plant, float64 (see
 * plant3l.h for the model, the neutral-point sign convention and the
 * integration method).
 *
 * Specification: shared/spec/plant-and-metrics.md "Plant" and
 * shared/spec/mpdtc-three-level.md "Inverter, vectors, neutral point".
 * C99; compiles warning-free with
 *   gcc -std=c99 -O2 -Wall -Wextra -Wconversion -Wdouble-promotion -Werror
 *       -ffp-contract=off
 * (no fused multiply-add: the same bits on every host, chunked runs equal
 * one long run exactly).
 */
#include "plant3l.h"

#include <math.h>
#include <stddef.h>

#include "pmsm_dq.h"

/* Constants of the right-hand side for one segment (one switching state). */
typedef struct {
    /* u_alpha = ua0 + ua1*V_o, u_beta = ub0 + ub1*V_o (u_xo = S*Udc/2 + |S|*V_o) */
    double ua0, ua1, ub0, ub1;
    /* i_o = ka*i_alpha + kb*i_beta, already divided by 2C: dV_o/dt = ka*i_al + kb*i_be */
    double ka, kb;
    pmsm_dq_rhs_t m;                      /* motor equations (pmsm_dq.h) */
    int zero_u;                           /* 1: NNN/OOO/PPP: u = 0 and i_o = 0 */
} rhs3_t;

int plant3l_levels(int state, int levels[3])
{
    if (state < 0 || state >= PLANT3L_N_STATES) {
        return -1;
    }
    levels[0] = state / 9 - 1;
    levels[1] = (state / 3) % 3 - 1;
    levels[2] = state % 3 - 1;
    return 0;
}

/* Coefficients of u_alpha, u_beta (V and V per V of V_o) and of i_o (per unit
 * i_alpha, i_beta) for state lv (see plant3l.h):
 *   u_alpha = (2/3)*(u_ao - (u_bo + u_co)/2),  u_beta = (u_bo - u_co)/sqrt(3)
 *   i_o = -sum |S_x| i_x = -(|Sa| - (|Sb|+|Sc|)/2)*i_alpha - (sqrt(3)/2)(|Sb|-|Sc|)*i_beta
 *   (i_a = i_alpha, i_b = -i_alpha/2 + (sqrt3/2) i_beta, i_c = -i_alpha/2 - (sqrt3/2) i_beta) */
static void state_coeffs(const plant3l_params_t *p, const int lv[3], double *ua0, double *ua1,
                         double *ub0, double *ub1, double *ka, double *kb)
{
    const double sa = (double)lv[0], sb = (double)lv[1], sc = (double)lv[2];
    const double aa = fabs(sa), ab = fabs(sb), ac = fabs(sc);
    const double half = 0.5 * p->udc_v;
    *ua0 = (2.0 / 3.0) * half * (sa - 0.5 * (sb + sc));
    *ua1 = (2.0 / 3.0) * (aa - 0.5 * (ab + ac));
    *ub0 = half * PMSM_DQ_SQRT3_INV * (sb - sc);
    *ub1 = PMSM_DQ_SQRT3_INV * (ab - ac);
    *ka = -(aa - 0.5 * (ab + ac));
    *kb = -PMSM_DQ_SQRT3_HALF * (ab - ac);
}

void plant3l_voltage_ab(const plant3l_params_t *p, int state, double vo_v,
                        double *u_alpha_v, double *u_beta_v)
{
    int lv[3];
    double ua0, ua1, ub0, ub1, ka, kb;
    if (plant3l_levels(state, lv) != 0) {
        *u_alpha_v = 0.0;
        *u_beta_v = 0.0;
        return;
    }
    state_coeffs(p, lv, &ua0, &ua1, &ub0, &ub1, &ka, &kb);
    *u_alpha_v = ua0 + ua1 * vo_v;
    *u_beta_v = ub0 + ub1 * vo_v;
}

/* u_ab = u_ao - u_bo, u_xo = S_x*Udc/2 + |S_x|*V_o */
double plant3l_uab(const plant3l_params_t *p, int state, double vo_v)
{
    int lv[3];
    double uao, ubo;
    if (plant3l_levels(state, lv) != 0) {
        return 0.0;
    }
    uao = (double)lv[0] * 0.5 * p->udc_v + (double)(lv[0] != 0) * vo_v;
    ubo = (double)lv[1] * 0.5 * p->udc_v + (double)(lv[1] != 0) * vo_v;
    return uao - ubo;
}

void plant3l_phase_currents(const plant3l_state_t *s, double *ia_a, double *ib_a)
{
    pmsm_dq_phase_currents(s->i_d_a, s->i_q_a, s->theta_e_rad, ia_a, ib_a);
}

double plant3l_io(const plant3l_state_t *s, int state)
{
    int lv[3];
    double ia, ib, ic;
    if (plant3l_levels(state, lv) != 0) {
        return 0.0;
    }
    plant3l_phase_currents(s, &ia, &ib);
    ic = -ia - ib;
    return (double)(lv[0] == 0) * ia + (double)(lv[1] == 0) * ib + (double)(lv[2] == 0) * ic;
}

double plant3l_wrap_angle(double x)
{
    return pmsm_dq_wrap_angle(x);
}

double plant3l_torque(const plant3l_state_t *s, const plant3l_params_t *p)
{
    return pmsm_dq_torque(s->i_d_a, s->i_q_a, p->ld_h, p->lq_h, p->psi_f_wb, p->pole_pairs);
}

double plant3l_flux(const plant3l_state_t *s, const plant3l_params_t *p)
{
    return pmsm_dq_flux(s->i_d_a, s->i_q_a, p->ld_h, p->lq_h, p->psi_f_wb);
}

/* ---------------------------------------------------------------------------
 * Right-hand side at one RK4 stage, x = (i_d, i_q, w_m, theta_e, V_o), given
 * cos/sin of the stage angle:
 *   u_alpha = ua0 + ua1*V_o, u_beta = ub0 + ub1*V_o
 *   u_d = u_alpha*cos + u_beta*sin,  u_q = u_beta*cos - u_alpha*sin  (Park)
 *   di_d/dt = (u_d - Rs*i_d + w_e*Lq*i_q)/Ld
 *   di_q/dt = (u_q - Rs*i_q - w_e*Ld*i_d - w_e*psi_f)/Lq
 *   dw_m/dt = (Te - T_L - B*w_m)/J  (0 when the speed is imposed)
 *   dtheta_e/dt = w_e = p*w_m
 *   dV_o/dt = i_o/(2C),  i_alpha = i_d*cos - i_q*sin, i_beta = i_d*sin + i_q*cos
 * ------------------------------------------------------------------------- */
static inline void rhs3(const rhs3_t *c, double id, double iq, double wm, double vo, double cs,
                        double sn, double *did, double *diq, double *dwm, double *dth, double *dvo)
{
    double ud = 0.0, uq = 0.0;
    if (!c->zero_u) {
        const double ua = c->ua0 + c->ua1 * vo;
        const double ub = c->ub0 + c->ub1 * vo;
        const double ial = id * cs - iq * sn;
        const double ibe = id * sn + iq * cs;
        ud = ua * cs + ub * sn;
        uq = ub * cs - ua * sn;
        *dvo = c->ka * ial + c->kb * ibe;
    } else {
        *dvo = 0.0;
    }
    pmsm_dq_derivs(&c->m, id, iq, wm, ud, uq, did, diq, dwm, dth);
}

static void setup(rhs3_t *c, const plant3l_params_t *p, int state, double load_nm, int speed_imposed)
{
    int lv[3] = {0, 0, 0};
    (void)plant3l_levels(state, lv); /* state checked by the callers */
    state_coeffs(p, lv, &c->ua0, &c->ua1, &c->ub0, &c->ub1, &c->ka, &c->kb);
    c->ka = c->ka / (2.0 * p->c_f);
    c->kb = c->kb / (2.0 * p->c_f);
    c->zero_u = (lv[0] == lv[1] && lv[1] == lv[2]);
    pmsm_dq_rhs_setup(&c->m, p->rs_ohm, p->ld_h, p->lq_h, p->psi_f_wb, p->pole_pairs, p->j_kgm2,
                      p->b_nms, load_nm, speed_imposed);
}

/* Classic RK4, `substeps` equal sub-steps of h = dt/substeps, on the
 * unwrapped angle (the caller wraps):
 *   k1 = f(x), k2 = f(x + h/2 k1), k3 = f(x + h/2 k2), k4 = f(x + h k3),
 *   x <- x + h/6 (k1 + 2 k2 + 2 k3 + k4).
 * Each stage uses its own angle (theta + h/2*w_e1, theta + h/2*w_e2,
 * theta + h*w_e3) for Park; cos/sin from one libm call per sub-step plus
 * pmsm_dq_rotate(). */
static void integrate(const rhs3_t *c, plant3l_state_t *s, double dt_s, int substeps)
{
    const double h = dt_s / (double)substeps;
    const double h2 = 0.5 * h;
    const double h6 = h / 6.0;
    double id = s->i_d_a, iq = s->i_q_a, wm = s->omega_m_rad_s, th = s->theta_e_rad, vo = s->vo_v;
    int n;

    for (n = 0; n < substeps; ++n) {
        double d1, q1, w1, t1, v1, d2, q2, w2, t2, v2, d3, q3, w3, t3, v3, d4, q4, w4, t4, v4;
        double c0 = 1.0, s0 = 0.0, cs = 1.0, sn = 0.0;

        if (!c->zero_u) {
            c0 = cos(th);
            s0 = sin(th);
        }
        rhs3(c, id, iq, wm, vo, c0, s0, &d1, &q1, &w1, &t1, &v1);

        if (!c->zero_u) {
            pmsm_dq_rotate(c0, s0, h2 * t1, &cs, &sn);
        }
        rhs3(c, id + h2 * d1, iq + h2 * q1, wm + h2 * w1, vo + h2 * v1, cs, sn, &d2, &q2, &w2, &t2, &v2);

        if (!c->zero_u && t2 != t1) {
            pmsm_dq_rotate(c0, s0, h2 * t2, &cs, &sn);
        }
        rhs3(c, id + h2 * d2, iq + h2 * q2, wm + h2 * w2, vo + h2 * v2, cs, sn, &d3, &q3, &w3, &t3, &v3);

        if (!c->zero_u) {
            pmsm_dq_rotate(c0, s0, h * t3, &cs, &sn);
        }
        rhs3(c, id + h * d3, iq + h * q3, wm + h * w3, vo + h * v3, cs, sn, &d4, &q4, &w4, &t4, &v4);

        id += h6 * (d1 + 2.0 * d2 + 2.0 * d3 + d4);
        iq += h6 * (q1 + 2.0 * q2 + 2.0 * q3 + q4);
        wm += h6 * (w1 + 2.0 * w2 + 2.0 * w3 + w4);
        th += h6 * (t1 + 2.0 * t2 + 2.0 * t3 + t4);
        vo += h6 * (v1 + 2.0 * v2 + 2.0 * v3 + v4);
    }
    s->i_d_a = id;
    s->i_q_a = iq;
    s->omega_m_rad_s = wm;
    s->theta_e_rad = th;
    s->vo_v = vo;
}

int plant3l_advance(plant3l_state_t *s, const plant3l_params_t *p, int state,
                    double load_nm, double dt_s, int substeps, int speed_imposed)
{
    rhs3_t c;
    if (state < 0 || state >= PLANT3L_N_STATES || substeps < 1 || !(dt_s > 0.0) || !isfinite(dt_s)) {
        return -1;
    }
    setup(&c, p, state, load_nm, speed_imposed);
    integrate(&c, s, dt_s, substeps);
    s->theta_e_rad = pmsm_dq_wrap_angle(s->theta_e_rad);
    return 0;
}

int plant3l_advance_segments(plant3l_state_t *s, const plant3l_params_t *p,
                             const unsigned short states[7], const double seg_s[7],
                             double load_nm, double substep_max_s, int speed_imposed,
                             double uab_v[7])
{
    int i;
    if (!(substep_max_s > 0.0) || !isfinite(substep_max_s)) {
        return -1;
    }
    for (i = 0; i < PLANT3L_N_SEG; ++i) {
        if (states[i] >= PLANT3L_N_STATES || !(seg_s[i] >= 0.0) || !isfinite(seg_s[i])) {
            return -1;
        }
    }
    for (i = 0; i < PLANT3L_N_SEG; ++i) {
        const int st = (int)states[i];
        if (uab_v != NULL) {
            uab_v[i] = plant3l_uab(p, st, s->vo_v);
        }
        if (seg_s[i] > 0.0) {
            rhs3_t c;
            /* fewest equal sub-steps with h <= substep_max_s (1e-9 relative tolerance) */
            double nd = ceil(seg_s[i] / substep_max_s - 1e-9);
            int n = (nd < 1.0) ? 1 : (nd > 1e8 ? 100000000 : (int)nd);
            setup(&c, p, st, load_nm, speed_imposed);
            integrate(&c, s, seg_s[i], n);
        }
    }
    s->theta_e_rad = pmsm_dq_wrap_angle(s->theta_e_rad);
    return 0;
}
