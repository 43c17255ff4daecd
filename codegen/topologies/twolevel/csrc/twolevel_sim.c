/*
 * sim2l.c -- closed-loop two-level PMSM drive: float64 plant (plant2l.c) +
 * the generated float32 controller step (through mpc_binding.h), with the
 * speed PI, sampling and switching timing of sim2l_api.h.
 *
 * Specification: shared/spec/plant-and-metrics.md "Plant" (sampling at the
 * start of each period, timing of delay_compensation, speed loop) and
 * shared/spec/mptc-two-level.md "Parameters and scenarios" (speed PI on the
 * mechanical speed error in rad/s, clamped output with anti-windup).
 * The period-by-period algorithm is documented in sim2l_api.h.
 *
 * mpc_binding.h is generated per config and provides mpc_input_t,
 * mpc_output_t and the macro MPC_STEP(in_ptr, out_ptr).
 */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "sim2l_api.h"
#include "plant2l.h"
#include "pmsm_dq.h"
#include "speed_pi.h"
#include "mpc_binding.h"

static void plant_params(const sim2l_params_t *p, plant2l_params_t *pp)
{
    pp->rs_ohm = p->rs_ohm;
    pp->ld_h = p->ld_h;
    pp->lq_h = p->lq_h;
    pp->psi_f_wb = p->psi_f_wb;
    pp->pole_pairs = p->pole_pairs;
    pp->j_kgm2 = p->j_kgm2;
    pp->b_nms = p->b_nms;
    pp->udc_v = p->udc_v;
}

static int params_valid(const sim2l_params_t *p)
{
    if (p == NULL) {
        return 0;
    }
    return pmsm_dq_sim_params_valid(p->rs_ohm, p->ld_h, p->lq_h, p->psi_f_wb, p->pole_pairs,
                                    p->j_kgm2, p->b_nms, p->udc_v, p->dt_s, p->kp, p->ki,
                                    p->limit_nm, p->speed_imposed)
           && p->substeps >= 1;
}

int sim2l_init(const sim2l_params_t *p, sim2l_state_t *state)
{
    if (state == NULL || !params_valid(p)) {
        return -1;
    }
    state->i_d_a = 0.0;
    state->i_q_a = 0.0;
    state->omega_m_rad_s = 0.0;
    state->theta_e_rad = 0.0;
    state->pi_integral_nm = 0.0;
    state->prev_sw = 0;
    state->k = 0;
    return 0;
}

int sim2l_run(const sim2l_params_t *p, const double *speed_ref_rad_s, const double *load_nm,
              long n, sim2l_trace_t *trace, sim2l_state_t *state)
{
    plant2l_params_t pp;
    plant2l_state_t x;
    sim2l_trace_t tr;
    const double pole_pairs = (p != NULL) ? (double)p->pole_pairs : 0.0;
    long j;

    if (!params_valid(p) || state == NULL || n < 0 || (n > 0 && (speed_ref_rad_s == NULL || load_nm == NULL))
        || state->prev_sw < 0 || state->prev_sw > 7 || state->k < 0) {
        return -1;
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

    for (j = 0; j < n; ++j) {
        mpc_input_t in;
        mpc_output_t out;
        double ia, ib, th, t_ref, w_ref, load;
        double integral = state->pi_integral_nm;
        int sw_dec, sw_apply;

        w_ref = speed_ref_rad_s[j];
        load = load_nm[j];

        /* 1. imposed speed: the load machine holds the profile */
        if (p->speed_imposed) {
            x.omega_m_rad_s = w_ref;
        }

        /* 2. sample the plant at t_k (plant-and-metrics.md "Sampling") */
        plant2l_phase_currents(&x, &ia, &ib);
        th = plant2l_theta_e(&x);

        /* 3. torque reference */
        if (p->speed_imposed) {
            t_ref = load;
        } else {
            t_ref = speed_pi_step(p->kp, p->ki, p->dt_s, p->limit_nm, &integral, w_ref,
                                  x.omega_m_rad_s);
        }

        /* 4. controller step, inputs cast to float as a real controller sees them */
        memset(&in, 0, sizeof in);
        memset(&out, 0, sizeof out);
        in.ia_a = (float)ia;
        in.ib_a = (float)ib;
        in.theta_e_rad = (float)th;
        in.omega_e_rad_s = (float)(pole_pairs * x.omega_m_rad_s);
        in.udc_v = (float)p->udc_v;
        in.torque_ref_nm = (float)t_ref;
        in.prev_sw = (unsigned short)state->prev_sw;
        MPC_STEP(&in, &out);
        sw_dec = (int)out.sw;

        /* 6. timing rule (plant-and-metrics.md "Timing") */
        sw_apply = p->delay_compensation ? state->prev_sw : sw_dec;

        /* 5. record the sample instant */
        if (tr.t_s != NULL) tr.t_s[j] = (double)state->k * p->dt_s;
        if (tr.speed_ref_rad_s != NULL) tr.speed_ref_rad_s[j] = w_ref;
        if (tr.omega_m_rad_s != NULL) tr.omega_m_rad_s[j] = x.omega_m_rad_s;
        if (tr.te_nm != NULL) tr.te_nm[j] = plant2l_torque(&x, &pp);
        if (tr.torque_ref_nm != NULL) tr.torque_ref_nm[j] = t_ref;
        if (tr.psi_wb != NULL) tr.psi_wb[j] = plant2l_flux(&x, &pp);
        if (tr.ia_a != NULL) tr.ia_a[j] = ia;
        if (tr.ib_a != NULL) tr.ib_a[j] = ib;
        if (tr.theta_e_rad != NULL) tr.theta_e_rad[j] = th;
        if (tr.sw != NULL) tr.sw[j] = (unsigned short)out.sw;
        if (tr.applied_sw != NULL) tr.applied_sw[j] = (unsigned short)(sw_apply & 0xFFFF);
        if (tr.vector != NULL) tr.vector[j] = (unsigned short)out.vector;
        if (tr.n_eval != NULL) tr.n_eval[j] = (unsigned short)out.n_eval;
        if (tr.fault != NULL) tr.fault[j] = (unsigned short)out.fault;
        if (tr.te_est_nm != NULL) tr.te_est_nm[j] = out.te_est_nm;
        if (tr.psi_est_wb != NULL) tr.psi_est_wb[j] = out.psi_est_wb;

        if (sw_dec < 0 || sw_dec > 7) {
            state->i_d_a = x.i_d_a;
            state->i_q_a = x.i_q_a;
            state->omega_m_rad_s = x.omega_m_rad_s;
            state->theta_e_rad = x.theta_e_rad;
            return -3;
        }

        /* 7. integrate the plant over [t_k, t_k+1) */
        (void)plant2l_advance(&x, &pp, sw_apply, load, p->dt_s, p->substeps, p->speed_imposed);
        if (!(isfinite(x.i_d_a) && isfinite(x.i_q_a) && isfinite(x.omega_m_rad_s)
              && isfinite(x.theta_e_rad))) {
            return -2; /* *state still holds the sample instant of period k */
        }
        /* commit period k */
        state->prev_sw = sw_dec;
        state->pi_integral_nm = integral;
        state->i_d_a = x.i_d_a;
        state->i_q_a = x.i_q_a;
        state->omega_m_rad_s = x.omega_m_rad_s;
        state->theta_e_rad = x.theta_e_rad;
        state->k += 1;
    }
    return 0;
}
