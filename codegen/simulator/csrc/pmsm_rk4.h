/*
 * pmsm_rk4.h -- classic 4th-order Runge-Kutta over one constant-voltage
 * interval, shared by every topology's plant (hand-written runtime, float64).
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
 * so the double operations are those of a hand-written loop, in the same
 * order (bit-identical results under -ffp-contract=off).
 *
 * C99, no dynamic memory, no global state.  Not part of any cffi cdef.
 */
#ifndef PMSM_RK4_H
#define PMSM_RK4_H

#include <math.h>

#include "pmsm_dq.h"

/* Largest state vector of any plant. */
#define PMSM_RK4_MAX 5
/* Index of theta_e in the state vector (its derivative is omega_e). */
#define PMSM_RK4_THETA 3

/* Right-hand side: dx = f(x) at the stage angle (cs = cos, sn = sin). */
typedef void (*pmsm_rk4_rhs_fn)(const void *ctx, const double *x, double cs, double sn, double *dx);

static inline void pmsm_rk4_integrate(pmsm_rk4_rhs_fn f, const void *ctx, int rotate, double *x,
                                      int nx, double dt_s, int substeps)
{
    const double h = dt_s / (double)substeps;
    const double h2 = 0.5 * h;
    const double h6 = h / 6.0;
    int n, i;

    for (n = 0; n < substeps; ++n) {
        double k1[PMSM_RK4_MAX], k2[PMSM_RK4_MAX], k3[PMSM_RK4_MAX], k4[PMSM_RK4_MAX];
        double xs[PMSM_RK4_MAX];
        double c0 = 1.0, s0 = 0.0, cs = 1.0, sn = 0.0;

        if (rotate) {
            c0 = cos(x[PMSM_RK4_THETA]);
            s0 = sin(x[PMSM_RK4_THETA]);
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
            x[i] += h6 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
    }
}

#endif /* PMSM_RK4_H */
