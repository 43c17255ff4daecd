/*
 * ttype_sim.c -- closed-loop T-type three-level PMSM drive: float64 plant
 * (ttype_plant.c, model and V_o sign convention in ttype_plant.h) + the
 * generated float32 controller step (through mpc_binding.h), with the
 * shared period steps of sim_period.h.
 *
 * Specification: docs/simulation.md ("Plant", "Sampling",
 * "Timing") and docs/algorithms.md (T-type MPDTC) (inverter, neutral point,
 * "one-step delay compensation", scenarios).  The API and its structs: the
 * generated sim_api.h (ttype_sim_params_t, _state_t, _trace_t from
 * codegen/topologies/ttype/sim.py).
 *
 * Timing: the decision computed from the samples at t_k is applied during
 * [t_k+d, t_k+d+1), d = the plant's actuation delay common.delay_periods
 * (0, 1, 2), whatever the controller assumes (the MPDTC step always
 * compensates one period).  The state carries a queue of the last two
 * decisions: "applied" = the decision of k-1, "prior" = that of k-2; before
 * the first decisions both are OOO (vector 13, states all 13, seg_s =
 * {dt_s, 0, ..., 0}, T_N = 0).
 *
 * One period k (k = 0 .. n-1 over all chunks, t_k = k*dt_s):
 *  1.-3. imposed speed, sampling (through the sensors), torque reference
 *     T*(k) (sim_period.h); also V_o as sampled (at t_k - measurement_delay_s),
 *     u_c1 = 0.5*Udc + V_o, u_c2 = 0.5*Udc - V_o (double, the plant's Udc).
 *  4. Controller input (every field in the step's number format): ia_a,
 *     ib_a, theta_e_rad, omega_e_rad_s, uc1_v, uc2_v, torque_ref_nm,
 *     prev_vector = the vector applied during [t_k, t_k+1), the decision of
 *     k-d (for d = 0, whose decision acts at once: the one held at the
 *     sample instant, of k-1; 13 = OOO before the first decisions),
 *     t_n_prev_s = its T_N (0 for OOO).  MPC_STEP(&in, &out).
 *  5. Record period k: sample-instant values, the decision, the controller's
 *     prev_vector / t_n_prev_s, and the waveform of the applied period (its 7
 *     segments).
 *  6. Check the decision (ttype_decision_take, ttype_decision.h: vector <= 62,
 *     states[i] <= 26, seg_s[i] finite and >= 0, |sum seg_s - dt_s| <=
 *     1e-4*dt_s).  It is stored in double with the last non-empty segment
 *     set to dt_s minus the sum of the others, so that the plant's period is
 *     dt_s (the float32 sum is off by ~1e-7 relative).  The period applied during [t_k, t_k+1) is the decision of
 *     k-d: this one (d = 0), "applied" (d = 1) or "prior" (d = 2).
 *     The step's gates_off travels with its decision (applied_gates_off,
 *     prior_gates_off): when the one of k-d is 1 the inverter is open during
 *     [t_k, t_k+1), every switch off (a gates-off request takes effect with
 *     the actuation delay of a decision); the controller's prev_vector stays
 *     the decision (the safe one, OOO, that the PWM holds while its outputs
 *     are off), the recorded segments and uab_v are the commanded ones.
 *  7. ttype_plant_advance_period_gates over the applied 7 segments from the
 *     state at the end of the previous period (dead time at every leg edge;
 *     after an open period the first dead time open), or with the inverter
 *     open, substep_max_s and load_nm[k], keeping the plant at
 *     t_k+1 - measurement_delay_s for the next period's samples.
 *  Commit: prior := applied, applied := the decision of k (with their
 *  gates_off), last_open := open.
 *
 * Leg-level changes of period k: sum over the legs and over consecutive
 * NON-EMPTY applied segments of |S_x(i) - S_x(i-1)| (a P<->N jump counts
 * 2), including the boundary from the last non-empty segment of the
 * previous period (OOO before period 0); 0 in an open period, whose
 * following period counts from the state before it.
 *
 * Period by period (the serial HIL's closed loop, where a board computes the
 * decision): ttype_sim_hil_input gives the controller input of the next
 * period, ttype_sim_hil_finish takes the decision and does steps 5.-7.; the
 * same code as ttype_sim_run, so the two agree bit for bit.
 *
 * mpc_binding.h is generated per config and provides mpc_input_t,
 * mpc_output_t and MPC_STEP(in_ptr, out_ptr).
 */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "pmsm_dq.h"
