/*
 * pmsm_dq.h -- PMSM dq model shared by the two-level (twolevel_plant.c) and
 * the T-type (ttype_plant.c) host plants and the firmware's on-board loop
 * (hand-written runtime, written once on sim_real_t: float64 on the host,
 * float32 on board, see sim_real.h).
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
 * The model is static inline here so that the plants' integration loops
 * inline it (the same operations in the same order: results are
 * bit-identical under -ffp-contract=off).  The float64 entry points the
 * host simulator and its tests call by name (pmsm_dq.c) wrap it.
 *
 * C99, no dynamic memory, no global state.  Not part of any cffi cdef.
 */
#ifndef PMSM_DQ_H
#define PMSM_DQ_H

#include "sim_real.h"

#define PMSM_DQ_TWO_PI SIM_R(6.283185307179586476925286766559)
#define PMSM_DQ_SQRT3_INV SIM_R(0.57735026918962576450914878050196)  /* 1/sqrt(3) */
#define PMSM_DQ_SQRT3_HALF SIM_R(0.86602540378443864676372317075294) /* sqrt(3)/2 */

/* Constants of the motor's right-hand side (current and mechanical
 * equations), computed once per constant-voltage interval. */
typedef struct {
    sim_real_t inv_ld, rs_ld, lq_ld;          /* d-axis current equation */
    sim_real_t inv_lq, rs_lq, ld_lq, psif_lq; /* q-axis current equation */
    sim_real_t p;                             /* pole pairs (as a real) */
    sim_real_t kt, psi_f, dl;                 /* torque: 1.5p, psi_f, Ld - Lq */
    sim_real_t inv_j, b_j, load_j;            /* mechanical equation */
    int mech;                                 /* 1: integrate omega_m, 0: held */
} pmsm_dq_rhs_t;

/* Fill c from the motor parameters and the load torque (N*m); with
 * speed_imposed != 0 the mechanical equation is off (J, B, load unused). */
static inline void pmsm_dq_rhs_setup(pmsm_dq_rhs_t *c, sim_real_t rs_ohm, sim_real_t ld_h,
                                     sim_real_t lq_h, sim_real_t psi_f_wb, int pole_pairs,
                                     sim_real_t j_kgm2, sim_real_t b_nms, sim_real_t load_nm,
                                     int speed_imposed)
{
    c->inv_ld = SIM_R(1.0) / ld_h;
    c->rs_ld = rs_ohm / ld_h;
    c->lq_ld = lq_h / ld_h;
    c->inv_lq = SIM_R(1.0) / lq_h;
    c->rs_lq = rs_ohm / lq_h;
    c->ld_lq = ld_h / lq_h;
    c->psif_lq = psi_f_wb / lq_h;
    c->p = (sim_real_t)pole_pairs;
    c->kt = SIM_R(1.5) * c->p;
    c->psi_f = psi_f_wb;
    c->dl = ld_h - lq_h;
    c->mech = speed_imposed ? 0 : 1;
    if (c->mech) {
        c->inv_j = SIM_R(1.0) / j_kgm2;
        c->b_j = b_nms / j_kgm2;
        c->load_j = load_nm / j_kgm2;
    } else {
        c->inv_j = SIM_R(0.0);
        c->b_j = SIM_R(0.0);
        c->load_j = SIM_R(0.0);
    }
}

/* Motor derivatives at the dq voltage (ud, uq):
 *   di_d/dt = (u_d - Rs*i_d + w_e*Lq*i_q) / Ld
 *   di_q/dt = (u_q - Rs*i_q - w_e*Ld*i_d - w_e*psi_f) / Lq
 *   Te = 1.5*p*(psi_f*i_q + (Ld - Lq)*i_d*i_q)
 *   dw_m/dt = (Te - T_L - B*w_m) / J     (0 when the speed is imposed)
 *   dtheta_e/dt = w_e = p*w_m */
static inline void pmsm_dq_derivs(const pmsm_dq_rhs_t *c, sim_real_t id, sim_real_t iq,
                                  sim_real_t wm, sim_real_t ud, sim_real_t uq, sim_real_t *did,
                                  sim_real_t *diq, sim_real_t *dwm, sim_real_t *dth)
{
    const sim_real_t we = c->p * wm;
    *did = c->inv_ld * ud - c->rs_ld * id + we * c->lq_ld * iq;
    *diq = c->inv_lq * uq - c->rs_lq * iq - we * c->ld_lq * id - we * c->psif_lq;
    if (c->mech) {
        const sim_real_t te = c->kt * (c->psi_f * iq + c->dl * id * iq);
        *dwm = c->inv_j * te - c->load_j - c->b_j * wm;
    } else {
        *dwm = SIM_R(0.0);
    }
    *dth = we;
}

