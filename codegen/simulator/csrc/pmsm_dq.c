/*
 * pmsm_dq.c -- the host simulator's float64 entry points of the PMSM dq
 * model (see pmsm_dq.h; the model itself is written once there).
 *
 * C99; compiles warning-free with
 *   gcc -std=c99 -O2 -Wall -Wextra -Wconversion -Wdouble-promotion -Werror
 *       -ffp-contract=off
 * (-ffp-contract=off: no fused multiply-add, so every host gives the same
 * bits and chunked runs equal one long run exactly).
 */
#include "pmsm_dq.h"

double pmsm_dq_wrap_angle(double x)
{
    return pmsm_dq_wrap(x);
}

void pmsm_dq_phase_currents(double id, double iq, double theta_e_rad, double *ia_a, double *ib_a)
{
    pmsm_dq_currents(id, iq, theta_e_rad, ia_a, ib_a);
}

double pmsm_dq_torque(double id, double iq, double ld_h, double lq_h, double psi_f_wb, int pole_pairs)
{
    return pmsm_dq_te(id, iq, ld_h, lq_h, psi_f_wb, pole_pairs);
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
