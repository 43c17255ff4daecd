/*
 * onboard_ttype.c -- the T-type three-level part of the on-board plant (see
 * onboard.h), after ttype_plant.c / ttype_sim.c: the controller's u_c1,
 * u_c2 (0.5*Udc +- V_o), prev_vector and t_n_prev_s; one-step delay
 * compensation (the decision of k is applied during [t_k+1, t_k+2), OOO
 * before the first); the applied period is its 7 segments (state, time),
 * the last non-empty segment taking dt minus the others.  State s = 9*(Sa+1)
 * + 3*(Sb+1) + (Sc+1), S in {-1, 0, 1}; u_xo = S*Udc/2 + |S|*V_o; the
 * neutral point has two capacitors C: dV_o/dt = i_o/(2C),
 * i_o = -sum |S_x|*i_x.
 */
#include "onboard.h"
#include "onboard_config.h"

/* This plant applies the decision of k one period late (the delay the T-type step compensates);
 * the host comparison runs the same timing (hil/onboard.py). */
#if ONB_DELAY_COMPENSATION == 0
#error "on-board T-type plant: the step compensates a one-period delay; set controller.delay_compensation = true"
#endif

#define ONB_OOO 13u
#define ONB_N_VECTORS 63u
#define ONB_N_STATES 27u
#define ONB_N_SEG 7u
#define ONB_SQRT3_INV 0.57735027f
#define ONB_SQRT3_HALF_T 0.8660254f

static uint16_t applied_vector;
/* the applied decision's t_n_s, in the step's number format (fed back as t_n_prev_s) */
static mpc_output_t applied_out;
static uint16_t applied_states[ONB_N_SEG];
static float applied_seg[ONB_N_SEG];

void onb_topo_reset(void)
{
    uint16_t i;
    applied_vector = ONB_OOO;
    applied_out.t_n_s = MPC_ENCODE_t_n_s(0.0f);
    for (i = 0u; i < ONB_N_SEG; ++i) {
        applied_states[i] = ONB_OOO;
        applied_seg[i] = 0.0f;
    }
    applied_seg[0] = ONB_DT;
}

void onb_topo_input(const onb_plant_t *p, mpc_input_t *in)
{
    in->uc1_v = MPC_ENCODE_uc1_v(0.5f * ONB_UDC + p->x[4]);
    in->uc2_v = MPC_ENCODE_uc2_v(0.5f * ONB_UDC - p->x[4]);
    in->prev_vector = applied_vector;
    in->t_n_prev_s = applied_out.t_n_s;
}

uint16_t onb_topo_decision(const mpc_output_t *out)
{
    return out->vector;
}

static float level(uint16_t state, uint16_t leg)
{
    uint16_t d = (leg == 0u) ? (uint16_t)(state / 9u) : (leg == 1u) ? (uint16_t)((state / 3u) % 3u)
                                                                     : (uint16_t)(state % 3u);
    return (float)d - 1.0f;
}

static void segment_of(uint16_t state, onb_segment_t *c)
{
    const float sa = level(state, 0u), sb = level(state, 1u), sc = level(state, 2u);
    const float aa = (sa != 0.0f) ? 1.0f : 0.0f, ab = (sb != 0.0f) ? 1.0f : 0.0f, ac = (sc != 0.0f) ? 1.0f : 0.0f;
    const float half = 0.5f * ONB_UDC;
    c->ua0 = (2.0f / 3.0f) * half * (sa - 0.5f * (sb + sc));
    c->ua1 = (2.0f / 3.0f) * (aa - 0.5f * (ab + ac));
    c->ub0 = half * ONB_SQRT3_INV * (sb - sc);
    c->ub1 = ONB_SQRT3_INV * (ab - ac);
    c->ka = -(aa - 0.5f * (ab + ac)) * (1.0f / (2.0f * ONB_C_F));
    c->kb = -ONB_SQRT3_HALF_T * (ab - ac) * (1.0f / (2.0f * ONB_C_F));
    c->zero = (uint16_t)(sa == sb && sb == sc);
}

int16_t onb_topo_apply(onb_plant_t *p, const mpc_output_t *out, float load_nm)
{
    const float hmax = ONB_DT / (float)ONB_SUBSTEPS;
    float sum = 0.0f, rest = 0.0f, next_seg[ONB_N_SEG];
    uint16_t i, last = ONB_N_SEG, bad = 0u;
    /* the applied period */
    for (i = 0u; i < ONB_N_SEG; ++i) {
        const float d = applied_seg[i];
        if (d > 0.0f) {
            onb_segment_t seg;
            uint16_t n = (uint16_t)(d / hmax);
            if ((float)n * hmax < d * 0.999f) {
                ++n;
            }
            if (n < 1u) {
                n = 1u;
            }
            segment_of(applied_states[i], &seg);
            onb_advance(p, &seg, load_nm, d, n);
        }
    }
    /* check and take the decision (applied in the next period) */
    if (out->vector >= ONB_N_VECTORS) {
        bad = 1u;
    }
    for (i = 0u; i < ONB_N_SEG; ++i) {
        const float d = (float)MPC_DECODE_seg_s(out->seg_s[i]);
        if (out->states[i] >= ONB_N_STATES || !(d >= 0.0f && d <= ONB_DT * 2.0f)) {
            bad = 1u;
        }
        next_seg[i] = d;
        sum += d;
        if (d > 0.0f) {
            last = i;
        }
    }
    if (bad != 0u || last == ONB_N_SEG || !(sum - ONB_DT <= 1e-4f * ONB_DT && ONB_DT - sum <= 1e-4f * ONB_DT)) {
        return -3;
    }
    for (i = 0u; i < ONB_N_SEG; ++i) {
        if (i != last) {
            rest += next_seg[i];
        }
    }
    next_seg[last] = ONB_DT - rest;
    if (!(next_seg[last] > 0.0f)) {
        return -3;
    }
    applied_vector = out->vector;
    applied_out.t_n_s = out->t_n_s;
    for (i = 0u; i < ONB_N_SEG; ++i) {
        applied_states[i] = out->states[i];
        applied_seg[i] = next_seg[i];
    }
    return 0;
}
