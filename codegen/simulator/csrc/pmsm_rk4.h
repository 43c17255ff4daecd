/*
 * pmsm_rk4.h -- classic 4th-order Runge-Kutta over one constant-voltage
 * interval, shared by every topology's plant (hand-written runtime, written
 * once on sim_real_t: float64 on the host, float32 on board, sim_real.h).
 *
 * Specification: docs/simulation.md "Integration" (RK4 with
 * sub-steps of at most 1 us).  The state is a vector x[0..nx-1] whose first
 * four entries are the motor's (i_d, i_q, omega_m, theta_e, see pmsm_state_t)
 * and whose further entries are the topology's (e.g. the neutral-point
 * voltage V_o); the topology supplies the right-hand side f(x) given cos/sin
 * of the stage angle.  In `substeps` equal sub-steps h = dt/substeps:
 *   k1 = f(x), k2 = f(x + h/2*k1), k3 = f(x + h/2*k2), k4 = f(x + h*k3)
 *   x <- x + h/6*(k1 + 2*k2 + 2*k3 + k4)
 * The angle used by Park at each stage is the stage's own theta_e:
 * theta + h/2*w_e1, theta + h/2*w_e2, theta + h*w_e3, with cos/sin from one
 * libm pair per sub-step and pmsm_dq_rotate().  With the speed held, stages
 * 2 and 3 share one angle and one rotation; with `rotate` == 0 (a zero
 * vector: no Park rotation needed) cos = 1, sin = 0 throughout.  theta_e is
 * integrated unwrapped (the caller wraps).
 *
 * static inline: each plant's call inlines it with its own right-hand side,
 * so the operations are those of a hand-written loop, in the same
 * order (bit-identical results under -ffp-contract=off).
 *
 * C99, no dynamic memory, no global state.  Not part of any cffi cdef.
 */
#ifndef PMSM_RK4_H
#define PMSM_RK4_H

#include "pmsm_dq.h"
#include "sim_real.h"

/* Largest state vector of any plant. */
#define PMSM_RK4_MAX 5
/* Index of theta_e in the state vector (its derivative is omega_e). */
#define PMSM_RK4_THETA 3

/* Right-hand side: dx = f(x) at the stage angle (cs = cos, sn = sin). */
typedef void (*pmsm_rk4_rhs_fn)(const void *ctx, const sim_real_t *x, sim_real_t cs, sim_real_t sn,
                                sim_real_t *dx);

static inline void pmsm_rk4_integrate(pmsm_rk4_rhs_fn f, const void *ctx, int rotate, sim_real_t *x,
                                      int nx, sim_real_t dt_s, int substeps)
{
    const sim_real_t h = dt_s / (sim_real_t)substeps;
    const sim_real_t h2 = SIM_R(0.5) * h;
    const sim_real_t h6 = h / SIM_R(6.0);
    int n, i;

    for (n = 0; n < substeps; ++n) {
        sim_real_t k1[PMSM_RK4_MAX], k2[PMSM_RK4_MAX], k3[PMSM_RK4_MAX], k4[PMSM_RK4_MAX];
        sim_real_t xs[PMSM_RK4_MAX];
        sim_real_t c0 = SIM_R(1.0), s0 = SIM_R(0.0), cs = SIM_R(1.0), sn = SIM_R(0.0);

        if (rotate) {
            c0 = SIM_COS(x[PMSM_RK4_THETA]);
            s0 = SIM_SIN(x[PMSM_RK4_THETA]);
        }
        f(ctx, x, c0, s0, k1);

        if (rotate) {
            pmsm_dq_rotate(c0, s0, h2 * k1[PMSM_RK4_THETA], &cs, &sn);
        }
        for (i = 0; i < nx; ++i) {
            xs[i] = x[i] + h2 * k1[i];
        }
        f(ctx, xs, cs, sn, k2);

        if (rotate && k2[PMSM_RK4_THETA] != k1[PMSM_RK4_THETA]) {
            pmsm_dq_rotate(c0, s0, h2 * k2[PMSM_RK4_THETA], &cs, &sn);
        }
        for (i = 0; i < nx; ++i) {
            xs[i] = x[i] + h2 * k2[i];
        }
        f(ctx, xs, cs, sn, k3);

        if (rotate) {
            pmsm_dq_rotate(c0, s0, h * k3[PMSM_RK4_THETA], &cs, &sn);
        }
        for (i = 0; i < nx; ++i) {
            xs[i] = x[i] + h * k3[i];
        }
        f(ctx, xs, cs, sn, k4);

        for (i = 0; i < nx; ++i) {
            x[i] += h6 * (k1[i] + SIM_R(2.0) * k2[i] + SIM_R(2.0) * k3[i] + k4[i]);
        }
    }
}

#endif /* PMSM_RK4_H */