#include "sim_period.h"
#include "ttype_plant.h"
#include "mpc_binding.h"
#include "ttype_decision.h"

/* The step's gates_off (1: open the inverter).  Every generated binding (mpc_binding.h, which defines
 * MPC_CONFIG_HASH) has it in its output record; the stub controllers of tests/fixtures do not, and never
 * open the inverter. */
#ifdef MPC_CONFIG_HASH
#define GATES_OFF(out) ((out)->gates_off != 0u ? 1 : 0)
#else
#define GATES_OFF(out) ((void)(out), 0)
#endif

#define TTYPE_SIM_OOO TTYPE_DECISION_OOO
#define TTYPE_SIM_N_VECTORS TTYPE_DECISION_N_VECTORS

static int params_valid(const ttype_sim_params_t *p)
{
    return p != NULL && sim_period_params_valid(&p->common) && pmsm_dq_finite_positive(p->c_f)
           && pmsm_dq_finite_positive(p->substep_max_s);
}

int ttype_sim_init(const ttype_sim_params_t *p, ttype_sim_state_t *state)
{
    int i;
    if (state == NULL || !params_valid(p)) {
        return -1;
    }
    memset(state, 0, sizeof *state);
    sim_period_reset(&state->common);
    state->applied_vector = TTYPE_SIM_OOO;
    state->applied_t_n_s = 0.0;
    state->prior_vector = TTYPE_SIM_OOO;
    state->prior_t_n_s = 0.0;
    for (i = 0; i < TTYPE_PLANT_N_SEG; ++i) {
        state->applied_states[i] = TTYPE_SIM_OOO;
        state->applied_seg_s[i] = 0.0;
        state->prior_states[i] = TTYPE_SIM_OOO;
        state->prior_seg_s[i] = 0.0;
    }
    state->applied_seg_s[0] = p->common.dt_s;
    state->prior_seg_s[0] = p->common.dt_s;
    state->last_state = TTYPE_SIM_OOO;
    state->sampled_vo_v = 0.0;
    state->applied_gates_off = 0;
    state->prior_gates_off = 0;
    state->last_open = 0;
    return 0;
}

/* A carried decision is valid (vector 0..62, states 0..26, durations finite, >= 0). */
static int decision_valid(int32_t vector, const uint16_t states[7], const double seg_s[7])
{
    int i;
    if (vector < 0 || vector >= TTYPE_SIM_N_VECTORS) {
        return 0;
    }
    for (i = 0; i < TTYPE_PLANT_N_SEG; ++i) {
        if (states[i] >= TTYPE_PLANT_N_STATES || !isfinite(seg_s[i]) || seg_s[i] < 0.0) {
            return 0;
        }
    }
    return 1;
}

static int is_flag(int32_t x)
{
    return x == 0 || x == 1;
}

/* The carried queue and last state are valid (the gates_off flags 0 or 1). */
static int state_valid(const ttype_sim_state_t *state)
{
    return decision_valid(state->applied_vector, state->applied_states, state->applied_seg_s)
           && decision_valid(state->prior_vector, state->prior_states, state->prior_seg_s)
           && state->last_state >= 0 && state->last_state < TTYPE_PLANT_N_STATES
           && is_flag(state->applied_gates_off) && is_flag(state->prior_gates_off)
           && is_flag(state->last_open);
}

/* The decision of k-1 (slot 0, "applied") or k-2 (slot 1, "prior"). */
static void queued(const ttype_sim_state_t *state, int slot, ttype_decision_t *d)
{
    int i;
    d->vector = slot == 0 ? state->applied_vector : state->prior_vector;
    d->t_n_s = slot == 0 ? state->applied_t_n_s : state->prior_t_n_s;
    for (i = 0; i < TTYPE_PLANT_N_SEG; ++i) {
        d->states[i] = slot == 0 ? state->applied_states[i] : state->prior_states[i];
        d->seg_s[i] = slot == 0 ? state->applied_seg_s[i] : state->prior_seg_s[i];
    }
}

