/*
 * ttype_plant.c -- T-type three-level inverter + PMSM plant, float64 (see
 * ttype_plant.h for the model, the neutral-point sign convention and the
 * integration method): the right-hand side of ttype_rhs.h (written once, also
 * the on-board plant's) with seven segments, dead time and snapshots.
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
#include "sim_exact.h"
#include "sim_inverter.h"
#include "ttype_rhs.h"

int ttype_plant_levels(int state, int levels[3])
{
    return ttype_rhs_levels(state, levels);
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
    ttype_rhs_coeffs(p->common.udc_v, lv, &ua0, &ua1, &ub0, &ub1, &ka, &kb);
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

/* The right-hand side of leg levels lv (ttype_rhs.h). */
static void setup(ttype_rhs_t *c, const ttype_sim_params_t *p, const int lv[3], double load_nm)
{
    const sim_params_t *m = &p->common;
    ttype_rhs_setup(c, lv, m->udc_v, p->c_f, m->device_drop_v);
    pmsm_dq_rhs_setup(&c->m, m->rs_ohm, m->ld_h, m->lq_h, m->psi_f_wb, m->pole_pairs, m->j_kgm2,
                      m->b_nms, load_nm, m->speed_imposed);
}

/* The exact integrator (sim_exact.h) over one interval of the right-hand side c (cos/sin kept in ang,
 * may be NULL): the device drops, if on, held at the phase currents' signs at the start; 0, or -1 (x
 * untouched) if a sign changed by the end (the caller integrates the interval with RK4 instead).  The
 * angle unwrapped. */
static int exact_levels(const ttype_rhs_t *c, double *x, double dt_s, sim_exact_angle_t *ang)
{
    sim_exact_t e;
    double cs, sn;

    e.m = c->m;
    e.ua0 = c->ua0;
    e.ub0 = c->ub0;
    e.ua1 = c->ua1;
    e.ub1 = c->ub1;
    e.ka = c->ka;
    e.kb = c->kb;
    e.np = !c->zero_u;
    if (sim_exact_held_drops(&e, x, 5, c->drop_v, c->n_dev, ang, dt_s, &cs, &sn) != 0) {
        return -1;
    }
    sim_exact_keep(ang, x[3], cs, sn);
    return 0;
}

/* One constant interval: RK4 (pmsm_rk4.h) in `substeps` sub-steps, or the exact integrator
 * (p->common.integrator, sim_exact.h; ang: its kept cos/sin, may be NULL), on the unwrapped angle (the
 * caller wraps). */
static void integrate(const ttype_rhs_t *c, const ttype_sim_params_t *p, ttype_plant_state_t *s,
                      double dt_s, int substeps, sim_exact_angle_t *ang)
{
    double x[PMSM_RK4_MAX];
    sim_period_motor_load(&s->motor, x);
    x[4] = s->vo_v;
    if (p->common.integrator != SIM_INTEGRATOR_EXACT || exact_levels(c, x, dt_s, ang) != 0) {
        ttype_rhs_interval(c, x, dt_s, substeps);
    }
    sim_period_motor_store(&s->motor, x);
    s->vo_v = x[4];
}

/* The open inverter (gates off, sim_inverter.h) over dt_s in `substeps` sub-steps: every switch off,
 * the phase currents in the outer diodes (each dropping device_drop_v) across the whole DC link, V_o
 * held (the clamp pair off: no midpoint current); the angle unwrapped (the caller wraps). */
static void integrate_open(ttype_plant_state_t *s, const ttype_sim_params_t *p, double load_nm,
                           double dt_s, int substeps)
{
    const sim_params_t *m = &p->common;
    sim_open_t c;
    double x[PMSM_RK4_MAX];
    sim_open_setup(&c, m->udc_v, m->device_drop_v, 5);
    pmsm_dq_rhs_setup(&c.m, m->rs_ohm, m->ld_h, m->lq_h, m->psi_f_wb, m->pole_pairs, m->j_kgm2,
                      m->b_nms, load_nm, m->speed_imposed);
    sim_period_motor_load(&s->motor, x);
    x[4] = s->vo_v;
    sim_open_interval(&c, x, dt_s, substeps);
    sim_period_motor_store(&s->motor, x);
    s->vo_v = x[4];
}

/* Integrate leg levels lv (NULL: the inverter open) over len_s in sub-steps of at most
 * substep_max_s (ang: the exact integrator's cos/sin kept between a period's pieces). */
static void integrate_levels(ttype_plant_state_t *s, const ttype_sim_params_t *p, const int *lv,
                             double load_nm, double len_s, sim_exact_angle_t *ang)
{
    ttype_rhs_t c;
    if (lv == NULL) {
        integrate_open(s, p, load_nm, len_s, sim_inverter_substeps(len_s, p->substep_max_s));
        return;
    }
    setup(&c, p, lv, load_nm);
    integrate(&c, p, s, len_s, sim_inverter_substeps(len_s, p->substep_max_s), ang);
}

/* The piece [t0, t0 + len) with levels lv (NULL: the inverter open), split at the snapshot offset
 * t_snap when it falls inside (*snap, *taken); ang: the exact integrator's kept cos/sin. */
