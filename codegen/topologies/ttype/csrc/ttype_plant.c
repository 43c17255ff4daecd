/*
 * ttype_plant.c -- T-type three-level inverter + PMSM plant, float64 (see
 * ttype_plant.h for the model, the neutral-point sign convention and the
 * integration method).
 *
 * Specification: docs/simulation.md "Plant" and
 * docs/algorithms.md (T-type MPDTC) "Inverter, vectors, neutral point".
 * C99; compiles warning-free with
 *   gcc -std=c99 -O2 -Wall -Wextra -Wconversion -Wdouble-promotion -Werror
 *       -ffp-contract=off
 * (no fused multiply-add: the same bits on every host, chunked runs equal
 * one long run exactly).
 */
#include "ttype_plant.h"

#include <math.h>
#include <stddef.h>

#include "pmsm_dq.h"
#include "pmsm_rk4.h"
#include "sim_inverter.h"

/* Constants of the right-hand side for one interval of constant leg levels. */
typedef struct {
    /* u_alpha = ua0 + ua1*V_o, u_beta = ub0 + ub1*V_o (u_xo = S*Udc/2 + |S|*V_o) */
    double ua0, ua1, ub0, ub1;
    /* i_o = ka*i_alpha + kb*i_beta, already divided by 2C: dV_o/dt = ka*i_al + kb*i_be */
    double ka, kb;
    pmsm_dq_rhs_t m;                      /* motor equations (pmsm_dq.h) */
    int zero_u;                           /* 1: NNN/OOO/PPP: u = 0 and i_o = 0 */
    double drop_v;                        /* device drop, V (0: off) */
    double n_dev[3];                      /* devices in each leg's path: 1 at P/N, 2 at O */
} rhs_t;

int ttype_plant_levels(int state, int levels[3])
{
    if (state < 0 || state >= TTYPE_PLANT_N_STATES) {
        return -1;
    }
    levels[0] = state / 9 - 1;
    levels[1] = (state / 3) % 3 - 1;
    levels[2] = state % 3 - 1;
    return 0;
}

/* Coefficients of u_alpha, u_beta (V and V per V of V_o) and of i_o (per unit
 * i_alpha, i_beta) for state lv (see ttype_plant.h):
 *   u_alpha = (2/3)*(u_ao - (u_bo + u_co)/2),  u_beta = (u_bo - u_co)/sqrt(3)
 *   i_o = -sum |S_x| i_x = -(|Sa| - (|Sb|+|Sc|)/2)*i_alpha - (sqrt(3)/2)(|Sb|-|Sc|)*i_beta
 *   (i_a = i_alpha, i_b = -i_alpha/2 + (sqrt3/2) i_beta, i_c = -i_alpha/2 - (sqrt3/2) i_beta) */
static void state_coeffs(const ttype_sim_params_t *p, const int lv[3], double *ua0, double *ua1,
                         double *ub0, double *ub1, double *ka, double *kb)
{
    const double sa = (double)lv[0], sb = (double)lv[1], sc = (double)lv[2];
    const double aa = fabs(sa), ab = fabs(sb), ac = fabs(sc);
    const double half = 0.5 * p->common.udc_v;
    *ua0 = (2.0 / 3.0) * half * (sa - 0.5 * (sb + sc));
    *ua1 = (2.0 / 3.0) * (aa - 0.5 * (ab + ac));
    *ub0 = half * PMSM_DQ_SQRT3_INV * (sb - sc);
    *ub1 = PMSM_DQ_SQRT3_INV * (ab - ac);
    *ka = -(aa - 0.5 * (ab + ac));
    *kb = -PMSM_DQ_SQRT3_HALF * (ab - ac);
}

void ttype_plant_voltage_ab(const ttype_sim_params_t *p, int state, double vo_v,
                        double *u_alpha_v, double *u_beta_v)
{
    int lv[3];
    double ua0, ua1, ub0, ub1, ka, kb;
    if (ttype_plant_levels(state, lv) != 0) {
        *u_alpha_v = 0.0;
        *u_beta_v = 0.0;
        return;
    }
    state_coeffs(p, lv, &ua0, &ua1, &ub0, &ub1, &ka, &kb);
    *u_alpha_v = ua0 + ua1 * vo_v;
    *u_beta_v = ub0 + ub1 * vo_v;
}

/* u_ab = u_ao - u_bo, u_xo = S_x*Udc/2 + |S_x|*V_o */
double ttype_plant_uab(const ttype_sim_params_t *p, int state, double vo_v)
{
    int lv[3];
    double uao, ubo;
    if (ttype_plant_levels(state, lv) != 0) {
        return 0.0;
    }
    uao = (double)lv[0] * 0.5 * p->common.udc_v + (double)(lv[0] != 0) * vo_v;
    ubo = (double)lv[1] * 0.5 * p->common.udc_v + (double)(lv[1] != 0) * vo_v;
    return uao - ubo;
}

