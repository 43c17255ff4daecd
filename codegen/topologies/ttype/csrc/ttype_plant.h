/*
 * plant3l.h -- T-type three-level inverter + PMSM plant, float64
 * (hand-written runtime).
 *
 * Specification: shared/spec/plant-and-metrics.md "Plant" and
 * shared/spec/mpdtc-three-level.md "Inverter, vectors, neutral point".  The
 * plant is simulated in double precision on purpose: it is the physical
 * system, separate from the float32 controller.
 *
 * State (SI units):
 *   i_d_a, i_q_a    stator current in the rotor (dq) frame, A (d axis on the
 *                   magnet, Park with the electrical rotor angle).
 *   omega_m_rad_s   mechanical rotor speed, rad/s.
 *   theta_e_rad     ELECTRICAL rotor angle, rad; wrapped to [0, 2*pi) at the
 *                   end of every plant3l_advance* call.
 *   vo_v            neutral-point voltage V_o = (u_c1 - u_c2)/2, V.
 *
 * Inverter (switching state index = 9*(Sa+1) + 3*(Sb+1) + (Sc+1), NNN = 0,
 * OOO = 13, PPP = 26; leg level S_x in {-1, 0, +1} = {N, O, P}):
 *   DC link: two capacitors C1 = C2 = C (c_f), P-o and o-N, fed by a stiff
 *   DC source across the pair:  u_c1 + u_c2 = Udc at all times, so
 *   u_c1 = Udc/2 + V_o,  u_c2 = Udc/2 - V_o.
 *   Leg voltage to the midpoint o:  u_xo = +u_c1 (S=+1), 0 (S=0), -u_c2 (S=-1)
 *                                        = S_x*Udc/2 + |S_x|*V_o.
 *   Phase voltage (isolated star point n): u_xn = u_xo - (u_ao+u_bo+u_co)/3;
 *   the amplitude-invariant Clarke transform of u_xn equals that of u_xo:
 *   u_alpha = (2/3)*(u_ao - (u_bo + u_co)/2),  u_beta = (u_bo - u_co)/sqrt(3).
 *   Line voltage u_ab = u_ao - u_bo.
 *
 * Neutral point, SIGN CONVENTION: the phase current i_x is positive out of
 * the inverter leg into the motor.  A leg at O connects its phase to the
 * midpoint, so the current drawn FROM the midpoint node o into the phases is
 *   i_o = sum_x (1 - |S_x|) * i_x          (= -sum_x |S_x|*i_x, i_a+i_b+i_c = 0).
 * KCL at o with C1 carrying i_C1 = C*du_c1/dt from P into o and C2 carrying
 * i_C2 = C*du_c2/dt from o to N:  i_C1 = i_C2 + i_o; the stiff source gives
 * du_c1/dt = -du_c2/dt, hence du_c1/dt = i_o/(2C), du_c2/dt = -i_o/(2C) and
 *   dV_o/dt = i_o / (2C)      (mpdtc-three-level.md, as the spec states).
 * Drawing current out of the midpoint (i_o > 0) raises V_o.  Example: the
 * P-type small state POO (legs b, c at O) with i_a > 0 has i_o = i_b + i_c =
 * -i_a < 0 and lowers V_o; its N-type partner ONN (leg a at O) has i_o = i_a
 * and raises it.
 *
 * Motor (as plant2l.h, Ld and Lq may differ):
 *   Ld*di_d/dt = u_d - Rs*i_d + omega_e*Lq*i_q
 *   Lq*di_q/dt = u_q - Rs*i_q - omega_e*Ld*i_d - omega_e*psi_f
 *   J*domega_m/dt = Te - T_L - B*omega_m   (or omega_m held: speed imposed)
 *   dtheta_e/dt = omega_e = p*omega_m
 *   Te = 1.5*p*(psi_d*i_q - psi_q*i_d),  psi_d = Ld*i_d + psi_f, psi_q = Lq*i_q
 *
 * Integration (plant-and-metrics.md "Integration"): within one segment the
 * switching state is constant; the 5-state ODE (i_d, i_q, omega_m, theta_e,
 * V_o) -- the inverter voltage depends on V_o, the midpoint current on the
 * currents -- is integrated with the classic 4th-order Runge-Kutta method in
 * equal sub-steps h = T_seg/ceil(T_seg/substep_max_s) <= substep_max_s
 * (1 us by default).  Zero-length segments are skipped.
 *
 * C99, no dynamic memory, no global state: every function is reentrant.
 */
