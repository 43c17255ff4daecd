/*
 * plant2l.h -- two-level inverter + PMSM plant, float64 (hand-written runtime).
 *
 * Specification: shared/spec/plant-and-metrics.md "Plant" and
 * shared/spec/mptc-two-level.md "Conventions".  The plant is simulated in
 * double precision on purpose: it is the physical system, separate from the
 * float32 controller, which only sees sampled currents, angle, speed and Udc.
 *
 * State (SI units):
 *   i_d_a, i_q_a       stator current in the rotor (dq) frame, A; d axis on
 *                      the magnet (Park with the electrical rotor angle).
 *   omega_m_rad_s      mechanical rotor speed, rad/s.
 *   theta_e_rad        ELECTRICAL rotor angle, rad.  plant2l_advance keeps it
 *                      wrapped to [0, 2*pi) at the end of every call (the
 *                      sub-steps inside a call integrate it unwrapped).
 *
 * Model (amplitude-invariant transforms, mptc-two-level.md "Conventions"):
 *   u_alpha + j*u_beta = (2/3)*Udc*(Sa + a*Sb + a^2*Sc),  a = exp(j*2*pi/3)
 *   u_d =  u_alpha*cos(theta_e) + u_beta*sin(theta_e)
 *   u_q = -u_alpha*sin(theta_e) + u_beta*cos(theta_e)
 *   Ld*di_d/dt = u_d - Rs*i_d + omega_e*Lq*i_q
 *   Lq*di_q/dt = u_q - Rs*i_q - omega_e*Ld*i_d - omega_e*psi_f
 *   J*domega_m/dt = Te - T_L - B*omega_m   (or omega_m held: speed imposed)
 *   dtheta_e/dt = omega_e = p*omega_m
 *   Te = 1.5*p*(psi_d*i_q - psi_q*i_d),  psi_d = Ld*i_d + psi_f, psi_q = Lq*i_q
 *
 * Integration (plant-and-metrics.md "Integration"): the inverter state is
 * constant over one call, so its alpha-beta voltage is constant; the 4-state
 * ODE is integrated with the classic 4th-order Runge-Kutta method in
 * `substeps` equal sub-steps (choose substeps so that dt/substeps <= 1 us,
 * e.g. 50 for dt = 50 us).  The convergence test (halving the sub-step
 * changes the currents by < 1e-6 A) is tests/sim/test_plant.py.
 *
 * C99, no dynamic memory, no global state: every function is reentrant.
 */
#ifndef PLANT2L_H
#define PLANT2L_H

/* Motor and inverter parameters (shared/spec/mptc-two-level.md "Parameters"). */
typedef struct {
    double rs_ohm;     /* stator resistance Rs, ohm */
    double ld_h;       /* d-axis inductance Ld, H */
    double lq_h;       /* q-axis inductance Lq, H */
    double psi_f_wb;   /* permanent-magnet flux linkage psi_f, Wb */
    int pole_pairs;    /* pole pairs p */
    double j_kgm2;     /* rotor + load inertia J, kg*m^2 (> 0 unless speed imposed) */
    double b_nms;      /* viscous friction B, N*m*s/rad */
    double udc_v;      /* DC-link voltage Udc, V (stiff source) */
} plant2l_params_t;

/* Plant state (see the header comment for the frame and angle convention). */
typedef struct {
    double i_d_a;
    double i_q_a;
    double omega_m_rad_s;
    double theta_e_rad;
} plant2l_state_t;

/*
 * Integrate the plant over one interval of length dt_s during which the
 * inverter holds switching state sw = Sa*4 + Sb*2 + Sc (1 = upper switch on)
 * and the load torque is load_nm (N*m, opposing positive speed as T_L in
 * J*dw/dt = Te - T_L - B*w).  substeps >= 1 RK4 sub-steps of dt_s/substeps.
 * speed_imposed != 0: omega_m stays as set (load machine holds speed), J, B
 * and load_nm are then unused.
 * Returns 0, or -1 (state untouched) if sw is not 0..7, substeps < 1 or
 * dt_s is not a positive finite number.
 */
int plant2l_advance(plant2l_state_t *s, const plant2l_params_t *p, int sw,
                    double load_nm, double dt_s, int substeps, int speed_imposed);

/* Stationary-frame voltage of switching state sw (0..7), V; (0,0) otherwise. */
void plant2l_voltage_ab(const plant2l_params_t *p, int sw, double *u_alpha_v, double *u_beta_v);

/* Phase currents i_a, i_b (A) from the state: inverse Park, inverse Clarke. */
void plant2l_phase_currents(const plant2l_state_t *s, double *ia_a, double *ib_a);

/* Electrical rotor angle wrapped to [0, 2*pi), rad. */
double plant2l_theta_e(const plant2l_state_t *s);

/* Electromagnetic torque Te = 1.5*p*(psi_d*i_q - psi_q*i_d), N*m. */
double plant2l_torque(const plant2l_state_t *s, const plant2l_params_t *p);

/* Stator flux magnitude |psi_s| = sqrt(psi_d^2 + psi_q^2), Wb. */
double plant2l_flux(const plant2l_state_t *s, const plant2l_params_t *p);

/* Wrap an angle to [0, 2*pi). */
double plant2l_wrap_angle(double x);

#endif /* PLANT2L_H */