double ttype_plant_io(const ttype_plant_state_t *s, int state)
{
    int lv[3];
    double ia, ib, ic;
    if (ttype_plant_levels(state, lv) != 0) {
        return 0.0;
    }
    pmsm_dq_phase_currents(s->motor.i_d_a, s->motor.i_q_a, s->motor.theta_e_rad, &ia, &ib);
    ic = -ia - ib;
    return (double)(lv[0] == 0) * ia + (double)(lv[1] == 0) * ib + (double)(lv[2] == 0) * ic;
}

/* ---------------------------------------------------------------------------
 * Right-hand side at one RK4 stage, x = (i_d, i_q, w_m, theta_e, V_o), given
 * cos/sin of the stage angle:
 *   u_alpha = ua0 + ua1*V_o, u_beta = ub0 + ub1*V_o
 *   u_d = u_alpha*cos + u_beta*sin,  u_q = u_beta*cos - u_alpha*sin  (Park)
 *   di_d/dt, di_q/dt, dw_m/dt, dtheta_e/dt: pmsm_dq_derivs (pmsm_dq.h)
 *   dV_o/dt = i_o/(2C),  i_alpha = i_d*cos - i_q*sin, i_beta = i_d*sin + i_q*cos
 * ------------------------------------------------------------------------- */
static inline void rhs(const void *ctx, const double *x, double cs, double sn, double *dx)
{
    const rhs_t *c = (const rhs_t *)ctx;
    double ud = 0.0, uq = 0.0;
    if (!c->zero_u) {
        const double ua = c->ua0 + c->ua1 * x[4];
        const double ub = c->ub0 + c->ub1 * x[4];
        const double ial = x[0] * cs - x[1] * sn;
        const double ibe = x[0] * sn + x[1] * cs;
        ud = ua * cs + ub * sn;
        uq = ub * cs - ua * sn;
        dx[4] = c->ka * ial + c->kb * ibe;
    } else {
        dx[4] = 0.0;
    }
    if (c->drop_v > 0.0) {
        double dua, dub;
        sim_inverter_drop_ab(c->drop_v, c->n_dev, x[0], x[1], cs, sn, &dua, &dub);
        ud += dua * cs + dub * sn;
        uq += dub * cs - dua * sn;
    }
    pmsm_dq_derivs(&c->m, x[0], x[1], x[2], ud, uq, &dx[0], &dx[1], &dx[2], &dx[3]);
}

/* The right-hand side of leg levels lv (each -1, 0, +1). */
static void setup(rhs_t *c, const ttype_sim_params_t *p, const int lv[3], double load_nm)
{
    const sim_params_t *m = &p->common;
    int x;
    state_coeffs(p, lv, &c->ua0, &c->ua1, &c->ub0, &c->ub1, &c->ka, &c->kb);
    c->ka = c->ka / (2.0 * p->c_f);
    c->kb = c->kb / (2.0 * p->c_f);
    c->zero_u = (lv[0] == lv[1] && lv[1] == lv[2]);
    c->drop_v = m->device_drop_v;
    for (x = 0; x < 3; ++x) {
        c->n_dev[x] = (lv[x] == 0) ? 2.0 : 1.0; /* O: a switch and a diode of the middle pair */
    }
    pmsm_dq_rhs_setup(&c->m, m->rs_ohm, m->ld_h, m->lq_h, m->psi_f_wb, m->pole_pairs, m->j_kgm2,
                      m->b_nms, load_nm, m->speed_imposed);
}

/* One constant interval: RK4 (pmsm_rk4.h) on the unwrapped angle (the
 * caller wraps); NNN/OOO/PPP without device drops need no Park rotation. */
static void integrate(const rhs_t *c, ttype_plant_state_t *s, double dt_s, int substeps)
{
    double x[PMSM_RK4_MAX];
    sim_period_motor_load(&s->motor, x);
    x[4] = s->vo_v;
    pmsm_rk4_integrate(rhs, c, !c->zero_u || c->drop_v > 0.0, x, 5, dt_s, substeps);
    sim_period_motor_store(&s->motor, x);
    s->vo_v = x[4];
}

/* Integrate leg levels lv over len_s in sub-steps of at most substep_max_s. */
static void integrate_levels(ttype_plant_state_t *s, const ttype_sim_params_t *p, const int lv[3],
                             double load_nm, double len_s)
{
    rhs_t c;
    setup(&c, p, lv, load_nm);
    integrate(&c, s, len_s, sim_inverter_substeps(len_s, p->substep_max_s));
}