static void integrate_piece(ttype_plant_state_t *s, const ttype_sim_params_t *p, const int *lv,
                            double load_nm, double t0, double len, double t_snap,
                            ttype_plant_state_t *snap, int *taken, sim_exact_angle_t *ang)
{
    const double a = *taken ? -1.0 : sim_period_snap_split(t0, len, t_snap);
    if (a < 0.0) {
        integrate_levels(s, p, lv, load_nm, len, ang);
        return;
    }
    if (a > 0.0) {
        integrate_levels(s, p, lv, load_nm, a, ang);
    }
    *snap = *s;
    snap->motor.theta_e_rad = pmsm_dq_wrap_angle(snap->motor.theta_e_rad);
    *taken = 1;
    if (len - a > 0.0) {
        integrate_levels(s, p, lv, load_nm, len - a, ang);
    }
}

int ttype_plant_advance(ttype_plant_state_t *s, const ttype_sim_params_t *p, int state,
                        double load_nm, double dt_s, int substeps)
{
    ttype_rhs_t c;
    int lv[3];
    if (state < 0 || state >= TTYPE_PLANT_N_STATES || substeps < 1 || !(dt_s > 0.0) || !isfinite(dt_s)) {
        return -1;
    }
    (void)ttype_rhs_levels(state, lv);
    setup(&c, p, lv, load_nm);
    integrate(&c, p, s, dt_s, substeps, NULL);
    s->motor.theta_e_rad = pmsm_dq_wrap_angle(s->motor.theta_e_rad);
    return 0;
}

int ttype_plant_advance_open(ttype_plant_state_t *s, const ttype_sim_params_t *p, double load_nm,
                             double dt_s, int substeps)
{
    if (substeps < 1 || !(dt_s > 0.0) || !isfinite(dt_s)) {
        return -1;
    }
    integrate_open(s, p, load_nm, dt_s, substeps);
    s->motor.theta_e_rad = pmsm_dq_wrap_angle(s->motor.theta_e_rad);
    return 0;
}

int ttype_plant_advance_period(ttype_plant_state_t *s, const ttype_sim_params_t *p, int from_state,
                               const uint16_t states[7], const double seg_s[7], double load_nm,
                               double uab_v[7], double t_snap_s, ttype_plant_state_t *snap)
{
    return ttype_plant_advance_period_gates(s, p, from_state, 0, 0, states, seg_s, load_nm, uab_v,
                                            t_snap_s, snap);
}

int ttype_plant_advance_period_gates(ttype_plant_state_t *s, const ttype_sim_params_t *p,
                                     int from_state, int from_open, int open,
                                     const uint16_t states[7], const double seg_s[7],
                                     double load_nm, double uab_v[7], double t_snap_s,
                                     ttype_plant_state_t *snap)
{
    const double td = p->common.dead_time_s;
    double t0 = 0.0;
    int i, taken = 0, prev[3], first = 1;
    sim_exact_angle_t ang;
    if (!(p->substep_max_s > 0.0) || !isfinite(p->substep_max_s)
        || (from_state >= TTYPE_PLANT_N_STATES) || (t_snap_s >= 0.0 && snap == NULL)) {
        return -1;
    }
    for (i = 0; i < TTYPE_PLANT_N_SEG; ++i) {
        if (states[i] >= TTYPE_PLANT_N_STATES || !(seg_s[i] >= 0.0) || !isfinite(seg_s[i])) {
            return -1;
        }
    }
    ang.valid = 0;
    if (ttype_plant_levels(from_state, prev) != 0) { /* no state before: no edge at the start */
        (void)ttype_plant_levels((int)states[0], prev);
    }
    for (i = 0; i < TTYPE_PLANT_N_SEG; ++i) {
        const int st = (int)states[i];
        int lv[3];
        if (uab_v != NULL) {
            uab_v[i] = ttype_plant_uab(p, st, s->vo_v); /* as commanded, also with the gates off */
        }
        if (!(seg_s[i] > 0.0)) {
            continue;
        }
        (void)ttype_plant_levels(st, lv);
        if (open) {
            /* gates off: every switch off over the segment's time (no dead time: nothing turns on) */
            integrate_piece(s, p, NULL, load_nm, t0, seg_s[i], t_snap_s, snap, &taken, &ang);
        } else if (first && from_open && td > 0.0) {
            /* gates on again after an open period: the switches turning on close one dead time late,
             * the legs meanwhile in their diodes (the open inverter) */
            const double dead_s = td < seg_s[i] ? td : seg_s[i];
            integrate_piece(s, p, NULL, load_nm, t0, dead_s, t_snap_s, snap, &taken, &ang);
            if (seg_s[i] - dead_s > 0.0) {
                integrate_piece(s, p, lv, load_nm, t0 + dead_s, seg_s[i] - dead_s, t_snap_s, snap,
                                &taken, &ang);
            }
        } else if (td > 0.0 && sim_inverter_edges(prev, lv)) {
            /* the dead time of this segment's edges (at most the segment) */
            const double dead_s = td < seg_s[i] ? td : seg_s[i];
            int dead[3];
            double i_abc[3];
            sim_inverter_phase_currents(s->motor.i_d_a, s->motor.i_q_a, s->motor.theta_e_rad, i_abc);
            sim_inverter_dead_levels(prev, lv, i_abc, dead);
            integrate_piece(s, p, dead, load_nm, t0, dead_s, t_snap_s, snap, &taken, &ang);
            if (seg_s[i] - dead_s > 0.0) {
                integrate_piece(s, p, lv, load_nm, t0 + dead_s, seg_s[i] - dead_s, t_snap_s, snap,
                                &taken, &ang);
            }
        } else {
            integrate_piece(s, p, lv, load_nm, t0, seg_s[i], t_snap_s, snap, &taken, &ang);
        }
        t0 += seg_s[i];
        first = 0;
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