/* The controller's prev_vector / t_n_prev_s: the decision of k-d applied during [t_k, t_k+1),
 * for d = 0 the one held at the sample instant (of k-1). */
static void controller_prev(const ttype_sim_params_t *p, const ttype_sim_state_t *state,
                            ttype_decision_t *d)
{
    queued(state, p->common.delay_periods >= 2 ? 1 : 0, d);
}

/* Sum of |S_x(to) - S_x(from)| over the three legs. */
static unsigned leg_steps(int from, int to)
{
    int a[3], b[3], i;
    unsigned n = 0u;
    if (ttype_plant_levels(from, a) != 0 || ttype_plant_levels(to, b) != 0) {
        return 0u;
    }
    for (i = 0; i < 3; ++i) {
        const int d = a[i] - b[i];
        n += (unsigned)(d < 0 ? -d : d);
    }
    return n;
}

/* Leg-level changes of the applied period a (non-empty segments only) after the state `from`;
 * *last receives the state of its last non-empty segment. */
static unsigned applied_changes(const ttype_decision_t *a, int from, int *last)
{
    unsigned changes = 0u;
    int i, prev = from;
    *last = prev;
    for (i = 0; i < TTYPE_PLANT_N_SEG; ++i) {
        if (a->seg_s[i] > 0.0) {
            changes += leg_steps(prev, (int)a->states[i]);
            prev = (int)a->states[i];
            *last = prev;
        }
    }
    return changes;
}

/* The plant at the sample instant of period state->common.k. */
static void plant_load(const ttype_sim_state_t *state, ttype_plant_state_t *x)
{
    x->motor = state->common.motor;
    x->vo_v = state->vo_v;
}

/* V_o as the controller samples it: at t_k - measurement_delay_s (the kept value), else at t_k. */
static double sampled_vo(const ttype_sim_params_t *p, const ttype_sim_state_t *state,
                         const ttype_plant_state_t *x)
{
    return sim_period_delayed(&p->common, &state->common) ? state->sampled_vo_v : x->vo_v;
}

/* Steps 1.-4. (inputs) of the period at state->common.k; x: the plant (step 1 may set its speed). */
static void period_input(const ttype_sim_params_t *p, const ttype_sim_state_t *state,
                         ttype_plant_state_t *x, double w_ref, double load, sim_sample_t *v,
                         mpc_input_t *in)
{
    ttype_decision_t prev;
    double vo;

    /* 1.-3. */
    sim_period_sample(&p->common, &state->common, &x->motor, w_ref, load, v);

    /* 4. controller inputs in the step's number format */
    vo = sampled_vo(p, state, x);
    controller_prev(p, state, &prev);
    memset(in, 0, sizeof *in);
    SIM_MOTOR_INPUTS(*in, *v);
    in->uc1_v = MPC_ENCODE_uc1_v(0.5 * p->common.udc_v + vo);
    in->uc2_v = MPC_ENCODE_uc2_v(0.5 * p->common.udc_v - vo);
    in->prev_vector = (uint16_t)prev.vector;
    in->t_n_prev_s = MPC_ENCODE_t_n_prev_s(prev.t_n_s);
}

