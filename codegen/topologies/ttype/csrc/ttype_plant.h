/*
 * ttype_plant.h -- T-type three-level inverter + PMSM plant, float64
 * (hand-written runtime).
 *
 * Specification: docs/simulation.md "Plant" and
 * docs/algorithms.md (T-type MPDTC) "Inverter, vectors, neutral point".  The
 * plant is simulated in double precision on purpose: it is the physical
 * system, separate from the float32 controller.
 *
 * State (SI units): the motor's pmsm_state_t (sim_api.h; the ELECTRICAL
 * angle is wrapped to [0, 2*pi) at the end of every ttype_plant_advance*
 * call) and the neutral-point voltage vo_v = V_o = (u_c1 - u_c2)/2, V.
 * Parameters: ttype_sim_params_t (common: motor, Udc, speed_imposed; c_f:
 * each DC-link capacitor; substep_max_s: largest RK4 sub-step).
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
 * Motor: pmsm_dq.h (Ld and Lq may differ).  The right-hand side of one
 * interval of constant leg levels: ttype_rhs.h (written once on sim_real_t:
 * also the firmware's on-board plant, in float32).
 *
 * Integration (docs/simulation.md "Plant"): within one segment the
 * switching state is constant; the 5-state ODE (i_d, i_q, omega_m, theta_e,
 * V_o) -- the inverter voltage depends on V_o, the midpoint current on the
 * currents -- is integrated by pmsm_rk4.h (classic 4th-order Runge-Kutta) in
 * equal sub-steps h = T_seg/ceil(T_seg/substep_max_s) <= substep_max_s
 * (1 us by default).  Zero-length segments are skipped.  With
 * p->common.integrator == SIM_INTEGRATOR_EXACT (plant.integrator = "exact")
 * every segment is instead the Taylor series of the plant's solution summed
 * to double rounding (sim_exact.h; RK4 sub-steps remain for a segment whose
 * device-drop sign changes and for the open inverter).
 *
 * C99, no dynamic memory, no global state: every function is reentrant.
 */
#ifndef TTYPE_PLANT_H
#define TTYPE_PLANT_H

#include "sim_period.h"

/* Number of segments of one control period (seven-segment virtual vectors). */
#define TTYPE_PLANT_N_SEG 7
/* Number of switching states. */
#define TTYPE_PLANT_N_STATES 27

/* Plant state (see the header comment). */
typedef struct {
    pmsm_state_t motor;
    double vo_v;
} ttype_plant_state_t;

/*
 * Integrate the plant over one constant segment of length dt_s during which
 * the inverter holds switching state `state` (0..26), in `substeps` >= 1
 * equal RK4 sub-steps, with load torque load_nm (as T_L in J*dw/dt = Te -
 * T_L - B*w; unused with p->common.speed_imposed != 0, when omega_m stays as
 * set).  Returns 0, or -1 (state untouched) for state outside 0..26,
 * substeps < 1 or dt_s not a positive finite number.
 */
int ttype_plant_advance(ttype_plant_state_t *s, const ttype_sim_params_t *p, int state,
                        double load_nm, double dt_s, int substeps);

/*
 * Integrate the seven segments of one control period: segment i holds
 * switching state states[i] for seg_s[i] seconds (seg_s[i] == 0: skipped).
 * Each non-empty segment takes ceil(seg_s[i]/p->substep_max_s) equal RK4
 * sub-steps (a 1e-9 relative tolerance keeps e.g. 50 us / 1 us at 50).
 * uab_v (may be NULL) receives, per segment, the line voltage u_ab = u_ao -
 * u_bo of the segment's state at the V_o of the segment's start (for a
 * zero-length segment: the V_o at that instant); the waveform is piecewise
 * constant at segment resolution (V_o moves by mV within a segment).
 * Returns 0, or -1 (state untouched, uab_v untouched) if any states[i] is
 * outside 0..26, any seg_s[i] is negative or non-finite, or substep_max_s is
 * not a positive finite number.  Dead time applies between its segments
 * only (no state before the period: ttype_plant_advance_period with
 * from_state -1), device drops throughout.
 */
