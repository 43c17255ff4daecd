/*
 * twolevel_sim.c -- closed-loop two-level PMSM drive: float64 plant
 * (twolevel_plant.c) + the generated float32 controller step (through
 * mpc_binding.h), with the shared period steps of sim_period.h.
 *
 * Specification: docs/simulation.md "Plant" (sampling at the
 * start of each period, the plant's actuation delay, speed loop) and
 * docs/algorithms.md (two-level MPTC) "Parameters and scenarios".  The API and its
 * structs: the generated sim_api.h (twolevel_sim_params_t, _state_t,
 * _trace_t from codegen/topologies/twolevel/sim.py).
 *
 * One period k (k = 0 .. n-1 over all chunks, t_k = k*dt_s), d = the
 * plant's actuation delay common.delay_periods (0, 1, 2):
 *  1.-3. imposed speed, sampling (through the sensors), torque reference
 *     T*(k) (sim_period.h).
 *  4. Controller input (every field in the step's number format): ia_a,
 *     ib_a, theta_e_rad, omega_e_rad_s, udc_v (the plant's), torque_ref_nm,
 *     prev_sw = the state the inverter applies during [t_k, t_k+1): the
 *     decision of k-d for d >= 1; for d = 0 (the decision of k acts at
 *     once) the state held at the sample instant, the decision of k-1.
 *     000 before the first decisions.  MPC_STEP(&in, &out).
 *  5. Record period k in the trace (sample-instant values, out.sw, prev_sw
 *     and the state applied during [t_k, t_k+1)).
 *  6. Decision queue: the state applied during [t_k, t_k+1) is the
 *     decision of k-d: out.sw (d = 0), prev_sw (d = 1, the decision of
 *     k-1) or prior_sw (d = 2, of k-2).  The step's gates_off travels with
 *     its decision (out.gates_off, prev_gates_off, prior_gates_off): when
 *     the one of k-d is 1 the inverter is open during [t_k, t_k+1), every
 *     switch off (a gates-off request takes effect with the actuation delay
 *     of a decision).  The controller's prev_sw stays the decision (the
 *     safe one, 000, that the PWM holds while its outputs are off).  The
 *     controller's delay_compensation (what it assumes) does not enter.  A
 *     decision outside 0..7 stops the run (-3).
 *  7. twolevel_plant_advance_period_gates from held_sw / held_open (the
 *     inverter of [t_k-1, t_k): the dead time of the edges at t_k) to the
 *     applied state, or the open inverter, over dt_s with `substeps` RK4
 *     sub-steps and the load torque load_nm[k] (ignored when the speed is
 *     imposed), keeping the plant at t_k+1 - measurement_delay_s for the
 *     next period's samples.
 *  Commit: held_sw := applied, held_open := open, prior_sw := prev_sw,
 *  prev_sw := out.sw, and the same for the gates_off queue.
 * Initial state: the shared one (sim_period_reset) and prev_sw = prior_sw =
 * held_sw = 0 (000), the gates_off queue 0, held_open 0.
 *
 * Period by period (the serial HIL's closed loop, where a board computes the
 * decision): twolevel_sim_hil_input gives the controller input of the next
 * period, twolevel_sim_hil_finish takes the decision and does steps 5.-7.;
 * the same code as twolevel_sim_run, so the two agree bit for bit.
 *
 * mpc_binding.h is generated per config and provides mpc_input_t,
 * mpc_output_t and the macro MPC_STEP(in_ptr, out_ptr).
 */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "sim_period.h"
#include "twolevel_plant.h"
#include "mpc_binding.h"

/* The step's gates_off (1: open the inverter).  Every generated binding (mpc_binding.h, which defines
 * MPC_CONFIG_HASH) has it in its output record; the stub controllers of tests/fixtures do not, and never
 * open the inverter. */
#ifdef MPC_CONFIG_HASH
#define GATES_OFF(out) ((out)->gates_off != 0u ? 1 : 0)
#else
#define GATES_OFF(out) ((void)(out), 0)
#endif

static int params_valid(const twolevel_sim_params_t *p)
{
    return p != NULL && sim_period_params_valid(&p->common) && p->substeps >= 1;
}

int twolevel_sim_init(const twolevel_sim_params_t *p, twolevel_sim_state_t *state)
{
    if (state == NULL || !params_valid(p)) {
        return -1;
    }
    sim_period_reset(&state->common);
    state->prev_sw = 0;
    state->prior_sw = 0;
    state->held_sw = 0;
    state->prev_gates_off = 0;
    state->prior_gates_off = 0;
    state->held_open = 0;
    return 0;
}

static int is_sw(int32_t sw)
{
    return sw >= 0 && sw <= 7;
}

static int is_flag(int32_t x)
{
    return x == 0 || x == 1;
}

