/*
 * twolevel_plant.c -- two-level inverter + PMSM plant, float64 (see
 * twolevel_plant.h): the right-hand side of twolevel_rhs.h (written once,
 * also the on-board plant's) with dead time and snapshots.
 *
 * Specification: docs/simulation.md "Plant" (motor, inverter,
 * integration) and docs/algorithms.md (two-level MPTC) "Conventions" (space vector,
 * Clarke/Park, torque).  C99; compiles warning-free with
 *   gcc -std=c99 -O2 -Wall -Wextra -Wconversion -Wdouble-promotion -Werror
 *       -ffp-contract=off
 * (-ffp-contract=off: no fused multiply-add, so every host gives the same
 * bits and chunked runs equal one long run exactly).
 */
#include "twolevel_plant.h"

#include <math.h>

#include "pmsm_dq.h"
#include "sim_exact.h"
#include "sim_inverter.h"
#include "twolevel_rhs.h"

void twolevel_plant_levels(int sw, int lv[3])
{
    twolevel_rhs_levels(sw, lv);
}

/* ---------------------------------------------------------------------------
 * Inverter: amplitude-invariant space vector of the switching state
 * (twolevel_rhs.h, mptc-two-level.md "Conventions").
 * ------------------------------------------------------------------------- */
void twolevel_plant_voltage_ab(const sim_params_t *p, int sw, double *u_alpha_v, double *u_beta_v)
{
    int lv[3];
    if (sw < 0 || sw > 7) {
        *u_alpha_v = 0.0;
        *u_beta_v = 0.0;
        return;
    }
    twolevel_rhs_levels(sw, lv);
    twolevel_rhs_voltage_ab(p->udc_v, lv, u_alpha_v, u_beta_v);
}

/* The exact integrator (sim_exact.h) over one interval of the right-hand side c, the angle wrapped at
 * the end (cos/sin kept in ang, may be NULL): the device drops, if on, held at the phase currents'
 * signs at the start; 0, or -1 (x untouched) if a sign changed by the end (the caller integrates the
 * interval with RK4 instead). */
static int exact_levels(const twolevel_rhs_t *c, double *x, double dt_s, sim_exact_angle_t *ang)
{
    /* devices in each leg's conducting path (one switch or diode), as twolevel_rhs */
    static const double n_dev[3] = {1.0, 1.0, 1.0};
    sim_exact_t e;
    double cs, sn;

    e.m = c->m;
    e.ua0 = c->u_alpha;
    e.ub0 = c->u_beta;
    e.ua1 = e.ub1 = e.ka = e.kb = 0.0;
    e.np = 0;
    if (sim_exact_held_drops(&e, x, 4, c->drop_v, n_dev, ang, dt_s, &cs, &sn) != 0) {
        return -1;
    }
    x[3] = pmsm_dq_wrap(x[3]);
    sim_exact_keep(ang, x[3], cs, sn);
    return 0;
}

/* One interval of constant leg levels: the right-hand side of twolevel_rhs.h, RK4 (pmsm_rk4.h) in
 * `substeps` sub-steps, or the exact integrator (p->integrator, sim_exact.h; ang: its kept cos/sin, may
 * be NULL). */
static void advance_levels(pmsm_state_t *s, const sim_params_t *p, const int lv[3],
                           double load_nm, double dt_s, int substeps, sim_exact_angle_t *ang)
{
    twolevel_rhs_t c;
    double x[PMSM_RK4_MAX];

    twolevel_rhs_setup(&c, lv, p->udc_v, p->device_drop_v);
    pmsm_dq_rhs_setup(&c.m, p->rs_ohm, p->ld_h, p->lq_h, p->psi_f_wb, p->pole_pairs, p->j_kgm2,
                      p->b_nms, load_nm, p->speed_imposed);

    sim_period_motor_load(s, x);
    if (p->integrator != SIM_INTEGRATOR_EXACT || exact_levels(&c, x, dt_s, ang) != 0) {
        twolevel_rhs_interval(&c, x, dt_s, substeps);
    }
    sim_period_motor_store(s, x);
}

/* One interval of the open inverter (gates off, sim_inverter.h): every switch off, the currents in the
 * diodes, each diode dropping p->device_drop_v; RK4 (pmsm_rk4.h) with the zero crossings located. */
static void advance_open(pmsm_state_t *s, const sim_params_t *p, double load_nm, double dt_s,
                         int substeps)
{
    sim_open_t c;
    double x[PMSM_RK4_MAX];

    sim_open_setup(&c, p->udc_v, p->device_drop_v, 4);
    pmsm_dq_rhs_setup(&c.m, p->rs_ohm, p->ld_h, p->lq_h, p->psi_f_wb, p->pole_pairs, p->j_kgm2,
                      p->b_nms, load_nm, p->speed_imposed);

    sim_period_motor_load(s, x);
    sim_open_interval(&c, x, dt_s, substeps);
    x[3] = pmsm_dq_wrap(x[3]);
    sim_period_motor_store(s, x);
}

/* One interval with leg levels lv, or (lv NULL) with the inverter open (ang: the exact integrator's
 * kept cos/sin, may be NULL). */
