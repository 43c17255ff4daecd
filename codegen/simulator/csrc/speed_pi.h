/*
 * speed_pi.h -- speed PI of the closed-loop host simulators (sim_period.c),
 * float64 (hand-written runtime).
 *
 * Specification: docs/algorithms.md (two-level MPTC) "Parameters and scenarios"
 * (speed PI on the mechanical speed error in rad/s, clamped output with
 * anti-windup); the three-level simulator uses the same PI.
 *
 * C99, no dynamic memory, no global state.  Not part of any cffi cdef.
 */
#ifndef SPEED_PI_H
#define SPEED_PI_H

/*
 * One period of the speed PI:
 *   e = w_ref - w_m (mechanical, rad/s); u = kp*e + I; T* = clamp(u, +-L)
 *   anti-windup, conditional integration: I += ki*e*dt unless
 *   (u > L and e > 0) or (u < -L and e < 0); then I = clamp(I, +-L).
 * *integral is I (N*m), updated in place; returns T* (N*m).
 */
double speed_pi_step(double kp, double ki, double dt_s, double limit_nm, double *integral,
                     double w_ref, double w_m);

#endif /* SPEED_PI_H */
