/*
 * pmsm_dq.c -- PMSM dq model shared by the host plants (see pmsm_dq.h).
 *
 * C99; compiles warning-free with
 *   gcc -std=c99 -O2 -Wall -Wextra -Wconversion -Wdouble-promotion -Werror
 *       -ffp-contract=off
 * (-ffp-contract=off: no fused multiply-add, so every host gives the same
 * bits and chunked runs equal one long run exactly).
 */
#include "pmsm_dq.h"

void pmsm_dq_rhs_setup(pmsm_dq_rhs_t *c, double rs_ohm, double ld_h, double lq_h, double psi_f_wb,
                       int pole_pairs, double j_kgm2, double b_nms, double load_nm,
                       int speed_imposed)
{
    c->inv_ld = 1.0 / ld_h;
    c->rs_ld = rs_ohm / ld_h;
    c->lq_ld = lq_h / ld_h;
    c->inv_lq = 1.0 / lq_h;
    c->rs_lq = rs_ohm / lq_h;
    c->ld_lq = ld_h / lq_h;
    c->psif_lq = psi_f_wb / lq_h;
    c->p = (double)pole_pairs;
    c->kt = 1.5 * c->p;
    c->psi_f = psi_f_wb;
    c->dl = ld_h - lq_h;
    c->mech = speed_imposed ? 0 : 1;
    if (c->mech) {
        c->inv_j = 1.0 / j_kgm2;
        c->b_j = b_nms / j_kgm2;
        c->load_j = load_nm / j_kgm2;
    } else {
        c->inv_j = 0.0;
        c->b_j = 0.0;
        c->load_j = 0.0;
    }
}

double pmsm_dq_wrap_angle(double x)
{
    double y = fmod(x, PMSM_DQ_TWO_PI);
    if (y < 0.0) {
        y += PMSM_DQ_TWO_PI;
    }
    if (y >= PMSM_DQ_TWO_PI) { /* -tiny + 2*pi rounds up to 2*pi */
        y = 0.0;
    }
    return y;
}

void pmsm_dq_phase_currents(double id, double iq, double theta_e_rad, double *ia_a, double *ib_a)
{
    const double cs = cos(theta_e_rad);
    const double sn = sin(theta_e_rad);
    const double i_alpha = id * cs - iq * sn;
    const double i_beta = id * sn + iq * cs;
    *ia_a = i_alpha;
    *ib_a = -0.5 * i_alpha + PMSM_DQ_SQRT3_HALF * i_beta;
}

double pmsm_dq_torque(double id, double iq, double ld_h, double lq_h, double psi_f_wb, int pole_pairs)
{
    const double psi_d = ld_h * id + psi_f_wb;
    const double psi_q = lq_h * iq;
    return 1.5 * (double)pole_pairs * (psi_d * iq - psi_q * id);
}

double pmsm_dq_flux(double id, double iq, double ld_h, double lq_h, double psi_f_wb)
{
    const double psi_d = ld_h * id + psi_f_wb;
    const double psi_q = lq_h * iq;
    return sqrt(psi_d * psi_d + psi_q * psi_q);
}

int pmsm_dq_finite_positive(double x)
{
    return isfinite(x) && x > 0.0;
}

int pmsm_dq_sim_params_valid(double rs_ohm, double ld_h, double lq_h, double psi_f_wb,
                             int pole_pairs, double j_kgm2, double b_nms, double udc_v,
                             double dt_s, double kp, double ki, double limit_nm,
                             int speed_imposed)
{
    if (!pmsm_dq_finite_positive(ld_h) || !pmsm_dq_finite_positive(lq_h)
        || !pmsm_dq_finite_positive(udc_v) || !pmsm_dq_finite_positive(dt_s)
        || !isfinite(rs_ohm) || rs_ohm < 0.0 || !isfinite(psi_f_wb) || !isfinite(b_nms)
        || !isfinite(kp) || !isfinite(ki) || !isfinite(limit_nm) || limit_nm < 0.0) {
        return 0;
    }
    if (pole_pairs < 1) {
        return 0;
    }
    if (!speed_imposed && !pmsm_dq_finite_positive(j_kgm2)) {
        return 0;
    }
    return 1;
}