/* Steps 5.-7. and the commit of period k (trace entry j) with the decision `out`. */
static int period_finish(const ttype_sim_params_t *p, ttype_sim_state_t *state,
                         ttype_plant_state_t *x, const sim_sample_t *v, const mpc_output_t *out,
                         const ttype_sim_trace_t *tr, long j)
{
    const int d = p->common.delay_periods;
    const double t_snap = sim_period_snap_offset(&p->common);
    double uab[7] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    const int gates_off = GATES_OFF(out);
    ttype_decision_t dec, cur, prev;
    ttype_plant_state_t snap;
    unsigned changes;
    int i, last, bad, open;

    /* 6. check the decision; the period applied now is the decision of k-d, with its gates_off
     * (1: the inverter open, docs/simulation.md "Fault behaviour of the plant") */
    bad = ttype_decision_take(out, p->common.dt_s, &dec);
    if (d == 0) {
        cur = dec;
        open = gates_off;
    } else {
        queued(state, d - 1, &cur);
        open = (d == 1) ? state->applied_gates_off : state->prior_gates_off;
    }
    controller_prev(p, state, &prev);
    changes = applied_changes(&cur, state->last_state, &last);
    if (open) { /* no leg switches; the next period's edges count from the state before */
        changes = 0u;
        last = state->last_state;
    }

    /* 5. record the sample instant, the decision, the applied period */
    sim_period_record(&tr->common, j, &p->common, &state->common, &x->motor, v, out->vector,
                      out->n_eval, out->fault, (uint16_t)gates_off, open,
                      (float)MPC_DECODE_te_est_nm(out->te_est_nm),
                      (float)MPC_DECODE_psi_est_wb(out->psi_est_wb));
    if (tr->vo_v != NULL) tr->vo_v[j] = x->vo_v;
    if (tr->vo_meas_v != NULL) tr->vo_meas_v[j] = sampled_vo(p, state, x);
    if (tr->t_n_s != NULL) tr->t_n_s[j] = (double)MPC_DECODE_t_n_s(out->t_n_s);
    if (tr->psi_ref_wb != NULL) tr->psi_ref_wb[j] = (float)MPC_DECODE_psi_ref_wb(out->psi_ref_wb);
    if (tr->vo_est_v != NULL) tr->vo_est_v[j] = (float)MPC_DECODE_vo_v(out->vo_v);
    if (tr->applied_vector != NULL) tr->applied_vector[j] = (uint16_t)cur.vector;
    if (tr->prev_vector != NULL) tr->prev_vector[j] = (uint16_t)prev.vector;
    if (tr->t_n_prev_s != NULL) tr->t_n_prev_s[j] = prev.t_n_s;
    if (tr->leg_changes != NULL) tr->leg_changes[j] = (uint16_t)changes;
    for (i = 0; i < TTYPE_PLANT_N_SEG; ++i) {
        if (tr->seg_s != NULL) tr->seg_s[7 * j + i] = cur.seg_s[i];
        if (tr->seg_states != NULL) tr->seg_states[7 * j + i] = cur.states[i];
    }

    /* 7. integrate the applied period over [t_k, t_k+1) (not an invalid decision of d = 0) */
    if (!(bad != 0 && d == 0)) {
        (void)ttype_plant_advance_period_gates(x, p, state->last_state, state->last_open, open,
                                               cur.states, cur.seg_s, v->load, uab, t_snap, &snap);
    }
    if (tr->uab_v != NULL) {
        for (i = 0; i < TTYPE_PLANT_N_SEG; ++i) {
            tr->uab_v[7 * j + i] = uab[i];
        }
    }
    if (bad != 0) {
        return -3; /* *state still holds the sample instant of period k */
    }
    if (!(sim_period_finite(&x->motor) && isfinite(x->vo_v))) {
        return -2;
    }

    /* commit period k: the queue moves on */
    state->last_state = last;
    state->last_open = open;
    state->prior_gates_off = state->applied_gates_off;
    state->applied_gates_off = gates_off;
    state->prior_vector = state->applied_vector;
    state->prior_t_n_s = state->applied_t_n_s;
    state->applied_vector = dec.vector;
    state->applied_t_n_s = dec.t_n_s;
    for (i = 0; i < TTYPE_PLANT_N_SEG; ++i) {
        state->prior_states[i] = state->applied_states[i];
        state->prior_seg_s[i] = state->applied_seg_s[i];
        state->applied_states[i] = dec.states[i];
        state->applied_seg_s[i] = dec.seg_s[i];
    }
    state->vo_v = x->vo_v;
    if (t_snap >= 0.0) {
        state->sampled_vo_v = snap.vo_v;
    }
    sim_period_commit(&p->common, &state->common, &x->motor, t_snap >= 0.0 ? &snap.motor : NULL, v);
    return 0;
}

/* ttype_sim_run, ttype_sim_hil_input and ttype_sim_hil_finish (sim_period.h) */
SIM_PERIOD_ENTRY_POINTS(ttype_sim, ttype_plant_state_t)