/* The carried decisions and the held state are switching states 0..7, the gates_off flags 0 or 1. */
static int state_valid(const twolevel_sim_state_t *state)
{
    return is_sw(state->prev_sw) && is_sw(state->prior_sw) && is_sw(state->held_sw)
           && is_flag(state->prev_gates_off) && is_flag(state->prior_gates_off)
           && is_flag(state->held_open);
}

/* The controller's prev_sw: the state applied during [t_k, t_k+1) (the decision of k-d), or for
 * d = 0 the state held at the sample instant (the decision of k-1). */
static int controller_prev(const twolevel_sim_params_t *p, const twolevel_sim_state_t *state)
{
    return p->common.delay_periods >= 2 ? state->prior_sw : state->prev_sw;
}

/* The state applied during [t_k, t_k+1): the decision of k-d (step 6). */
static int applied(const twolevel_sim_params_t *p, const twolevel_sim_state_t *state, int sw_dec)
{
    switch (p->common.delay_periods) {
    case 0:
        return sw_dec;
    case 1:
        return state->prev_sw;
    default:
        return state->prior_sw;
    }
}

/* 1 if the inverter is open during [t_k, t_k+1): the gates_off of k-d (step 6), travelling with its
 * decision. */
static int applied_open(const twolevel_sim_params_t *p, const twolevel_sim_state_t *state, int gates_off)
{
    switch (p->common.delay_periods) {
    case 0:
        return gates_off;
    case 1:
        return state->prev_gates_off;
    default:
        return state->prior_gates_off;
    }
}

/* The plant at the sample instant of period state->common.k. */
static void plant_load(const twolevel_sim_state_t *state, pmsm_state_t *x)
{
    *x = state->common.motor;
}

/* Steps 1.-4. (inputs) of the period at state->common.k; x: the plant (step 1 may set its speed). */
static void period_input(const twolevel_sim_params_t *p, const twolevel_sim_state_t *state,
                         pmsm_state_t *x, double w_ref, double load, sim_sample_t *v,
                         mpc_input_t *in)
{
    /* 1.-3. */
    sim_period_sample(&p->common, &state->common, x, w_ref, load, v);

    /* 4. controller inputs in the step's number format, as a real controller sees them */
    memset(in, 0, sizeof *in);
    SIM_MOTOR_INPUTS(*in, *v);
    in->udc_v = MPC_ENCODE_udc_v(p->common.udc_v);
    in->prev_sw = (uint16_t)controller_prev(p, state);
}

/* Steps 5.-7. and the commit of period k (trace entry j) with the decision `out`. */
static int period_finish(const twolevel_sim_params_t *p, twolevel_sim_state_t *state,
                         pmsm_state_t *x, const sim_sample_t *v, const mpc_output_t *out,
                         const twolevel_sim_trace_t *tr, long j)
{
    const int sw_dec = (int)out->sw;
    const int gates_off = GATES_OFF(out);
    /* 6. the decision queue: the decision of k-d acts now (docs/simulation.md "Timing"), and its
     * gates_off: 1 opens the inverter (docs/simulation.md "Fault behaviour of the plant") */
    const int sw_apply = applied(p, state, sw_dec);
    const int open = applied_open(p, state, gates_off);
    const double t_snap = sim_period_snap_offset(&p->common);
    pmsm_state_t snap;

    /* 5. record the sample instant */
    sim_period_record(&tr->common, j, &p->common, &state->common, x, v, out->vector, out->n_eval,
                      out->fault, (uint16_t)gates_off, open,
                      (float)MPC_DECODE_te_est_nm(out->te_est_nm),
                      (float)MPC_DECODE_psi_est_wb(out->psi_est_wb));
    if (tr->sw != NULL) tr->sw[j] = (uint16_t)out->sw;
    if (tr->applied_sw != NULL) tr->applied_sw[j] = (uint16_t)(sw_apply & 0xFFFF);
    if (tr->prev_sw != NULL) tr->prev_sw[j] = (uint16_t)controller_prev(p, state);

    if (!is_sw(sw_dec)) {
        state->common.motor = *x;
        return -3;
    }

    /* 7. integrate the plant over [t_k, t_k+1), from the inverter held before t_k */
    (void)twolevel_plant_advance_period_gates(x, &p->common, state->held_sw, state->held_open,
                                              sw_apply, open, v->load, p->substeps, t_snap, &snap);
    if (!sim_period_finite(x)) {
        return -2; /* *state still holds the sample instant of period k */
    }
    state->held_sw = sw_apply;
    state->held_open = open;
    state->prior_sw = state->prev_sw;
    state->prev_sw = sw_dec;
    state->prior_gates_off = state->prev_gates_off;
    state->prev_gates_off = gates_off;
    sim_period_commit(&p->common, &state->common, x, t_snap >= 0.0 ? &snap : NULL, v);
    return 0;
}

/* twolevel_sim_run, twolevel_sim_hil_input and twolevel_sim_hil_finish (sim_period.h) */
SIM_PERIOD_ENTRY_POINTS(twolevel_sim, pmsm_state_t)