/* The piece [t0, t0 + len) with levels lv, split at the snapshot offset t_snap when it falls
 * inside (*snap, *taken). */
static void integrate_piece(ttype_plant_state_t *s, const ttype_sim_params_t *p, const int lv[3],
                            double load_nm, double t0, double len, double t_snap,
                            ttype_plant_state_t *snap, int *taken)
{
    const double a = *taken ? -1.0 : sim_period_snap_split(t0, len, t_snap);
    if (a < 0.0) {
        integrate_levels(s, p, lv, load_nm, len);
        return;
    }
    if (a > 0.0) {
        integrate_levels(s, p, lv, load_nm, a);
    }
    *snap = *s;
    snap->motor.theta_e_rad = pmsm_dq_wrap_angle(snap->motor.theta_e_rad);
    *taken = 1;
    if (len - a > 0.0) {
        integrate_levels(s, p, lv, load_nm, len - a);
    }
}

int ttype_plant_advance(ttype_plant_state_t *s, const ttype_sim_params_t *p, int state,
                        double load_nm, double dt_s, int substeps)
{
    rhs_t c;
    int lv[3];
    if (state < 0 || state >= TTYPE_PLANT_N_STATES || substeps < 1 || !(dt_s > 0.0) || !isfinite(dt_s)) {
        return -1;
    }
    (void)ttype_plant_levels(state, lv);
    setup(&c, p, lv, load_nm);
    integrate(&c, s, dt_s, substeps);
    s->motor.theta_e_rad = pmsm_dq_wrap_angle(s->motor.theta_e_rad);
    return 0;
}

int ttype_plant_advance_period(ttype_plant_state_t *s, const ttype_sim_params_t *p, int from_state,
                               const uint16_t states[7], const double seg_s[7], double load_nm,
                               double uab_v[7], double t_snap_s, ttype_plant_state_t *snap)
{
    const double td = p->common.dead_time_s;
    double t0 = 0.0;
    int i, taken = 0, prev[3];
    if (!(p->substep_max_s > 0.0) || !isfinite(p->substep_max_s)
        || (from_state >= TTYPE_PLANT_N_STATES) || (t_snap_s >= 0.0 && snap == NULL)) {
        return -1;
    }
    for (i = 0; i < TTYPE_PLANT_N_SEG; ++i) {
        if (states[i] >= TTYPE_PLANT_N_STATES || !(seg_s[i] >= 0.0) || !isfinite(seg_s[i])) {
            return -1;
        }
    }
    if (ttype_plant_levels(from_state, prev) != 0) { /* no state before: no edge at the start */
        (void)ttype_plant_levels((int)states[0], prev);
    }
    for (i = 0; i < TTYPE_PLANT_N_SEG; ++i) {
        const int st = (int)states[i];
        int lv[3];
        if (uab_v != NULL) {
            uab_v[i] = ttype_plant_uab(p, st, s->vo_v);
        }
        if (!(seg_s[i] > 0.0)) {
            continue;
        }
        (void)ttype_plant_levels(st, lv);
        if (td > 0.0 && sim_inverter_edges(prev, lv)) {
            /* the dead time of this segment's edges (at most the segment) */
            const double dead_s = td < seg_s[i] ? td : seg_s[i];
            int dead[3];
            double i_abc[3];
            sim_inverter_phase_currents(s->motor.i_d_a, s->motor.i_q_a, s->motor.theta_e_rad, i_abc);
            sim_inverter_dead_levels(prev, lv, i_abc, dead);
            integrate_piece(s, p, dead, load_nm, t0, dead_s, t_snap_s, snap, &taken);
            if (seg_s[i] - dead_s > 0.0) {
                integrate_piece(s, p, lv, load_nm, t0 + dead_s, seg_s[i] - dead_s, t_snap_s, snap,
                                &taken);
            }
        } else {
            integrate_piece(s, p, lv, load_nm, t0, seg_s[i], t_snap_s, snap, &taken);
        }
        t0 += seg_s[i];
        prev[0] = lv[0];
        prev[1] = lv[1];
        prev[2] = lv[2];
    }
    s->motor.theta_e_rad = pmsm_dq_wrap_angle(s->motor.theta_e_rad);
    if (t_snap_s >= 0.0 && !taken) {
        *snap = *s; /* the offset rounded onto the period's end */
    }
    return 0;
}

int ttype_plant_advance_segments(ttype_plant_state_t *s, const ttype_sim_params_t *p,
                                 const uint16_t states[7], const double seg_s[7],
                                 double load_nm, double uab_v[7])
{
    return ttype_plant_advance_period(s, p, -1, states, seg_s, load_nm, uab_v, -1.0, NULL);
}
