/*
 * sim_period.c -- the period steps every closed-loop simulator shares (see
 * sim_period.h for the algorithm and its specification).
 */
#include "sim_period.h"

#include <math.h>
#include <stddef.h>

#include "pmsm_dq.h"
#include "sim_exact.h"
#include "sim_sensors.h"
#include "speed_pi.h"

static int finite_nonneg(double x)
{
    return isfinite(x) && x >= 0.0;
}

int sim_period_plant_valid(const sim_params_t *p)
{
    return p->delay_periods >= 0 && p->delay_periods <= SIM_PERIOD_MAX_DELAY
           && finite_nonneg(p->dead_time_s) && p->dead_time_s < p->dt_s
           && finite_nonneg(p->device_drop_v)
           && isfinite(p->current_gain_error) && p->current_gain_error > -1.0
           && isfinite(p->current_offset_a)
           && p->adc_bits >= 0 && p->adc_bits <= 30
           && (p->adc_bits == 0 || pmsm_dq_finite_positive(p->adc_full_scale_a))
           && finite_nonneg(p->noise_a)
           && p->encoder_bits >= 0 && p->encoder_bits <= 30
           && finite_nonneg(p->measurement_delay_s) && p->measurement_delay_s <= p->dt_s
           && (p->integrator == SIM_INTEGRATOR_RK4 || p->integrator == SIM_INTEGRATOR_EXACT);
}

int sim_period_params_valid(const sim_params_t *p)
{
    if (p == NULL) {
        return 0;
    }
    return pmsm_dq_sim_params_valid(p->rs_ohm, p->ld_h, p->lq_h, p->psi_f_wb, p->pole_pairs,
                                    p->j_kgm2, p->b_nms, p->udc_v, p->dt_s, p->kp, p->ki,
                                    p->limit_nm, p->speed_imposed)
           && sim_period_plant_valid(p);
}

void sim_period_reset(sim_state_t *s)
{
    int i;
    s->motor.i_d_a = 0.0;
    s->motor.i_q_a = 0.0;
    s->motor.omega_m_rad_s = 0.0;
    s->motor.theta_e_rad = 0.0;
    s->sampled = s->motor;
    s->pi_integral_nm = 0.0;
    s->k = 0;
    s->theta_m_rad = 0.0;
    s->sampled_theta_m_rad = 0.0;
    for (i = 0; i < SIM_SENSORS_ENC_WINDOW; ++i) {
        s->enc_counts[i] = 0;
    }
}

int sim_period_args_valid(const sim_state_t *s, long n, const double *speed_ref_rad_s,
                          const double *load_nm)
{
    return s != NULL && n >= 0 && (n == 0 || (speed_ref_rad_s != NULL && load_nm != NULL))
           && s->k >= 0;
}

int sim_period_delayed(const sim_params_t *p, const sim_state_t *s)
{
    return p->measurement_delay_s > 0.0 && s->k > 0;
}

double sim_period_snap_offset(const sim_params_t *p)
{
    return p->measurement_delay_s > 0.0 ? p->dt_s - p->measurement_delay_s : -1.0;
}

/* Step 2, what the controller sees of the plant m (at t_k or t_k - tau) whose mechanical angle
 * is theta_m: currents through the sensors, angle and speed through the encoder. */
static void measure(const sim_params_t *p, const sim_state_t *s, const pmsm_state_t *m,
                    double theta_m, sim_sample_t *out)
{
    if (m != NULL) { /* the kept (delayed) state; else the plant at t_k, already in out */
        pmsm_dq_phase_currents(m->i_d_a, m->i_q_a, m->theta_e_rad, &out->ia, &out->ib);
        out->th = pmsm_dq_wrap_angle(m->theta_e_rad);
        out->omega_m = m->omega_m_rad_s;
    }
    if (sim_sensors_current_active(p)) {
        double za = 0.0, zb = 0.0;
        if (p->noise_a > 0.0) {
            sim_sensors_noise_pair(p->noise_seed, s->k, &za, &zb);
        }
        out->ia = sim_sensors_current(p, out->ia, za);
        out->ib = sim_sensors_current(p, out->ib, zb);
    }
    out->enc_count = 0;
    if (p->encoder_bits > 0) {
        out->enc_count = sim_sensors_encoder_count(p, theta_m);
        out->th = sim_sensors_encoder_angle(p, out->enc_count);
        out->omega_m = sim_sensors_encoder_speed(p, s, out->enc_count, out->omega_m);
    }
}

