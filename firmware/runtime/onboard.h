/*
 * onboard.h -- mode onboard of the serial HIL protocol (HIL builds): the
 * board runs a float32 plant AND the controller at full rate on a
 * piecewise-constant speed/load profile (SETPOINTS) and sends decimated
 * samples (TELEMETRY) and cycle statistics (ONBOARD_END).
 *
 * The plant (onboard.c): the dq PMSM of codegen/simulator/csrc/pmsm_dq.h in
 * float32 (Rs, Ld, Lq, psi_f, p, J, B from the generated onboard_config.h),
 * classic RK4 with ONB_SUBSTEPS sub-steps per control period (a 7-segment
 * period: every segment in sub-steps of at most ONB_DT/ONB_SUBSTEPS), the
 * stage angle rotated from one sinf/cosf pair per sub-step; the speed PI in
 * float32 with the host's conditional-integration anti-windup (speed_pi.c);
 * sampling at the start of each period as the host simulator does.
 *
 * The inverter voltage is u_alpha = ua0 + ua1*V_o, u_beta = ub0 + ub1*V_o
 * and the neutral point dV_o/dt = ka*i_alpha + kb*i_beta (two capacitors C,
 * ka and kb already divided by 2C; all four 0 for a two-level inverter).
 * What differs per topology (the controller's extra inputs, how a decision
 * becomes voltage segments, the timing rule) is in onboard_<topology>.c,
 * the one file of the build that implements the onb_topo_* functions below.
 *
 * The controller's real inputs and outputs are reached through the generated
 * MPC_ENCODE_<field> / MPC_DECODE_<field> of mpc_binding.h (SI value <-> the
 * step's number format: float32 a cast, fixed point a Q-format count), so the
 * same plant drives either format.
 *
 * C99, C28x-safe: float only (no double arithmetic of our own), no 8-bit
 * types, no byte pointers.
 */
#ifndef ONBOARD_H
#define ONBOARD_H

#include <stdint.h>

#include "hil_codec.h"
#include "mpc_binding.h"

/* Plant state: i_d, i_q (A), omega_m (rad/s), theta_e (rad, [0, 2*pi)), V_o (V). */
typedef struct {
    float x[5];
} onb_plant_t;

/* One constant-voltage interval (see above). */
typedef struct {
    float ua0, ua1, ub0, ub1, ka, kb;
    uint16_t zero; /* 1: u = 0 and no neutral-point current (no Park rotation) */
} onb_segment_t;

/* Called with every full block of samples (and the last, shorter one). */
typedef void (*onb_emit_fn)(const hil_sample_t *samples, uint16_t n);

/* 0 if the setpoints are valid, else the ERROR detail (1 periods, 2 decimation, 3 step count, 4 step order). */
uint16_t onboard_check(const hil_setpoints_t *sp);

/* Run the profile from rest (plant, PI, topology state reset); fill *end. */
void onboard_run(const hil_setpoints_t *sp, uint32_t overhead, onb_emit_fn emit, hil_onboard_end_t *end);

/* Integrate the plant over dt_s (> 0) in `substeps` RK4 sub-steps of the segment's voltage. */
void onb_advance(onb_plant_t *p, const onb_segment_t *seg, float load_nm, float dt_s, uint16_t substeps);

/* The topology's part (onboard_<topology>.c). */
void onb_topo_reset(void);
/* The topology's controller inputs at the sample instant. */
void onb_topo_input(const onb_plant_t *p, mpc_input_t *in);
/* The decision (telemetry, change count). */
uint16_t onb_topo_decision(const mpc_output_t *out);
/* Apply the period [t_k, t_k+1) with the decision `out` (its timing rule); 0, or -3 for an invalid decision. */
int16_t onb_topo_apply(onb_plant_t *p, const mpc_output_t *out, float load_nm);

#endif /* ONBOARD_H */