int ttype_plant_advance_segments(ttype_plant_state_t *s, const ttype_sim_params_t *p,
                                 const uint16_t states[7], const double seg_s[7],
                                 double load_nm, double uab_v[7]);

/*
 * One control period of seven segments (as ttype_plant_advance_segments)
 * with the inverter non-idealities of p->common (sim_inverter.h): every leg
 * edge -- from from_state (held before the period; < 0: as if states[0])
 * to the first non-empty segment, and between consecutive non-empty
 * segments -- spends the first min(dead_time_s, segment) of the new segment
 * at the level its phase current at the edge dictates; device drops
 * (device_drop_v per conducting device: 1 at P and N, 2 at O) against the
 * stage currents throughout.  t_snap_s >= 0: the plant state at that offset
 * into the period goes to *snap (its angle wrapped; an interval is split
 * there); -1: none.  Each piece takes ceil(length/substep_max_s) equal RK4
 * sub-steps.  With dead time and drops off, no snapshot, this equals
 * ttype_plant_advance_segments bit for bit.  Returns 0 or -1 (as
 * ttype_plant_advance_segments; also for from_state > 26).
 */
int ttype_plant_advance_period(ttype_plant_state_t *s, const ttype_sim_params_t *p, int from_state,
                               const uint16_t states[7], const double seg_s[7], double load_nm,
                               double uab_v[7], double t_snap_s, ttype_plant_state_t *snap);

/*
 * ttype_plant_advance_period with the gates: open != 0 (the step's gates_off acting in this period)
 * integrates the period's time (the segments' sum) with the inverter open -- every switch off, the
 * phase currents in the outer diodes across the whole DC link, the clamp pair off so V_o is held
 * (sim_inverter.h "The open inverter") -- the states then only recorded (uab_v as commanded);
 * from_open != 0 (the inverter was open before t_k) with dead_time_s > 0 spends the first
 * min(dead_time_s, segment) of the first non-empty segment open.  With open = from_open = 0 this is
 * ttype_plant_advance_period, bit for bit.  Returns 0 or -1 (as ttype_plant_advance_period).
 */
int ttype_plant_advance_period_gates(ttype_plant_state_t *s, const ttype_sim_params_t *p,
                                     int from_state, int from_open, int open,
                                     const uint16_t states[7], const double seg_s[7],
                                     double load_nm, double uab_v[7], double t_snap_s,
                                     ttype_plant_state_t *snap);

/*
 * Integrate the plant over dt_s with the inverter open (gates off): every switch off, each phase
 * current freewheeling through an outer diode against the whole DC link until it reaches zero, then
 * held there while the back-EMF stays within the DC link; V_o held (sim_inverter.h "The open
 * inverter"); each diode drops device_drop_v.  substeps >= 1 equal sub-steps, a zero crossing
 * located inside its sub-step; the angle wrapped at the end.  Returns 0, or -1 (state untouched) if
 * substeps < 1 or dt_s is not a positive finite number.
 */
int ttype_plant_advance_open(ttype_plant_state_t *s, const ttype_sim_params_t *p, double load_nm,
                             double dt_s, int substeps);

/* Leg levels (Sa, Sb, Sc) in {-1, 0, +1} of state 0..26; returns -1 otherwise. */
int ttype_plant_levels(int state, int levels[3]);

/* Stationary-frame voltage of `state` at neutral-point voltage vo_v, V. */
void ttype_plant_voltage_ab(const ttype_sim_params_t *p, int state, double vo_v,
                            double *u_alpha_v, double *u_beta_v);

/* Line voltage u_ab = u_ao - u_bo of `state` at vo_v, V (0 for a bad state). */
double ttype_plant_uab(const ttype_sim_params_t *p, int state, double vo_v);

/* Midpoint current i_o = sum_x (1 - |S_x|) i_x of `state` at the plant state, A. */
double ttype_plant_io(const ttype_plant_state_t *s, int state);

#endif /* TTYPE_PLANT_H */
