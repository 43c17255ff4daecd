/*
 * ttype_rhs.h -- the right-hand side of the T-type three-level inverter +
 * PMSM plant over one interval of constant leg levels, written once on
 * sim_real_t (sim_real.h): float64 in the host plant (ttype_plant.c),
 * float32 in the firmware's on-board loop (ttype_onboard.c) (hand-written
 * runtime).
 *
 * Specification: docs/simulation.md "Plant" and docs/algorithms.md (T-type
 * MPDTC) "Inverter, vectors, neutral point"; the model and the neutral-point
 * sign convention: ttype_plant.h.  Leg levels S_x in {-1, 0, +1} = {N, O, P}
 * of switching state s = 9*(Sa+1) + 3*(Sb+1) + (Sc+1):
 *   u_xo = S_x*Udc/2 + |S_x|*V_o
 *   u_alpha = (2/3)*(u_ao - (u_bo + u_co)/2) = ua0 + ua1*V_o,
 *   u_beta = (u_bo - u_co)/sqrt(3)           = ub0 + ub1*V_o
 *   i_o = -sum |S_x| i_x = -(|Sa| - (|Sb|+|Sc|)/2)*i_alpha - (sqrt(3)/2)(|Sb|-|Sc|)*i_beta
 *   (i_a = i_alpha, i_b = -i_alpha/2 + (sqrt3/2) i_beta, i_c = -i_alpha/2 - (sqrt3/2) i_beta)
 *   dV_o/dt = i_o/(2C) = ka*i_alpha + kb*i_beta
 * Right-hand side at one RK4 stage, x = (i_d, i_q, w_m, theta_e, V_o), given
 * cos/sin of the stage angle: Park of (u_alpha, u_beta), the device drops
 * (sim_inverter.h) when on, the motor (pmsm_dq_derivs, pmsm_dq.h),
 * i_alpha = i_d*cos - i_q*sin, i_beta = i_d*sin + i_q*cos.  Integration:
 * pmsm_rk4.h on the unwrapped angle (the caller wraps); NNN/OOO/PPP without
 * device drops need no Park rotation.
 *
 * C99, no dynamic memory, no global state.  Not part of any cffi cdef.
 */
#ifndef TTYPE_RHS_H
#define TTYPE_RHS_H

#include "pmsm_dq.h"
#include "pmsm_rk4.h"
#include "sim_inverter.h"
#include "sim_real.h"

/* Number of switching states. */
#define TTYPE_RHS_N_STATES 27

/* Constants of the right-hand side for one interval of constant leg levels. */
typedef struct {
    /* u_alpha = ua0 + ua1*V_o, u_beta = ub0 + ub1*V_o (u_xo = S*Udc/2 + |S|*V_o) */
    sim_real_t ua0, ua1, ub0, ub1;
    /* i_o = ka*i_alpha + kb*i_beta, already divided by 2C: dV_o/dt = ka*i_al + kb*i_be */
    sim_real_t ka, kb;
    pmsm_dq_rhs_t m;      /* motor equations (pmsm_dq.h) */
    int zero_u;           /* 1: NNN/OOO/PPP: u = 0 and i_o = 0 */
    sim_real_t drop_v;    /* device drop, V (0: off) */
    sim_real_t n_dev[3];  /* devices in each leg's path: 1 at P/N, 2 at O */
} ttype_rhs_t;

/* Leg levels (Sa, Sb, Sc) in {-1, 0, +1} of state 0..26; returns -1 otherwise. */
static inline int ttype_rhs_levels(int state, int levels[3])
{
    if (state < 0 || state >= TTYPE_RHS_N_STATES) {
        return -1;
    }
    levels[0] = state / 9 - 1;
    levels[1] = (state / 3) % 3 - 1;
    levels[2] = state % 3 - 1;
    return 0;
}

/* Coefficients of u_alpha, u_beta (V and V per V of V_o) and of i_o (per unit i_alpha, i_beta)
 * of leg levels lv at DC-link voltage udc_v (see the header comment). */
