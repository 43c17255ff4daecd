/*
 * twolevel_plant.h -- two-level inverter + PMSM plant, float64 (hand-written
 * runtime).
 *
 * Specification: docs/simulation.md "Plant" and
 * docs/algorithms.md (two-level MPTC) "Conventions".  The plant is simulated in
 * double precision on purpose: it is the physical system, separate from the
 * float32 controller, which only sees sampled currents, angle, speed and Udc.
 *
 * State: pmsm_state_t (sim_api.h): i_d, i_q in the rotor (dq) frame, d axis
 * on the magnet; mechanical speed; ELECTRICAL angle, wrapped to [0, 2*pi) at
 * the end of every twolevel_plant_advance call (the sub-steps inside a call
 * integrate it unwrapped).  Parameters: sim_params_t (motor, Udc,
 * speed_imposed).
 *
 * Model (amplitude-invariant transforms, mptc-two-level.md "Conventions"):
 *   u_alpha + j*u_beta = (2/3)*Udc*(Sa + a*Sb + a^2*Sc),  a = exp(j*2*pi/3)
 *   u_d =  u_alpha*cos(theta_e) + u_beta*sin(theta_e)
 *   u_q = -u_alpha*sin(theta_e) + u_beta*cos(theta_e)
 *   motor equations: pmsm_dq.h
 *
 * Integration (plant-and-metrics.md "Integration"): the inverter state is
 * constant over one call, so its alpha-beta voltage is constant; the 4-state
 * ODE is integrated by pmsm_rk4.h in `substeps` equal sub-steps (choose
 * substeps so that dt/substeps <= 1 us, e.g. 50 for dt = 50 us).  The
 * convergence test (halving the sub-step changes the currents by < 1e-6 A)
 * is tests/topologies/twolevel/test_plant.py.
 *
 * C99, no dynamic memory, no global state: every function is reentrant.
 */
#ifndef TWOLEVEL_PLANT_H
#define TWOLEVEL_PLANT_H

#include "sim_period.h"

/*
 * Integrate the plant over one interval of length dt_s during which the
 * inverter holds switching state sw = Sa*4 + Sb*2 + Sc (1 = upper switch on)
 * and the load torque is load_nm (N*m, opposing positive speed as T_L in
 * J*dw/dt = Te - T_L - B*w).  substeps >= 1 RK4 sub-steps of dt_s/substeps.
 * p->speed_imposed != 0: omega_m stays as set (load machine holds speed), J,
 * B and load_nm are then unused.
 * Returns 0, or -1 (state untouched) if sw is not 0..7, substeps < 1 or
 * dt_s is not a positive finite number.
 */
int twolevel_plant_advance(pmsm_state_t *s, const sim_params_t *p, int sw, double load_nm,
                           double dt_s, int substeps);

/* Stationary-frame voltage of switching state sw (0..7), V; (0,0) otherwise. */
void twolevel_plant_voltage_ab(const sim_params_t *p, int sw, double *u_alpha_v, double *u_beta_v);

#endif /* TWOLEVEL_PLANT_H */
