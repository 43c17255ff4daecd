/*
 * speed_pi.h -- the speed PI of the closed loop, written once on sim_real_t
 * (sim_real.h): float64 in the host simulators (sim_period.c, through
 * speed_pi.c's speed_pi_step), float32 in the firmware's on-board loop
 * (firmware/runtime/onboard.c) (hand-written runtime).
 *
 * Specification: docs/algorithms.md (two-level MPTC) "Parameters and scenarios"
 * (speed PI on the mechanical speed error in rad/s, clamped output with
 * anti-windup); the three-level simulator uses the same PI.  The portable
 * PI the generator writes for a drive (<prefix>_speed_pi.c) folds ki*dt into
 * one constant rounded once in its number format; this one takes ki and dt
 * and rounds ki*e*dt in that order.
 *
 * C99, no dynamic memory, no global state.  Not part of any cffi cdef.
 */
#ifndef SPEED_PI_H
#define SPEED_PI_H

#include "sim_real.h"

/*
 * One period of the speed PI:
 *   e = w_ref - w_m (mechanical, rad/s); u = kp*e + I; T* = clamp(u, +-L)
 *   anti-windup, conditional integration: I += ki*e*dt unless
 *   (u > L and e > 0) or (u < -L and e < 0); then I = clamp(I, +-L).
 * *integral is I (N*m), updated in place; returns T* (N*m).
 */
static inline sim_real_t speed_pi_update(sim_real_t kp, sim_real_t ki, sim_real_t dt_s,
                                         sim_real_t limit_nm, sim_real_t *integral, sim_real_t w_ref,
                                         sim_real_t w_m)
{
    const sim_real_t lim = limit_nm;
    const sim_real_t e = w_ref - w_m;
    const sim_real_t u = kp * e + *integral;
    sim_real_t t_ref = u;
    if (t_ref > lim) {
        t_ref = lim;
    } else if (t_ref < -lim) {
        t_ref = -lim;
    }
    if (!((u > lim && e > SIM_R(0.0)) || (u < -lim && e < SIM_R(0.0)))) {
        sim_real_t i_new = *integral + ki * e * dt_s;
        if (i_new > lim) {
            i_new = lim;
        } else if (i_new < -lim) {
            i_new = -lim;
        }
        *integral = i_new;
    }
    return t_ref;
}

#if !SIM_REAL_IS_F32
/* The float64 PI of the host simulators (speed_pi.c): speed_pi_update by name. */
double speed_pi_step(double kp, double ki, double dt_s, double limit_nm, double *integral,
                     double w_ref, double w_m);
#endif

#endif /* SPEED_PI_H */
