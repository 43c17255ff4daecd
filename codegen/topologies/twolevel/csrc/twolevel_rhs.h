/*
 * twolevel_rhs.h -- the right-hand side of the two-level inverter + PMSM
 * plant over one interval of constant leg levels, written once on
 * sim_real_t (sim_real.h): float64 in the host plant (twolevel_plant.c),
 * float32 in the firmware's on-board loop (twolevel_onboard.c)
 * (hand-written runtime).
 *
 * Specification: docs/simulation.md "Plant" (motor, inverter, integration)
 * and docs/algorithms.md (two-level MPTC) "Conventions".  Inverter:
 * amplitude-invariant space vector of the leg levels (Sa, Sb, Sc) in {0, 1},
 * switching state sw = Sa*4 + Sb*2 + Sc:
 *   u_alpha + j*u_beta = (2/3)*Udc*(Sa + a*Sb + a^2*Sc), a = exp(j*2*pi/3)
 *   => u_alpha = (2/3)*Udc*(Sa - (Sb + Sc)/2),  u_beta = (Udc/sqrt(3))*(Sb - Sc)
 * Right-hand side f(x), x = (i_d, i_q, omega_m, theta_e), given cos/sin of
 * the stage angle:
 *   u_d = u_alpha*cos + u_beta*sin,  u_q = u_beta*cos - u_alpha*sin  (Park)
 *   (+ the device drops at the stage currents, sim_inverter.h, when on)
 *   di_d/dt, di_q/dt, dw_m/dt, dtheta_e/dt: pmsm_dq_derivs (pmsm_dq.h)
 * Integration: pmsm_rk4.h in equal sub-steps, the angle integrated
 * unwrapped and wrapped to [0, 2*pi) at the end of the interval; a zero
 * vector without device drops needs no Park rotation.
 *
 * C99, no dynamic memory, no global state.  Not part of any cffi cdef.
 */
#ifndef TWOLEVEL_RHS_H
#define TWOLEVEL_RHS_H

#include "pmsm_dq.h"
#include "pmsm_rk4.h"
#include "sim_inverter.h"
#include "sim_real.h"

/* Constants of the right-hand side, computed once per constant-voltage interval. */
typedef struct {
    sim_real_t u_alpha, u_beta; /* inverter voltage, stationary frame, V */
    pmsm_dq_rhs_t m;            /* motor equations (pmsm_dq.h) */
    int zero_u;                 /* 1: zero vector (all legs at one level), u_alpha = u_beta = 0 */
    sim_real_t drop_v;          /* device drop, V (0: off) */
} twolevel_rhs_t;

/* Leg levels (Sa, Sb, Sc) in {0, 1} of switching state sw = Sa*4 + Sb*2 + Sc. */
static inline void twolevel_rhs_levels(int sw, int lv[3])
{
    lv[0] = (sw >> 2) & 1;
    lv[1] = (sw >> 1) & 1;
    lv[2] = sw & 1;
}

/* The space vector of leg levels lv (0/1) at DC-link voltage udc_v, V. */
static inline void twolevel_rhs_voltage_ab(sim_real_t udc_v, const int lv[3], sim_real_t *u_alpha_v,
                                           sim_real_t *u_beta_v)
{
    const sim_real_t sa = (sim_real_t)lv[0], sb = (sim_real_t)lv[1], sc = (sim_real_t)lv[2];
    *u_alpha_v = (SIM_R(2.0) / SIM_R(3.0)) * udc_v * (sa - SIM_R(0.5) * (sb + sc));
    *u_beta_v = udc_v * PMSM_DQ_SQRT3_INV * (sb - sc);
}

/* The inverter part of c for leg levels lv (the motor part: pmsm_dq_rhs_setup(&c->m, ...)). */
static inline void twolevel_rhs_setup(twolevel_rhs_t *c, const int lv[3], sim_real_t udc_v,
                                      sim_real_t drop_v)
{
    twolevel_rhs_voltage_ab(udc_v, lv, &c->u_alpha, &c->u_beta);
    c->zero_u = (lv[0] == lv[1] && lv[1] == lv[2]);
    c->drop_v = drop_v;
}

/* f(x) at the stage angle (cs = cos, sn = sin): see the header comment. */
static inline void twolevel_rhs(const void *ctx, const sim_real_t *x, sim_real_t cs, sim_real_t sn,
                                sim_real_t *dx)
{
    /* devices in each leg's conducting path (one switch or diode), for the device drops */
    static const sim_real_t n_dev[3] = {SIM_R(1.0), SIM_R(1.0), SIM_R(1.0)};
    const twolevel_rhs_t *c = (const twolevel_rhs_t *)ctx;
    sim_real_t ud = SIM_R(0.0), uq = SIM_R(0.0);
    if (!c->zero_u) {
        pmsm_dq_park(c->u_alpha, c->u_beta, cs, sn, &ud, &uq);
    }
    if (c->drop_v > SIM_R(0.0)) {
        sim_inverter_add_drops(c->drop_v, n_dev, x[0], x[1], cs, sn, &ud, &uq);
    }
    pmsm_dq_derivs(&c->m, x[0], x[1], x[2], ud, uq, &dx[0], &dx[1], &dx[2], &dx[3]);
}

/* Integrate x = (i_d, i_q, omega_m, theta_e) over dt_s in `substeps` equal RK4 sub-steps of c;
 * theta_e wrapped to [0, 2*pi) at the end. */
static inline void twolevel_rhs_interval(const twolevel_rhs_t *c, sim_real_t *x, sim_real_t dt_s,
                                         int substeps)
{
    pmsm_rk4_integrate(twolevel_rhs, c, !c->zero_u || c->drop_v > SIM_R(0.0), x, 4, dt_s, substeps);
    x[3] = pmsm_dq_wrap(x[3]);
}

#endif /* TWOLEVEL_RHS_H */
