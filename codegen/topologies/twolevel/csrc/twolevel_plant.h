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
 * (the right-hand side: twolevel_rhs.h, written once on sim_real_t: also the
 * firmware's on-board plant, in float32).
 *
 * Integration (docs/simulation.md "Plant"): the inverter state is
 * constant over one call, so its alpha-beta voltage is constant; the 4-state
 * ODE is integrated by pmsm_rk4.h in `substeps` equal sub-steps (choose
 * substeps so that dt/substeps <= 1 us, e.g. 50 for dt = 50 us).  The
 * convergence test (halving the sub-step changes the currents by < 1e-6 A)
 * is tests/topologies/twolevel/test_plant.py.  With p->integrator ==
 * SIM_INTEGRATOR_EXACT (plant.integrator = "exact") every interval is
 * instead the Taylor series of the plant's solution summed to double
 * rounding (sim_exact.h; `substeps` then only serves the RK4 fallback of an
 * interval whose device-drop sign changes, and the open inverter's).
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
 * With p->device_drop_v > 0 each leg's voltage drops that much against its
 * phase current (sim_inverter.h); no dead time (no edge inside).
 * p->speed_imposed != 0: omega_m stays as set (load machine holds speed), J,
 * B and load_nm are then unused.
 * Returns 0, or -1 (state untouched) if sw is not 0..7, substeps < 1 or
 * dt_s is not a positive finite number.
 */
int twolevel_plant_advance(pmsm_state_t *s, const sim_params_t *p, int sw, double load_nm,
                           double dt_s, int substeps);

/*
 * One control period [t_k, t_k + dt_s) in which the inverter goes from
 * from_sw (held before t_k) to sw (both 0..7): the legs that change spend
 * p->dead_time_s at the level their current at t_k dictates
 * (sim_inverter.h), then sw for the rest of the period; every interval with
 * p->device_drop_v's drops against the stage currents.  RK4 sub-steps of at
 * most dt_s/substeps (exactly `substeps` over a whole period at one state).
 * t_snap_s >= 0: the plant state at that offset into the period goes to
 * *snap (the measurement-delay sample of the next period; an interval is
 * split there); -1: none.  With dead time and drops off and no snapshot
 * this is twolevel_plant_advance(s, p, sw, load_nm, dt_s, substeps), bit
 * for bit.  Returns 0, or -1 (state untouched) for a bad state or substeps.
 */
int twolevel_plant_advance_period(pmsm_state_t *s, const sim_params_t *p, int from_sw, int sw,
                                  double load_nm, int substeps, double t_snap_s, pmsm_state_t *snap);

/*
 * twolevel_plant_advance_period with the gates: open != 0 (the step's gates_off acting in this
 * period) integrates the whole period with the inverter open (every switch off, the phase currents
 * freewheeling in the diodes, sim_inverter.h "The open inverter"; sw then only validated);
 * from_open != 0 (the inverter was open before t_k) with p->dead_time_s > 0 spends the first dead
 * time open, then sw (every leg's switch turning on closes one dead time late).  With open =
 * from_open = 0 this is twolevel_plant_advance_period, bit for bit.  Returns 0 or -1 (as
 * twolevel_plant_advance_period).
 */
int twolevel_plant_advance_period_gates(pmsm_state_t *s, const sim_params_t *p, int from_sw,
                                        int from_open, int sw, int open, double load_nm, int substeps,
                                        double t_snap_s, pmsm_state_t *snap);

/*
 * Integrate the plant over dt_s with the inverter open (gates off): every switch off, each phase
 * current freewheeling through a diode against the DC link until it reaches zero, then held there
 * while the back-EMF stays within the DC link (sim_inverter.h "The open inverter"); each diode drops
 * p->device_drop_v.  substeps >= 1 equal sub-steps, a zero crossing located inside its sub-step.
 * Returns 0, or -1 (state untouched) if substeps < 1 or dt_s is not a positive finite number.
 */
int twolevel_plant_advance_open(pmsm_state_t *s, const sim_params_t *p, double load_nm, double dt_s,
                                int substeps);

/* Leg levels (Sa, Sb, Sc) in {0, 1} of switching state sw = Sa*4 + Sb*2 + Sc. */
void twolevel_plant_levels(int sw, int lv[3]);

/* Stationary-frame voltage of switching state sw (0..7), V; (0,0) otherwise. */
void twolevel_plant_voltage_ab(const sim_params_t *p, int sw, double *u_alpha_v, double *u_beta_v);

#endif /* TWOLEVEL_PLANT_H */
