/*
 * pmsm_dq.h -- PMSM dq model shared by the two-level (twolevel_plant.c) and
 * the T-type (ttype_plant.c) host plants, float64 (hand-written runtime).
 *
 * Specification: docs/simulation.md "Plant" and
 * docs/algorithms.md (two-level MPTC) "Conventions" (amplitude-invariant
 * transforms).  Motor model, d axis on the magnet:
 *   Ld*di_d/dt = u_d - Rs*i_d + omega_e*Lq*i_q
 *   Lq*di_q/dt = u_q - Rs*i_q - omega_e*Ld*i_d - omega_e*psi_f
 *   J*domega_m/dt = Te - T_L - B*omega_m   (or omega_m held: speed imposed)
 *   dtheta_e/dt = omega_e = p*omega_m
 *   Te = 1.5*p*(psi_d*i_q - psi_q*i_d),  psi_d = Ld*i_d + psi_f, psi_q = Lq*i_q
 *
 * The right-hand side and the RK4 stage-angle rotation are static inline
 * here so that the plants' integration loops inline them exactly as before
 * (the same double operations in the same order: results are bit-identical
 * under -ffp-contract=off).
 *
 * C99, no dynamic memory, no global state.  Not part of any cffi cdef.
 */
#ifndef PMSM_DQ_H
#define PMSM_DQ_H

#include <math.h>

#define PMSM_DQ_TWO_PI 6.283185307179586476925286766559
#define PMSM_DQ_SQRT3_INV 0.57735026918962576450914878050196  /* 1/sqrt(3) */
#define PMSM_DQ_SQRT3_HALF 0.86602540378443864676372317075294 /* sqrt(3)/2 */

/* Constants of the motor's right-hand side (current and mechanical
 * equations), computed once per constant-voltage interval. */
typedef struct {
    double inv_ld, rs_ld, lq_ld;          /* d-axis current equation */
    double inv_lq, rs_lq, ld_lq, psif_lq; /* q-axis current equation */
    double p;                             /* pole pairs (as double) */
    double kt, psi_f, dl;                 /* torque: 1.5p, psi_f, Ld - Lq */
    double inv_j, b_j, load_j;            /* mechanical equation */
    int mech;                             /* 1: integrate omega_m, 0: held */
} pmsm_dq_rhs_t;

/* Fill c from the motor parameters and the load torque (N*m); with
 * speed_imposed != 0 the mechanical equation is off (J, B, load unused). */
void pmsm_dq_rhs_setup(pmsm_dq_rhs_t *c, double rs_ohm, double ld_h, double lq_h, double psi_f_wb,
                       int pole_pairs, double j_kgm2, double b_nms, double load_nm,
                       int speed_imposed);

/* Motor derivatives at the dq voltage (ud, uq):
 *   di_d/dt = (u_d - Rs*i_d + w_e*Lq*i_q) / Ld
 *   di_q/dt = (u_q - Rs*i_q - w_e*Ld*i_d - w_e*psi_f) / Lq
 *   Te = 1.5*p*(psi_f*i_q + (Ld - Lq)*i_d*i_q)
 *   dw_m/dt = (Te - T_L - B*w_m) / J     (0 when the speed is imposed)
 *   dtheta_e/dt = w_e = p*w_m */
static inline void pmsm_dq_derivs(const pmsm_dq_rhs_t *c, double id, double iq, double wm,
                                  double ud, double uq,
                                  double *did, double *diq, double *dwm, double *dth)
{
    const double we = c->p * wm;
    *did = c->inv_ld * ud - c->rs_ld * id + we * c->lq_ld * iq;
    *diq = c->inv_lq * uq - c->rs_lq * iq - we * c->ld_lq * id - we * c->psif_lq;
    if (c->mech) {
        const double te = c->kt * (c->psi_f * iq + c->dl * id * iq);
        *dwm = c->inv_j * te - c->load_j - c->b_j * wm;
    } else {
        *dwm = 0.0;
    }
    *dth = we;
}

/*
 * cos/sin of the stage angle theta + d from cos/sin of theta (angle-sum
 * identity): cos(theta + d) = c*cos(d) - s*sin(d), sin(theta + d) = s*cos(d) +
 * c*sin(d).  RK4 stage increments are tiny (d = h*omega_e ~ 1e-3 rad for
 * h = 1 us at 1600 rad/s electrical), so cos(d), sin(d) come from their
 * Taylor series, truncated where the next term is below 1e-19 for |d| <=
 * 0.01 (far below double rounding); larger d falls back to libm.  This
 * needs one libm sin/cos pair per sub-step instead of four.
 */
static inline void pmsm_dq_rotate(double c0, double s0, double d, double *cs, double *sn)
{
    double cd, sd;
    if (fabs(d) <= 1e-2) {
        const double d2 = d * d;
        /* sin d = d - d^3/3! + d^5/5! - d^7/7!;  cos d = 1 - d^2/2! + ... + d^8/8! */
        /* (reciprocals as multiplications: divisions are slow in this loop) */
        sd = d * (1.0 - d2 * (1.0 / 6.0) * (1.0 - d2 * (1.0 / 20.0) * (1.0 - d2 * (1.0 / 42.0))));
        cd = 1.0 - d2 * 0.5 * (1.0 - d2 * (1.0 / 12.0) * (1.0 - d2 * (1.0 / 30.0) * (1.0 - d2 * (1.0 / 56.0))));
    } else {
        cd = cos(d);
        sd = sin(d);
    }
    *cs = c0 * cd - s0 * sd;
    *sn = s0 * cd + c0 * sd;
}

/* Wrap an angle to [0, 2*pi). */
double pmsm_dq_wrap_angle(double x);

/* Phase currents i_a, i_b (A) of the dq currents at electrical angle theta:
 *   inverse Park:   i_alpha = i_d*cos - i_q*sin,  i_beta = i_d*sin + i_q*cos
 *   inverse Clarke: i_a = i_alpha,  i_b = -i_alpha/2 + (sqrt(3)/2)*i_beta */
void pmsm_dq_phase_currents(double id, double iq, double theta_e_rad, double *ia_a, double *ib_a);

/* Te = 1.5*p*(psi_d*i_q - psi_q*i_d), psi_d = Ld*i_d + psi_f, psi_q = Lq*i_q, N*m. */
double pmsm_dq_torque(double id, double iq, double ld_h, double lq_h, double psi_f_wb, int pole_pairs);

/* |psi_s| = sqrt(psi_d^2 + psi_q^2), Wb (the dq and alpha-beta magnitudes agree). */
double pmsm_dq_flux(double id, double iq, double ld_h, double lq_h, double psi_f_wb);

/* Parameter checks shared by the closed-loop simulators. */
int pmsm_dq_finite_positive(double x);

/* Motor + DC link + speed-loop parameters usable by the simulators:
 * Ld, Lq, Udc, dt > 0, Rs >= 0, psi_f, B, kp, ki finite, limit >= 0,
 * pole_pairs >= 1, J > 0 unless the speed is imposed.  1 valid, 0 not. */
int pmsm_dq_sim_params_valid(double rs_ohm, double ld_h, double lq_h, double psi_f_wb,
                             int pole_pairs, double j_kgm2, double b_nms, double udc_v,
                             double dt_s, double kp, double ki, double limit_nm,
                             int speed_imposed);

#endif /* PMSM_DQ_H */