#ifndef PLANT3L_H
#define PLANT3L_H

/* Number of segments of one control period (seven-segment virtual vectors). */
#define PLANT3L_N_SEG 7
/* Number of switching states. */
#define PLANT3L_N_STATES 27

/* Motor, inverter and DC-link parameters (SI units). */
typedef struct {
    double rs_ohm;     /* stator resistance Rs, ohm */
    double ld_h;       /* d-axis inductance Ld, H */
    double lq_h;       /* q-axis inductance Lq, H */
    double psi_f_wb;   /* permanent-magnet flux linkage psi_f, Wb */
    int pole_pairs;    /* pole pairs p */
    double j_kgm2;     /* rotor + load inertia J, kg*m^2 (> 0 unless speed imposed) */
    double b_nms;      /* viscous friction B, N*m*s/rad */
    double udc_v;      /* DC-link voltage Udc = u_c1 + u_c2, V (stiff source) */
    double c_f;        /* each DC-link capacitor C1 = C2 = C, F */
} plant3l_params_t;

/* Plant state (see the header comment). */
typedef struct {
    double i_d_a;
    double i_q_a;
    double omega_m_rad_s;
    double theta_e_rad;
    double vo_v;
} plant3l_state_t;

/*
 * Integrate the plant over one constant segment of length dt_s during which
 * the inverter holds switching state `state` (0..26), in `substeps` >= 1
 * equal RK4 sub-steps, with load torque load_nm (as T_L in J*dw/dt = Te -
 * T_L - B*w; unused with speed_imposed != 0, when omega_m stays as set).
 * Returns 0, or -1 (state untouched) for state outside 0..26, substeps < 1 or
 * dt_s not a positive finite number.
 */
int plant3l_advance(plant3l_state_t *s, const plant3l_params_t *p, int state,
                    double load_nm, double dt_s, int substeps, int speed_imposed);

/*
 * Integrate the seven segments of one control period: segment i holds
 * switching state states[i] for seg_s[i] seconds (seg_s[i] == 0: skipped).
 * Each non-empty segment takes ceil(seg_s[i]/substep_max_s) equal RK4
 * sub-steps (a 1e-9 relative tolerance keeps e.g. 50 us / 1 us at 50).
 * uab_v (may be NULL) receives, per segment, the line voltage u_ab = u_ao -
 * u_bo of the segment's state at the V_o of the segment's start (for a
 * zero-length segment: the V_o at that instant); the waveform is piecewise
 * constant at segment resolution (V_o moves by mV within a segment).
 * Returns 0, or -1 (state untouched, uab_v untouched) if any states[i] is
 * outside 0..26, any seg_s[i] is negative or non-finite, or substep_max_s is
 * not a positive finite number.
 */
int plant3l_advance_segments(plant3l_state_t *s, const plant3l_params_t *p,
                             const unsigned short states[7], const double seg_s[7],
                             double load_nm, double substep_max_s, int speed_imposed,
                             double uab_v[7]);

/* Leg levels (Sa, Sb, Sc) in {-1, 0, +1} of state 0..26; returns -1 otherwise. */
int plant3l_levels(int state, int levels[3]);

/* Stationary-frame voltage of `state` at neutral-point voltage vo_v, V. */
void plant3l_voltage_ab(const plant3l_params_t *p, int state, double vo_v,
                        double *u_alpha_v, double *u_beta_v);

/* Line voltage u_ab = u_ao - u_bo of `state` at vo_v, V (0 for a bad state). */
double plant3l_uab(const plant3l_params_t *p, int state, double vo_v);

/* Midpoint current i_o = sum_x (1 - |S_x|) i_x of `state` at the plant state, A. */
double plant3l_io(const plant3l_state_t *s, int state);

/* Phase currents i_a, i_b (A): inverse Park, inverse Clarke (as plant2l). */
void plant3l_phase_currents(const plant3l_state_t *s, double *ia_a, double *ib_a);

/* Electromagnetic torque Te, N*m. */
double plant3l_torque(const plant3l_state_t *s, const plant3l_params_t *p);

/* Stator flux magnitude |psi_s|, Wb. */
double plant3l_flux(const plant3l_state_t *s, const plant3l_params_t *p);

/* Wrap an angle to [0, 2*pi). */
double plant3l_wrap_angle(double x);

#endif /* PLANT3L_H */