void sim_period_sample(const sim_params_t *p, const sim_state_t *s, pmsm_state_t *x,
                       double w_ref, double load, sim_sample_t *out)
{
    const int delayed = sim_period_delayed(p, s);

    out->w_ref = w_ref;
    out->load = load;
    out->integral = s->pi_integral_nm;

    /* 1. imposed speed: the load machine holds the profile */
    if (p->speed_imposed) {
        x->omega_m_rad_s = w_ref;
    }

    /* 2. the plant at t_k (docs/simulation.md "Plant"), and what the controller sees */
    pmsm_dq_phase_currents(x->i_d_a, x->i_q_a, x->theta_e_rad, &out->ia_plant, &out->ib_plant);
    out->th_plant = pmsm_dq_wrap_angle(x->theta_e_rad);
    out->ia = out->ia_plant;
    out->ib = out->ib_plant;
    out->th = out->th_plant;
    out->omega_m = x->omega_m_rad_s;
    measure(p, s, delayed ? &s->sampled : NULL, delayed ? s->sampled_theta_m_rad : s->theta_m_rad,
            out);
    out->omega_e = (double)p->pole_pairs * out->omega_m;

    /* 3. torque reference: load torque (speed imposed) or the speed PI on the measured speed */
    if (p->speed_imposed) {
        out->t_ref = load;
    } else {
        out->t_ref = speed_pi_step(p->kp, p->ki, p->dt_s, p->limit_nm, &out->integral, w_ref,
                                   out->omega_m);
    }
}

void sim_period_record(const sim_trace_t *tr, long j, const sim_params_t *p, const sim_state_t *s,
                       const pmsm_state_t *x, const sim_sample_t *v, uint16_t vector,
                       uint16_t n_eval, uint16_t fault, uint16_t gates_off, int open,
                       float te_est_nm, float psi_est_wb)
{
    if (tr->t_s != NULL) tr->t_s[j] = (double)s->k * p->dt_s;
    if (tr->speed_ref_rad_s != NULL) tr->speed_ref_rad_s[j] = v->w_ref;
    if (tr->omega_m_rad_s != NULL) tr->omega_m_rad_s[j] = x->omega_m_rad_s;
    if (tr->te_nm != NULL) {
        tr->te_nm[j] = pmsm_dq_torque(x->i_d_a, x->i_q_a, p->ld_h, p->lq_h, p->psi_f_wb, p->pole_pairs);
    }
    if (tr->torque_ref_nm != NULL) tr->torque_ref_nm[j] = v->t_ref;
    if (tr->psi_wb != NULL) tr->psi_wb[j] = pmsm_dq_flux(x->i_d_a, x->i_q_a, p->ld_h, p->lq_h, p->psi_f_wb);
    if (tr->ia_a != NULL) tr->ia_a[j] = v->ia_plant;
    if (tr->ib_a != NULL) tr->ib_a[j] = v->ib_plant;
    if (tr->ic_a != NULL) tr->ic_a[j] = -v->ia_plant - v->ib_plant; /* isolated star point */
    if (tr->theta_e_rad != NULL) tr->theta_e_rad[j] = v->th_plant;
    if (tr->ia_meas_a != NULL) tr->ia_meas_a[j] = v->ia;
    if (tr->ib_meas_a != NULL) tr->ib_meas_a[j] = v->ib;
    if (tr->theta_e_meas_rad != NULL) tr->theta_e_meas_rad[j] = v->th;
    if (tr->omega_m_meas_rad_s != NULL) tr->omega_m_meas_rad_s[j] = v->omega_m;
    if (tr->vector != NULL) tr->vector[j] = vector;
    if (tr->n_eval != NULL) tr->n_eval[j] = n_eval;
    if (tr->fault != NULL) tr->fault[j] = fault;
    if (tr->gates_off != NULL) tr->gates_off[j] = gates_off;
    if (tr->inverter_open != NULL) tr->inverter_open[j] = (uint16_t)(open ? 1 : 0);
    if (tr->te_est_nm != NULL) tr->te_est_nm[j] = te_est_nm;
    if (tr->psi_est_wb != NULL) tr->psi_est_wb[j] = psi_est_wb;
}

int sim_period_finite(const pmsm_state_t *x)
{
    return isfinite(x->i_d_a) && isfinite(x->i_q_a) && isfinite(x->omega_m_rad_s)
           && isfinite(x->theta_e_rad);
}

/* theta_m + (the electrical angle's change from th0 to th1, both wrapped, taken in [-pi, pi))/p:
 * the mechanical angle follows the plant's wrapped electrical angle (|change| < pi per period). */
static double advance_theta_m(const sim_params_t *p, double theta_m, double th0, double th1)
{
    double d = th1 - th0;
    d -= PMSM_DQ_TWO_PI * floor((d + 0.5 * PMSM_DQ_TWO_PI) / PMSM_DQ_TWO_PI);
    return theta_m + d / (double)p->pole_pairs;
}

void sim_period_commit(const sim_params_t *p, sim_state_t *s, const pmsm_state_t *x,
                       const pmsm_state_t *snap, const sim_sample_t *v)
{
    const double th0 = s->motor.theta_e_rad;
    s->pi_integral_nm = v->integral;
    s->enc_counts[s->k % SIM_SENSORS_ENC_WINDOW] = v->enc_count;
    if (snap != NULL) {
        s->sampled = *snap;
        s->sampled_theta_m_rad = advance_theta_m(p, s->theta_m_rad, th0, snap->theta_e_rad);
    }
    s->theta_m_rad = advance_theta_m(p, s->theta_m_rad, th0, x->theta_e_rad);
    s->motor = *x;
    s->k += 1;
}
