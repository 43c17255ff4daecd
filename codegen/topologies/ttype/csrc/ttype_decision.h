/*
 * ttype_decision.h -- one decision of the T-type step as the plant applies
 * it, written once on sim_real_t (sim_real.h): float64 in the host
 * simulator (ttype_sim.c), float32 in the firmware's on-board loop
 * (ttype_onboard.c) (hand-written runtime).
 *
 * A decision is the vector, its T_N and its seven segments (state 0..26,
 * duration).  ttype_decision_take checks the step's output and converts it
 * (docs/simulation.md "Timing"): vector <= 62, states[i] <= 26, seg_s[i]
 * finite and >= 0, |sum seg_s - dt_s| <= 1e-4*dt_s; the last non-empty
 * segment is set to dt_s minus the sum of the others, so that the plant's
 * period is dt_s (the step's float32 sum is off by ~1e-7 relative).
 *
 * Include after the generated mpc_binding.h (mpc_output_t, MPC_DECODE_*).
 * C99, no dynamic memory, no global state.  Not part of any cffi cdef.
 */
#ifndef TTYPE_DECISION_H
#define TTYPE_DECISION_H

#include <math.h>
#include <stdint.h>

#include "sim_real.h"
#include "ttype_rhs.h"

/* Segments of one control period (seven-segment virtual vectors). */
#define TTYPE_DECISION_N_SEG 7
/* Vectors of the step. */
#define TTYPE_DECISION_N_VECTORS 63
/* The zero vector and zero state OOO (the inverter before the first decisions). */
#define TTYPE_DECISION_OOO 13

/* One decision: vector, T_N, and its 7 segments. */
typedef struct {
    int32_t vector;
    sim_real_t t_n_s;
    uint16_t states[TTYPE_DECISION_N_SEG];
    sim_real_t seg_s[TTYPE_DECISION_N_SEG];
} ttype_decision_t;

/* v in [0, n) (a function, so that unsigned fields do not trip -Wtype-limits) */
static inline int ttype_decision_in_range(long v, long n)
{
    return v >= 0 && v < n;
}

/* OOO over the whole period dt_s, T_N = 0: the decision before the first ones. */
static inline void ttype_decision_idle(ttype_decision_t *dec, sim_real_t dt_s)
{
    int i;
    dec->vector = TTYPE_DECISION_OOO;
    dec->t_n_s = SIM_R(0.0);
    for (i = 0; i < TTYPE_DECISION_N_SEG; ++i) {
        dec->states[i] = TTYPE_DECISION_OOO;
        dec->seg_s[i] = SIM_R(0.0);
    }
    dec->seg_s[0] = dt_s;
}

/* Check the step's output `out` and convert it into *dec (see the header comment; an invalid
 * decision leaves the states OOO and the durations 0 from the first bad field on).  0 or -1. */
static inline int ttype_decision_take(const mpc_output_t *out, sim_real_t dt_s, ttype_decision_t *dec)
{
    uint16_t *st = dec->states;
    sim_real_t *seg = dec->seg_s;
    sim_real_t sum = SIM_R(0.0), rest = SIM_R(0.0);
    int i, last = -1;
    dec->vector = (int32_t)out->vector;
    dec->t_n_s = (sim_real_t)MPC_DECODE_t_n_s(out->t_n_s);
    for (i = 0; i < TTYPE_DECISION_N_SEG; ++i) {
        st[i] = TTYPE_DECISION_OOO;
        seg[i] = SIM_R(0.0);
    }
    if (!ttype_decision_in_range((long)out->vector, TTYPE_DECISION_N_VECTORS)) {
        return -1;
    }
    for (i = 0; i < TTYPE_DECISION_N_SEG; ++i) {
        const sim_real_t d = (sim_real_t)MPC_DECODE_seg_s(out->seg_s[i]);
        if (!ttype_decision_in_range((long)out->states[i], TTYPE_RHS_N_STATES) || !isfinite(d)
            || d < SIM_R(0.0)) {
            return -1;
        }
        st[i] = (uint16_t)out->states[i];
        seg[i] = d;
        sum += d;
        if (d > SIM_R(0.0)) {
            last = i;
        }
    }
    if (last < 0 || !(SIM_FABS(sum - dt_s) <= SIM_R(1e-4) * dt_s)) {
        return -1;
    }
    for (i = 0; i < TTYPE_DECISION_N_SEG; ++i) {
        if (i != last) {
            rest += seg[i];
        }
    }
    seg[last] = dt_s - rest;
    return (seg[last] > SIM_R(0.0)) ? 0 : -1;
}

#endif /* TTYPE_DECISION_H */
