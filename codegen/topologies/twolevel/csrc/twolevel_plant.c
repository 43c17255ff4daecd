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

/* Constants of the right-hand side, computed once per twolevel_plant_advance call. */
typedef struct {
    double u_alpha, u_beta;   /* inverter voltage, stationary frame, V */
    pmsm_dq_rhs_t m;          /* motor equations (pmsm_dq.h) */
    int zero_u;               /* 1: zero vector, u_dq = 0 */
} rhs_t;

/* ---------------------------------------------------------------------------
 * Inverter: amplitude-invariant space vector of the switching state
 * (mptc-two-level.md "Conventions"):
 *   u_alpha + j*u_beta = (2/3)*Udc*(Sa + a*Sb + a^2*Sc), a = exp(j*2*pi/3)
 *   => u_alpha = (2/3)*Udc*(Sa - (Sb + Sc)/2),  u_beta = (Udc/sqrt(3))*(Sb - Sc)
 * ------------------------------------------------------------------------- */
void twolevel_plant_voltage_ab(const sim_params_t *p, int sw, double *u_alpha_v, double *u_beta_v)
{
    double sa, sb, sc;
    if (sw < 0 || sw > 7) {
        *u_alpha_v = 0.0;
        *u_beta_v = 0.0;
        return;
    }
    sa = (double)((sw >> 2) & 1);
    sb = (double)((sw >> 1) & 1);
    sc = (double)(sw & 1);
    *u_alpha_v = (2.0 / 3.0) * p->udc_v * (sa - 0.5 * (sb + sc));
    *u_beta_v = p->udc_v * PMSM_DQ_SQRT3_INV * (sb - sc);
}

/* ---------------------------------------------------------------------------
 * Right-hand side f(x) of the plant ODE, x = (i_d, i_q, omega_m, theta_e),
 * given cos/sin of the stage angle (plant-and-metrics.md "Plant", motor):
 *   u_d =  u_alpha*cos + u_beta*sin,  u_q = u_beta*cos - u_alpha*sin  (Park)
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
    pmsm_dq_derivs(&c->m, x[0], x[1], x[2], ud, uq, &dx[0], &dx[1], &dx[2], &dx[3]);
}

/* One interval of constant inverter voltage: RK4 (pmsm_rk4.h); the zero
 * vector needs no Park rotation. */
int twolevel_plant_advance(pmsm_state_t *s, const sim_params_t *p, int sw, double load_nm,
                           double dt_s, int substeps)
{
    rhs_t c;
    double x[PMSM_RK4_MAX];

    if (sw < 0 || sw > 7 || substeps < 1 || !(dt_s > 0.0) || !isfinite(dt_s)) {
        return -1;
    }
    twolevel_plant_voltage_ab(p, sw, &c.u_alpha, &c.u_beta);
    c.zero_u = (sw == 0 || sw == 7);
    pmsm_dq_rhs_setup(&c.m, p->rs_ohm, p->ld_h, p->lq_h, p->psi_f_wb, p->pole_pairs, p->j_kgm2,
                      p->b_nms, load_nm, p->speed_imposed);

    sim_period_motor_load(s, x);
    pmsm_rk4_integrate(rhs, &c, !c.zero_u, x, 4, dt_s, substeps);
    sim_period_motor_store(s, x);
    s->theta_e_rad = pmsm_dq_wrap_angle(s->theta_e_rad);
    return 0;
}
