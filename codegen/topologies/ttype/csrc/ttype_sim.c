/*
 * sim3l.c -- closed-loop T-type three-level PMSM drive: float64 plant
 * (plant3l.c) + the generated float32 controller step (through
 * mpc_binding.h), with the speed PI, sampling and one-step-delay timing of
 * sim3l_api.h (where the period-by-period algorithm is documented).
 *
 * Specification: shared/spec/plant-and-metrics.md "Plant" and
 * shared/spec/mpdtc-three-level.md.  mpc_binding.h is generated per config
 * and provides mpc_input_t, mpc_output_t and MPC_STEP(in_ptr, out_ptr).
 */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "sim3l_api.h"
#include "plant3l.h"
#include "pmsm_dq.h"
#include "speed_pi.h"
#include "mpc_binding.h"

#define SIM3L_OOO 13
#define SIM3L_N_VECTORS 63

static void plant_params(const sim3l_params_t *p, plant3l_params_t *pp)
{
    pp->rs_ohm = p->rs_ohm;
    pp->ld_h = p->ld_h;
    pp->lq_h = p->lq_h;
    pp->psi_f_wb = p->psi_f_wb;
    pp->pole_pairs = p->pole_pairs;
    pp->j_kgm2 = p->j_kgm2;
    pp->b_nms = p->b_nms;
    pp->udc_v = p->udc_v;
    pp->c_f = p->c_f;
}

static int params_valid(const sim3l_params_t *p)
{
    if (p == NULL) {
        return 0;
    }
    return pmsm_dq_sim_params_valid(p->rs_ohm, p->ld_h, p->lq_h, p->psi_f_wb, p->pole_pairs,
                                    p->j_kgm2, p->b_nms, p->udc_v, p->dt_s, p->kp, p->ki,
                                    p->limit_nm, p->speed_imposed)
           && pmsm_dq_finite_positive(p->c_f) && pmsm_dq_finite_positive(p->substep_max_s);
}

int sim3l_init(const sim3l_params_t *p, sim3l_state_t *state)
{
    int i;
    if (state == NULL || !params_valid(p)) {
        return -1;
    }
    memset(state, 0, sizeof *state);
    state->applied_vector = SIM3L_OOO;
    state->applied_t_n_s = 0.0;
    for (i = 0; i < PLANT3L_N_SEG; ++i) {
        state->applied_states[i] = SIM3L_OOO;
        state->applied_seg_s[i] = 0.0;
    }
    state->applied_seg_s[0] = p->dt_s;
    state->last_state = SIM3L_OOO;
    state->k = 0;
    return 0;
}

/* Sum of |S_x(to) - S_x(from)| over the three legs. */
static unsigned leg_steps(int from, int to)
{
    int a[3], b[3], i;
    unsigned n = 0u;
    if (plant3l_levels(from, a) != 0 || plant3l_levels(to, b) != 0) {
        return 0u;
    }
    for (i = 0; i < 3; ++i) {
        const int d = a[i] - b[i];
        n += (unsigned)(d < 0 ? -d : d);
    }
    return n;
}

/* v in [0, n) (a function, so that unsigned fields do not trip -Wtype-limits) */
static int in_range(long v, long n)
{
    return v >= 0 && v < n;
}

/* Validate the decision and convert it to the double segment times of the
 * next period (sim3l_api.h step 6).  Returns 0 or -1. */
static int take_decision(const sim3l_params_t *p, const mpc_output_t *out,
                         unsigned short st[7], double seg[7])
{
    double sum = 0.0, rest = 0.0;
    int i, last = -1;
    if (!in_range((long)out->vector, SIM3L_N_VECTORS)) {
        return -1;
    }
    for (i = 0; i < PLANT3L_N_SEG; ++i) {
        const double d = (double)out->seg_s[i];
        if (!in_range((long)out->states[i], PLANT3L_N_STATES) || !isfinite(d) || d < 0.0) {
            return -1;
        }
        st[i] = (unsigned short)out->states[i];
        seg[i] = d;
        sum += d;
        if (d > 0.0) {
            last = i;
        }
    }
    if (last < 0 || !(fabs(sum - p->dt_s) <= 1e-4 * p->dt_s)) {
        return -1;
    }
    for (i = 0; i < PLANT3L_N_SEG; ++i) {
        if (i != last) {
            rest += seg[i];
        }
    }
    seg[last] = p->dt_s - rest;
    return (seg[last] > 0.0) ? 0 : -1;
}

