/*
 * twolevel_plant.c -- two-level inverter + PMSM plant, float64 (see
 * twolevel_plant.h).
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
#include "pmsm_rk4.h"
#include "sim_inverter.h"

/* Devices in each leg's conducting path (one switch or diode), for the device drops. */
static const double k_n_dev[3] = {1.0, 1.0, 1.0};

/* Constants of the right-hand side, computed once per constant-voltage interval. */
typedef struct {
    double u_alpha, u_beta;   /* inverter voltage, stationary frame, V */
    pmsm_dq_rhs_t m;          /* motor equations (pmsm_dq.h) */
    int zero_u;               /* 1: zero vector (all legs at one level), u_alpha = u_beta = 0 */
    double drop_v;            /* device drop, V (0: off) */
} rhs_t;

void twolevel_plant_levels(int sw, int lv[3])
{
    lv[0] = (sw >> 2) & 1;
    lv[1] = (sw >> 1) & 1;
    lv[2] = sw & 1;
}

/* The space vector of leg levels lv (0/1) (see twolevel_plant_voltage_ab). */
static void levels_voltage_ab(const sim_params_t *p, const int lv[3], double *u_alpha_v,
                              double *u_beta_v)
{
    const double sa = (double)lv[0], sb = (double)lv[1], sc = (double)lv[2];
    *u_alpha_v = (2.0 / 3.0) * p->udc_v * (sa - 0.5 * (sb + sc));
    *u_beta_v = p->udc_v * PMSM_DQ_SQRT3_INV * (sb - sc);
}

/* ---------------------------------------------------------------------------
 * Inverter: amplitude-invariant space vector of the switching state
 * (mptc-two-level.md "Conventions"):
 *   u_alpha + j*u_beta = (2/3)*Udc*(Sa + a*Sb + a^2*Sc), a = exp(j*2*pi/3)
 *   => u_alpha = (2/3)*Udc*(Sa - (Sb + Sc)/2),  u_beta = (Udc/sqrt(3))*(Sb - Sc)
 * ------------------------------------------------------------------------- */
void twolevel_plant_voltage_ab(const sim_params_t *p, int sw, double *u_alpha_v, double *u_beta_v)
{
    int lv[3];
    if (sw < 0 || sw > 7) {
        *u_alpha_v = 0.0;
        *u_beta_v = 0.0;
        return;
    }
    twolevel_plant_levels(sw, lv);
    levels_voltage_ab(p, lv, u_alpha_v, u_beta_v);
}

/* ---------------------------------------------------------------------------
 * Right-hand side f(x) of the plant ODE, x = (i_d, i_q, omega_m, theta_e),
 * given cos/sin of the stage angle (docs/simulation.md "Plant"):
 *   u_d =  u_alpha*cos + u_beta*sin,  u_q = u_beta*cos - u_alpha*sin  (Park)
 *   (+ the device drops at the stage currents, sim_inverter.h, when on)
 *   di_d/dt, di_q/dt, dw_m/dt, dtheta_e/dt: pmsm_dq_derivs (pmsm_dq.h)
 * ------------------------------------------------------------------------- */
static inline void rhs(const void *ctx, const double *x, double cs, double sn, double *dx)
{
    const rhs_t *c = (const rhs_t *)ctx;
    double ud = 0.0, uq = 0.0;
    if (!c->zero_u) {
        ud = c->u_alpha * cs + c->u_beta * sn;
        uq = c->u_beta * cs - c->u_alpha * sn;
    }
    if (c->drop_v > 0.0) {
        double dua, dub;
        sim_inverter_drop_ab(c->drop_v, k_n_dev, x[0], x[1], cs, sn, &dua, &dub);
        ud += dua * cs + dub * sn;
        uq += dub * cs - dua * sn;
    }
    pmsm_dq_derivs(&c->m, x[0], x[1], x[2], ud, uq, &dx[0], &dx[1], &dx[2], &dx[3]);
}

/* One interval of constant leg levels: RK4 (pmsm_rk4.h); a zero vector
 * without device drops needs no Park rotation. */