static void advance_interval(pmsm_state_t *s, const sim_params_t *p, const int *lv, double load_nm,
                             double dt_s, int substeps, sim_exact_angle_t *ang)
{
    if (lv == NULL) {
        advance_open(s, p, load_nm, dt_s, substeps);
    } else {
        advance_levels(s, p, lv, load_nm, dt_s, substeps, ang);
    }
}

int twolevel_plant_advance_open(pmsm_state_t *s, const sim_params_t *p, double load_nm, double dt_s,
                                int substeps)
{
    if (substeps < 1 || !(dt_s > 0.0) || !isfinite(dt_s)) {
        return -1;
    }
    advance_open(s, p, load_nm, dt_s, substeps);
    return 0;
}

int twolevel_plant_advance(pmsm_state_t *s, const sim_params_t *p, int sw, double load_nm,
                           double dt_s, int substeps)
{
    int lv[3];
    if (sw < 0 || sw > 7 || substeps < 1 || !(dt_s > 0.0) || !isfinite(dt_s)) {
        return -1;
    }
    twolevel_rhs_levels(sw, lv);
    advance_levels(s, p, lv, load_nm, dt_s, substeps, NULL);
    return 0;
}

/* The piece [t0, t0 + len) of a period with levels lv (NULL: the inverter open), sub-steps of at most
 * h_max (n_full for len == dt_s), split at the snapshot offset t_snap when it falls inside (*snap,
 * *taken); ang: the exact integrator's cos/sin kept between the period's pieces. */
static void advance_piece(pmsm_state_t *s, const sim_params_t *p, const int *lv, double load_nm,
                          double t0, double len, int n_full, double t_snap, pmsm_state_t *snap,
                          int *taken, sim_exact_angle_t *ang)
{
    const double h_max = p->dt_s / (double)n_full;
    const double a = *taken ? -1.0 : sim_period_snap_split(t0, len, t_snap);
    if (a < 0.0) {
        advance_interval(s, p, lv, load_nm, len, len == p->dt_s ? n_full : sim_inverter_substeps(len, h_max),
                         ang);
        return;
    }
    if (a > 0.0) {
        advance_interval(s, p, lv, load_nm, a, sim_inverter_substeps(a, h_max), ang);
    }
    *snap = *s;
    *taken = 1;
    if (len - a > 0.0) {
        advance_interval(s, p, lv, load_nm, len - a, sim_inverter_substeps(len - a, h_max), ang);
    }
}

int twolevel_plant_advance_period(pmsm_state_t *s, const sim_params_t *p, int from_sw, int sw,
                                  double load_nm, int substeps, double t_snap_s, pmsm_state_t *snap)
{
    return twolevel_plant_advance_period_gates(s, p, from_sw, 0, sw, 0, load_nm, substeps, t_snap_s,
                                               snap);
}

int twolevel_plant_advance_period_gates(pmsm_state_t *s, const sim_params_t *p, int from_sw,
                                        int from_open, int sw, int open, double load_nm, int substeps,
                                        double t_snap_s, pmsm_state_t *snap)
{
    int from[3], to[3], taken = 0;
    const double td = p->dead_time_s;
    sim_exact_angle_t ang;

    if (sw < 0 || sw > 7 || from_sw < 0 || from_sw > 7 || substeps < 1
        || (t_snap_s >= 0.0 && snap == NULL)) {
        return -1;
    }
    twolevel_rhs_levels(from_sw, from);
    twolevel_rhs_levels(sw, to);
    ang.valid = 0;
    if (open) {
        /* gates off: every switch opens at t_k (no dead time: nothing turns on) */
        advance_piece(s, p, NULL, load_nm, 0.0, p->dt_s, substeps, t_snap_s, snap, &taken, &ang);
    } else if (from_open && td > 0.0) {
        /* gates on again after an open period: every leg's switch turning on closes one dead time late,
         * the legs meanwhile in their diodes (the open inverter) */
        advance_piece(s, p, NULL, load_nm, 0.0, td, substeps, t_snap_s, snap, &taken, &ang);
        advance_piece(s, p, to, load_nm, td, p->dt_s - td, substeps, t_snap_s, snap, &taken, &ang);
    } else if (td > 0.0 && sim_inverter_edges(from, to)) {
        int dead[3];
        double i_abc[3];
        sim_inverter_phase_currents(s->i_d_a, s->i_q_a, s->theta_e_rad, i_abc);
        sim_inverter_dead_levels(from, to, i_abc, dead);
        advance_piece(s, p, dead, load_nm, 0.0, td, substeps, t_snap_s, snap, &taken, &ang);
        advance_piece(s, p, to, load_nm, td, p->dt_s - td, substeps, t_snap_s, snap, &taken, &ang);
    } else {
        advance_piece(s, p, to, load_nm, 0.0, p->dt_s, substeps, t_snap_s, snap, &taken, &ang);
    }
    if (t_snap_s >= 0.0 && !taken) {
        *snap = *s; /* the offset rounded onto the period's end */
    }
    return 0;
}
