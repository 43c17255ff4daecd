/*
 * sim_period.c -- the period steps every closed-loop simulator shares (see
 * sim_period.h for the algorithm and its specification).
 */
#include "sim_period.h"

#include <math.h>
#include <stddef.h>

#include "pmsm_dq.h"
#include "speed_pi.h"

int sim_period_params_valid(const sim_params_t *p)
{
    if (p == NULL) {
        return 0;
    }
    return pmsm_dq_sim_params_valid(p->rs_ohm, p->ld_h, p->lq_h, p->psi_f_wb, p->pole_pairs,
                                    p->j_kgm2, p->b_nms, p->udc_v, p->dt_s, p->kp, p->ki,
                                    p->limit_nm, p->speed_imposed);
}

void sim_period_reset(sim_state_t *s)
{
    s->motor.i_d_a = 0.0;
    s->motor.i_q_a = 0.0;
    s->motor.omega_m_rad_s = 0.0;
    s->motor.theta_e_rad = 0.0;
    s->pi_integral_nm = 0.0;
    s->k = 0;
}

int sim_period_args_valid(const sim_state_t *s, long n, const double *speed_ref_rad_s,
                          const double *load_nm)
{
    return s != NULL && n >= 0 && (n == 0 || (speed_ref_rad_s != NULL && load_nm != NULL))
           && s->k >= 0;
}

void sim_period_sample(const sim_params_t *p, const sim_state_t *s, pmsm_state_t *x,
                       double w_ref, double load, sim_sample_t *out)
{
    out->w_ref = w_ref;
    out->load = load;
    out->integral = s->pi_integral_nm;

    /* 1. imposed speed: the load machine holds the profile */
    if (p->speed_imposed) {
        x->omega_m_rad_s = w_ref;
    }

    /* 2. sample the plant at t_k (plant-and-metrics.md "Sampling") */
    pmsm_dq_phase_currents(x->i_d_a, x->i_q_a, x->theta_e_rad, &out->ia, &out->ib);
    out->th = pmsm_dq_wrap_angle(x->theta_e_rad);
    out->omega_e = (double)p->pole_pairs * x->omega_m_rad_s;

    /* 3. torque reference: load torque (speed imposed) or the speed PI */
    if (p->speed_imposed) {
        out->t_ref = load;
    } else {
        out->t_ref = speed_pi_step(p->kp, p->ki, p->dt_s, p->limit_nm, &out->integral, w_ref,
                                   x->omega_m_rad_s);
    }
}

void sim_period_record(const sim_trace_t *tr, long j, const sim_params_t *p, const sim_state_t *s,
                       const pmsm_state_t *x, const sim_sample_t *v, uint16_t vector,
                       uint16_t n_eval, uint16_t fault, float te_est_nm, float psi_est_wb)
{
    if (tr->t_s != NULL) tr->t_s[j] = (double)s->k * p->dt_s;
    if (tr->speed_ref_rad_s != NULL) tr->speed_ref_rad_s[j] = v->w_ref;
    if (tr->omega_m_rad_s != NULL) tr->omega_m_rad_s[j] = x->omega_m_rad_s;
    if (tr->te_nm != NULL) {
        tr->te_nm[j] = pmsm_dq_torque(x->i_d_a, x->i_q_a, p->ld_h, p->lq_h, p->psi_f_wb, p->pole_pairs);
    }
    if (tr->torque_ref_nm != NULL) tr->torque_ref_nm[j] = v->t_ref;
    if (tr->psi_wb != NULL) tr->psi_wb[j] = pmsm_dq_flux(x->i_d_a, x->i_q_a, p->ld_h, p->lq_h, p->psi_f_wb);
    if (tr->ia_a != NULL) tr->ia_a[j] = v->ia;
    if (tr->ib_a != NULL) tr->ib_a[j] = v->ib;
    if (tr->ic_a != NULL) tr->ic_a[j] = -v->ia - v->ib; /* isolated star point */
    if (tr->theta_e_rad != NULL) tr->theta_e_rad[j] = v->th;
    if (tr->vector != NULL) tr->vector[j] = vector;
    if (tr->n_eval != NULL) tr->n_eval[j] = n_eval;
    if (tr->fault != NULL) tr->fault[j] = fault;
    if (tr->te_est_nm != NULL) tr->te_est_nm[j] = te_est_nm;
    if (tr->psi_est_wb != NULL) tr->psi_est_wb[j] = psi_est_wb;
}

int sim_period_finite(const pmsm_state_t *x)
{
    return isfinite(x->i_d_a) && isfinite(x->i_q_a) && isfinite(x->omega_m_rad_s)
           && isfinite(x->theta_e_rad);
}

void sim_period_commit(sim_state_t *s, const pmsm_state_t *x, double integral)
{
    s->pi_integral_nm = integral;
    s->motor = *x;
    s->k += 1;
}