static void advance_levels(pmsm_state_t *s, const sim_params_t *p, const int lv[3],
                           double load_nm, double dt_s, int substeps)
{
    rhs_t c;
    double x[PMSM_RK4_MAX];

    levels_voltage_ab(p, lv, &c.u_alpha, &c.u_beta);
    c.zero_u = (lv[0] == lv[1] && lv[1] == lv[2]);
    c.drop_v = p->device_drop_v;
    pmsm_dq_rhs_setup(&c.m, p->rs_ohm, p->ld_h, p->lq_h, p->psi_f_wb, p->pole_pairs, p->j_kgm2,
                      p->b_nms, load_nm, p->speed_imposed);

    sim_period_motor_load(s, x);
    pmsm_rk4_integrate(rhs, &c, !c.zero_u || c.drop_v > 0.0, x, 4, dt_s, substeps);
    sim_period_motor_store(s, x);
    s->theta_e_rad = pmsm_dq_wrap_angle(s->theta_e_rad);
}

int twolevel_plant_advance(pmsm_state_t *s, const sim_params_t *p, int sw, double load_nm,
                           double dt_s, int substeps)
{
    int lv[3];
    if (sw < 0 || sw > 7 || substeps < 1 || !(dt_s > 0.0) || !isfinite(dt_s)) {
        return -1;
    }
    twolevel_plant_levels(sw, lv);
    advance_levels(s, p, lv, load_nm, dt_s, substeps);
    return 0;
}

/* The piece [t0, t0 + len) of a period with levels lv, sub-steps of at most h_max (n_full for
 * len == dt_s), split at the snapshot offset t_snap when it falls inside (*snap, *taken). */
static void advance_piece(pmsm_state_t *s, const sim_params_t *p, const int lv[3], double load_nm,
                          double t0, double len, int n_full, double t_snap, pmsm_state_t *snap,
                          int *taken)
{
    const double h_max = p->dt_s / (double)n_full;
    const double a = *taken ? -1.0 : sim_period_snap_split(t0, len, t_snap);
    if (a < 0.0) {
        advance_levels(s, p, lv, load_nm, len, len == p->dt_s ? n_full : sim_inverter_substeps(len, h_max));
        return;
    }
    if (a > 0.0) {
        advance_levels(s, p, lv, load_nm, a, sim_inverter_substeps(a, h_max));
    }
    *snap = *s;
    *taken = 1;
    if (len - a > 0.0) {
        advance_levels(s, p, lv, load_nm, len - a, sim_inverter_substeps(len - a, h_max));
    }
}

int twolevel_plant_advance_period(pmsm_state_t *s, const sim_params_t *p, int from_sw, int sw,
                                  double load_nm, int substeps, double t_snap_s, pmsm_state_t *snap)
{
    int from[3], to[3], taken = 0;
    const double td = p->dead_time_s;

    if (sw < 0 || sw > 7 || from_sw < 0 || from_sw > 7 || substeps < 1
        || (t_snap_s >= 0.0 && snap == NULL)) {
        return -1;
    }
    twolevel_plant_levels(from_sw, from);
    twolevel_plant_levels(sw, to);
    if (td > 0.0 && sim_inverter_edges(from, to)) {
        int dead[3];
        double i_abc[3];
        sim_inverter_phase_currents(s->i_d_a, s->i_q_a, s->theta_e_rad, i_abc);
        sim_inverter_dead_levels(from, to, i_abc, dead);
        advance_piece(s, p, dead, load_nm, 0.0, td, substeps, t_snap_s, snap, &taken);
        advance_piece(s, p, to, load_nm, td, p->dt_s - td, substeps, t_snap_s, snap, &taken);
    } else {
        advance_piece(s, p, to, load_nm, 0.0, p->dt_s, substeps, t_snap_s, snap, &taken);
    }
    if (t_snap_s >= 0.0 && !taken) {
        *snap = *s; /* the offset rounded onto the period's end */
    }
    return 0;
}
