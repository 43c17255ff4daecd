/*
 * onboard.h -- mode onboard of the serial HIL protocol (HIL builds): the
 * board runs a float32 plant AND the controller at full rate on a
 * piecewise-constant speed/load profile (SETPOINTS) and sends decimated
 * samples (TELEMETRY) and cycle statistics (RUN_END).
 *
 * The plant is the host simulator's, written once on sim_real_t
 * (codegen/simulator/csrc/sim_real.h) and compiled here in float32: the dq
 * motor (pmsm_dq.h), classic RK4 (pmsm_rk4.h) in sub-steps of at most
 * ONB_SUBSTEP_MAX_S, the speed PI (speed_pi.h), the controller's motor
 * inputs (sim_motor_inputs.h) and the topology's right-hand side
 * (<topology>_rhs.h); sampling at the start of each period as the host
 * simulator does, the decision of period k acting during [t_k+d, t_k+d+1)
 * with d = ONB_DELAY_PERIODS, the simulator's actuation delay
 * (codegen.model.Plant.delay_periods).  No inverter or sensor
 * non-idealities.  The constants (motor, DC link, speed loop, timing) are
 * the generated plant_config.h's, the plant core's files and the topology's
 * part (the onb_topo_* functions below) come with the topology
 * (Topology.firmware_plant).
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

/* the plant core in float32 (sim_real.h): before any of its headers */
#ifndef SIM_REAL_F32
#define SIM_REAL_F32 1
#endif
#include "sim_real.h"
#if !SIM_REAL_IS_F32
#error "onboard.h: the plant core was included in float64 before onboard.h"
#endif

#include <stdint.h>

#include "hil_codec.h"
#include "mpc_binding.h"

/* Plant state: i_d, i_q (A), omega_m (rad/s), theta_e (rad, [0, 2*pi) at the sample instant), V_o (V;
 * 0 for a two-level inverter). */
typedef struct {
    sim_real_t x[5];
} onb_plant_t;

/* Called with every full block of samples (and the last, shorter one), whether or not the block is sent:
 * the run does not depend on the frame window. */
typedef void (*onb_emit_fn)(const hil_sample_t *samples, uint16_t n);

/* 0 if the setpoints are valid, else the ERROR detail (1 periods, 2 decimation, 3 step count, 4 step order,
 * 5 frame window: frame_first or frame_count negative). */
uint16_t onboard_check(const hil_setpoints_t *sp);

/* Run the profile from rest (plant, PI, topology state reset); fill *end. */
void onboard_run(const hil_setpoints_t *sp, uint32_t overhead, onb_emit_fn emit, hil_run_end_t *end);

/* The topology's part (its firmware plant file): reset its decision queue (the inverter idle before the
 * first decisions). */
void onb_topo_reset(void);
/* The topology's controller inputs at the sample instant. */
void onb_topo_input(const onb_plant_t *p, mpc_input_t *in);
/* Take the decision `out` and integrate the period [t_k, t_k+1) with the one acting then (the decision of
 * k - ONB_DELAY_PERIODS), the angle wrapped at the end; 0, or -3 for an invalid decision. */
int16_t onb_topo_apply(onb_plant_t *p, const mpc_output_t *out, sim_real_t load_nm);
/* For the topology's part: shift its gates-off queue (gates[0] the request of k, [1] of k-1, [2] of k-2);
 * when the acting request (of k - ONB_DELAY_PERIODS) is set, integrate the period with the inverter open
 * (every switch off, the currents in the diodes: sim_inverter.h "The open inverter"; nx the plant state's
 * length) and return 1; else 0, and the topology applies its decision. */
int onb_gates_open_period(uint16_t gates[3], uint16_t gates_off, onb_plant_t *p, sim_real_t load_nm, int nx);

#endif /* ONBOARD_H */