static inline void ttype_rhs_coeffs(sim_real_t udc_v, const int lv[3], sim_real_t *ua0,
                                    sim_real_t *ua1, sim_real_t *ub0, sim_real_t *ub1,
                                    sim_real_t *ka, sim_real_t *kb)
{
    const sim_real_t sa = (sim_real_t)lv[0], sb = (sim_real_t)lv[1], sc = (sim_real_t)lv[2];
    const sim_real_t aa = SIM_FABS(sa), ab = SIM_FABS(sb), ac = SIM_FABS(sc);
    const sim_real_t half = SIM_R(0.5) * udc_v;
    *ua0 = (SIM_R(2.0) / SIM_R(3.0)) * half * (sa - SIM_R(0.5) * (sb + sc));
    *ua1 = (SIM_R(2.0) / SIM_R(3.0)) * (aa - SIM_R(0.5) * (ab + ac));
    *ub0 = half * PMSM_DQ_SQRT3_INV * (sb - sc);
    *ub1 = PMSM_DQ_SQRT3_INV * (ab - ac);
    *ka = -(aa - SIM_R(0.5) * (ab + ac));
    *kb = -PMSM_DQ_SQRT3_HALF * (ab - ac);
}

/* The inverter and neutral-point part of c for leg levels lv (each capacitor c_f; the motor part:
 * pmsm_dq_rhs_setup(&c->m, ...)). */
static inline void ttype_rhs_setup(ttype_rhs_t *c, const int lv[3], sim_real_t udc_v,
                                   sim_real_t c_f, sim_real_t drop_v)
{
    int x;
    ttype_rhs_coeffs(udc_v, lv, &c->ua0, &c->ua1, &c->ub0, &c->ub1, &c->ka, &c->kb);
    c->ka = c->ka / (SIM_R(2.0) * c_f);
    c->kb = c->kb / (SIM_R(2.0) * c_f);
    c->zero_u = (lv[0] == lv[1] && lv[1] == lv[2]);
    c->drop_v = drop_v;
    for (x = 0; x < 3; ++x) {
        c->n_dev[x] = (lv[x] == 0) ? SIM_R(2.0) : SIM_R(1.0); /* O: a switch and a diode of the middle pair */
    }
}

/* f(x) at the stage angle (cs = cos, sn = sin): see the header comment. */
static inline void ttype_rhs(const void *ctx, const sim_real_t *x, sim_real_t cs, sim_real_t sn,
                             sim_real_t *dx)
{
    const ttype_rhs_t *c = (const ttype_rhs_t *)ctx;
    sim_real_t ud = SIM_R(0.0), uq = SIM_R(0.0);
    if (!c->zero_u) {
        const sim_real_t ua = c->ua0 + c->ua1 * x[4];
        const sim_real_t ub = c->ub0 + c->ub1 * x[4];
        const sim_real_t ial = x[0] * cs - x[1] * sn;
        const sim_real_t ibe = x[0] * sn + x[1] * cs;
        pmsm_dq_park(ua, ub, cs, sn, &ud, &uq);
        dx[4] = c->ka * ial + c->kb * ibe;
    } else {
        dx[4] = SIM_R(0.0);
    }
    if (c->drop_v > SIM_R(0.0)) {
        sim_inverter_add_drops(c->drop_v, c->n_dev, x[0], x[1], cs, sn, &ud, &uq);
    }
    pmsm_dq_derivs(&c->m, x[0], x[1], x[2], ud, uq, &dx[0], &dx[1], &dx[2], &dx[3]);
}

/* Integrate x = (i_d, i_q, omega_m, theta_e, V_o) over dt_s in `substeps` equal RK4 sub-steps of c
 * (the angle unwrapped: the caller wraps). */
static inline void ttype_rhs_interval(const ttype_rhs_t *c, sim_real_t *x, sim_real_t dt_s,
                                      int substeps)
{
    pmsm_rk4_integrate(ttype_rhs, c, !c->zero_u || c->drop_v > SIM_R(0.0), x, 5, dt_s, substeps);
}

#endif /* TTYPE_RHS_H */