int sim3l_run(const sim3l_params_t *p, const double *speed_ref_rad_s, const double *load_nm,
              long n, sim3l_trace_t *trace, sim3l_state_t *state)
{
    plant3l_params_t pp;
    plant3l_state_t x;
    sim3l_trace_t tr;
    const double pole_pairs = (p != NULL) ? (double)p->pole_pairs : 0.0;
    long j;
    int i;

    if (!params_valid(p) || state == NULL || n < 0 || (n > 0 && (speed_ref_rad_s == NULL || load_nm == NULL))
        || state->applied_vector < 0 || state->applied_vector >= SIM3L_N_VECTORS
        || state->last_state < 0 || state->last_state >= PLANT3L_N_STATES || state->k < 0) {
        return -1;
    }
    for (i = 0; i < PLANT3L_N_SEG; ++i) {
        if (state->applied_states[i] >= PLANT3L_N_STATES || !isfinite(state->applied_seg_s[i])
            || state->applied_seg_s[i] < 0.0) {
            return -1;
        }
    }
    if (trace != NULL) {
        tr = *trace;
    } else {
        memset(&tr, 0, sizeof tr);
    }
    plant_params(p, &pp);
    x.i_d_a = state->i_d_a;
    x.i_q_a = state->i_q_a;
    x.omega_m_rad_s = state->omega_m_rad_s;
    x.theta_e_rad = state->theta_e_rad;
    x.vo_v = state->vo_v;

    for (j = 0; j < n; ++j) {
        mpc_input_t in;
        mpc_output_t out;
        double ia, ib, th, t_ref, w_ref, load, uc1, uc2;
        double integral = state->pi_integral_nm;
        double uab[7], next_seg[7];
        unsigned short next_st[7];
        unsigned changes = 0u;
        int prev, last, bad;

        w_ref = speed_ref_rad_s[j];
        load = load_nm[j];

        /* 1. imposed speed */
        if (p->speed_imposed) {
            x.omega_m_rad_s = w_ref;
        }

        /* 2. sample the plant at t_k */
        plant3l_phase_currents(&x, &ia, &ib);
        th = plant3l_wrap_angle(x.theta_e_rad);
        uc1 = 0.5 * p->udc_v + x.vo_v;
        uc2 = 0.5 * p->udc_v - x.vo_v;

        /* 3. torque reference */
        if (p->speed_imposed) {
            t_ref = load;
        } else {
            t_ref = speed_pi_step(p->kp, p->ki, p->dt_s, p->limit_nm, &integral, w_ref,
                                  x.omega_m_rad_s);
        }

        /* 4. controller step, inputs cast to float */
        memset(&in, 0, sizeof in);
        memset(&out, 0, sizeof out);
        in.ia_a = (float)ia;
        in.ib_a = (float)ib;
        in.theta_e_rad = (float)th;
        in.omega_e_rad_s = (float)(pole_pairs * x.omega_m_rad_s);
        in.uc1_v = (float)uc1;
        in.uc2_v = (float)uc2;
        in.torque_ref_nm = (float)t_ref;
        in.prev_vector = (uint16_t)state->applied_vector;
        in.t_n_prev_s = (float)state->applied_t_n_s;
        MPC_STEP(&in, &out);

        /* leg-level changes of the applied period (non-empty segments only) */
        prev = state->last_state;
        last = prev;
        for (i = 0; i < PLANT3L_N_SEG; ++i) {
            if (state->applied_seg_s[i] > 0.0) {
                changes += leg_steps(prev, (int)state->applied_states[i]);
                prev = (int)state->applied_states[i];
                last = prev;
            }
        }

        /* 5. record the sample instant, the decision, the applied period */
        if (tr.t_s != NULL) tr.t_s[j] = (double)state->k * p->dt_s;
        if (tr.speed_ref_rad_s != NULL) tr.speed_ref_rad_s[j] = w_ref;
        if (tr.omega_m_rad_s != NULL) tr.omega_m_rad_s[j] = x.omega_m_rad_s;
        if (tr.te_nm != NULL) tr.te_nm[j] = plant3l_torque(&x, &pp);
        if (tr.torque_ref_nm != NULL) tr.torque_ref_nm[j] = t_ref;
        if (tr.psi_wb != NULL) tr.psi_wb[j] = plant3l_flux(&x, &pp);
        if (tr.ia_a != NULL) tr.ia_a[j] = ia;
        if (tr.ib_a != NULL) tr.ib_a[j] = ib;
        if (tr.ic_a != NULL) tr.ic_a[j] = -ia - ib;
        if (tr.theta_e_rad != NULL) tr.theta_e_rad[j] = th;
        if (tr.vo_v != NULL) tr.vo_v[j] = x.vo_v;
        if (tr.vector != NULL) tr.vector[j] = (unsigned short)out.vector;
        if (tr.n_eval != NULL) tr.n_eval[j] = (unsigned short)out.n_eval;
        if (tr.fault != NULL) tr.fault[j] = (unsigned short)out.fault;
        if (tr.t_n_s != NULL) tr.t_n_s[j] = out.t_n_s;
        if (tr.te_est_nm != NULL) tr.te_est_nm[j] = out.te_est_nm;
        if (tr.psi_est_wb != NULL) tr.psi_est_wb[j] = out.psi_est_wb;
        if (tr.psi_ref_wb != NULL) tr.psi_ref_wb[j] = out.psi_ref_wb;
        if (tr.vo_est_v != NULL) tr.vo_est_v[j] = out.vo_v;
        if (tr.applied_vector != NULL) tr.applied_vector[j] = (unsigned short)state->applied_vector;
        if (tr.leg_changes != NULL) tr.leg_changes[j] = (unsigned short)changes;
        for (i = 0; i < PLANT3L_N_SEG; ++i) {
            if (tr.seg_s != NULL) tr.seg_s[7 * j + i] = state->applied_seg_s[i];
            if (tr.seg_states != NULL) tr.seg_states[7 * j + i] = state->applied_states[i];
        }

        /* 6. check the decision */
        bad = take_decision(p, &out, next_st, next_seg);

        /* 7. integrate the applied period over [t_k, t_k+1) */
        (void)plant3l_advance_segments(&x, &pp, state->applied_states, state->applied_seg_s, load,
                                       p->substep_max_s, p->speed_imposed, uab);
        if (tr.uab_v != NULL) {
            for (i = 0; i < PLANT3L_N_SEG; ++i) {
                tr.uab_v[7 * j + i] = uab[i];
            }
        }
        if (bad != 0) {
            return -3; /* *state still holds the sample instant of period k */
        }
        if (!(isfinite(x.i_d_a) && isfinite(x.i_q_a) && isfinite(x.omega_m_rad_s)
              && isfinite(x.theta_e_rad) && isfinite(x.vo_v))) {
            return -2;
        }

        /* commit period k */
        state->last_state = last;
        state->applied_vector = (int)out.vector;
        state->applied_t_n_s = (double)out.t_n_s;
        for (i = 0; i < PLANT3L_N_SEG; ++i) {
            state->applied_states[i] = next_st[i];
            state->applied_seg_s[i] = next_seg[i];
        }
        state->pi_integral_nm = integral;
        state->i_d_a = x.i_d_a;
        state->i_q_a = x.i_q_a;
        state->omega_m_rad_s = x.omega_m_rad_s;
        state->theta_e_rad = x.theta_e_rad;
        state->vo_v = x.vo_v;
        state->k += 1;
    }
    return 0;
}