/* Park of a stationary-frame voltage at cos/sin of the angle:
 *   u_d = u_alpha*cos + u_beta*sin,  u_q = u_beta*cos - u_alpha*sin */
static inline void pmsm_dq_park(sim_real_t u_alpha, sim_real_t u_beta, sim_real_t cs, sim_real_t sn,
                                sim_real_t *ud, sim_real_t *uq)
{
    *ud = u_alpha * cs + u_beta * sn;
    *uq = u_beta * cs - u_alpha * sn;
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
static inline void pmsm_dq_rotate(sim_real_t c0, sim_real_t s0, sim_real_t d, sim_real_t *cs,
                                  sim_real_t *sn)
{
    sim_real_t cd, sd;
    if (SIM_FABS(d) <= SIM_R(1e-2)) {
        const sim_real_t d2 = d * d;
        /* sin d = d - d^3/3! + d^5/5! - d^7/7!;  cos d = 1 - d^2/2! + ... + d^8/8! */
        /* (reciprocals as multiplications: divisions are slow in this loop) */
        sd = d * (SIM_R(1.0) - d2 * (SIM_R(1.0) / SIM_R(6.0))
                  * (SIM_R(1.0) - d2 * (SIM_R(1.0) / SIM_R(20.0)) * (SIM_R(1.0) - d2 * (SIM_R(1.0) / SIM_R(42.0)))));
        cd = SIM_R(1.0) - d2 * SIM_R(0.5) * (SIM_R(1.0) - d2 * (SIM_R(1.0) / SIM_R(12.0))
             * (SIM_R(1.0) - d2 * (SIM_R(1.0) / SIM_R(30.0)) * (SIM_R(1.0) - d2 * (SIM_R(1.0) / SIM_R(56.0)))));
    } else {
        cd = SIM_COS(d);
        sd = SIM_SIN(d);
    }
    *cs = c0 * cd - s0 * sd;
    *sn = s0 * cd + c0 * sd;
}

/* An angle wrapped to [0, 2*pi). */
static inline sim_real_t pmsm_dq_wrap(sim_real_t x)
{
    sim_real_t y = SIM_FMOD(x, PMSM_DQ_TWO_PI);
    if (y < SIM_R(0.0)) {
        y += PMSM_DQ_TWO_PI;
    }
    if (y >= PMSM_DQ_TWO_PI) { /* -tiny + 2*pi rounds up to 2*pi */
        y = SIM_R(0.0);
    }
    return y;
}

/* Phase currents i_a, i_b (A) of the dq currents at electrical angle theta:
 *   inverse Park:   i_alpha = i_d*cos - i_q*sin,  i_beta = i_d*sin + i_q*cos
 *   inverse Clarke: i_a = i_alpha,  i_b = -i_alpha/2 + (sqrt(3)/2)*i_beta */
static inline void pmsm_dq_currents(sim_real_t id, sim_real_t iq, sim_real_t theta_e_rad,
                                    sim_real_t *ia_a, sim_real_t *ib_a)
{
    const sim_real_t cs = SIM_COS(theta_e_rad);
    const sim_real_t sn = SIM_SIN(theta_e_rad);
    const sim_real_t i_alpha = id * cs - iq * sn;
    const sim_real_t i_beta = id * sn + iq * cs;
    *ia_a = i_alpha;
    *ib_a = -SIM_R(0.5) * i_alpha + PMSM_DQ_SQRT3_HALF * i_beta;
}

/* Te = 1.5*p*(psi_d*i_q - psi_q*i_d), psi_d = Ld*i_d + psi_f, psi_q = Lq*i_q, N*m. */
static inline sim_real_t pmsm_dq_te(sim_real_t id, sim_real_t iq, sim_real_t ld_h, sim_real_t lq_h,
                                    sim_real_t psi_f_wb, int pole_pairs)
{
    const sim_real_t psi_d = ld_h * id + psi_f_wb;
    const sim_real_t psi_q = lq_h * iq;
    return SIM_R(1.5) * (sim_real_t)pole_pairs * (psi_d * iq - psi_q * id);
}

#if !SIM_REAL_IS_F32
/* The host simulator's float64 entry points (pmsm_dq.c): the model above by name, for the host
 * plants and the cffi tests. */

/* Wrap an angle to [0, 2*pi) (pmsm_dq_wrap). */
double pmsm_dq_wrap_angle(double x);

/* Phase currents i_a, i_b (A) of the dq currents at electrical angle theta (pmsm_dq_currents). */
void pmsm_dq_phase_currents(double id, double iq, double theta_e_rad, double *ia_a, double *ib_a);

/* Te, N*m (pmsm_dq_te). */
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
#endif

#endif /* PMSM_DQ_H */
