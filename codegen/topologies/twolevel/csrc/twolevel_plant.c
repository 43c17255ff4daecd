/*
 * plant2l.c -- two-level inverter + PMSM plant, float64 (see plant2l.h).
 *
 * Specification: shared/spec/plant-and-metrics.md "Plant" (motor, inverter,
 * integration) and shared/spec/mptc-two-level.md "Conventions" (space vector,
 * Clarke/Park, torque).  C99; compiles warning-free with
 *   gcc -std=c99 -O2 -Wall -Wextra -Wconversion -Wdouble-promotion -Werror
 *       -ffp-contract=off
 * (-ffp-contract=off: no fused multiply-add, so every host gives the same
 * bits and chunked runs equal one long run exactly).
 */
#include "plant2l.h"

#include <math.h>

#include "pmsm_dq.h"

/* Constants of the right-hand side, computed once per plant2l_advance call. */
typedef struct {
    double u_alpha, u_beta;   /* inverter voltage, stationary frame, V */
    pmsm_dq_rhs_t m;          /* motor equations (pmsm_dq.h) */
    int zero_u;               /* 1: zero vector, u_dq = 0 */
} rhs_t;

/* ---------------------------------------------------------------------------
 * Inverter: amplitude-invariant space vector of the switching state
 * (mptc-two-level.md "Conventions"):
 *   u_alpha + j*u_beta = (2/3)*Udc*(Sa + a*Sb + a^2*Sc), a = exp(j*2*pi/3)
 *   => u_alpha = (2/3)*Udc*(Sa - (Sb + Sc)/2),  u_beta = (Udc/sqrt(3))*(Sb - Sc)
 * ------------------------------------------------------------------------- */
void plant2l_voltage_ab(const plant2l_params_t *p, int sw, double *u_alpha_v, double *u_beta_v)
{
    double sa, sb, sc;
    if (sw < 0 || sw > 7) {
        *u_alpha_v = 0.0;
        *u_beta_v = 0.0;
        return;
    }
    sa = (double)((sw >> 2) & 1);
    sb = (double)((sw >> 1) & 1);
    sc = (double)(sw & 1);
    *u_alpha_v = (2.0 / 3.0) * p->udc_v * (sa - 0.5 * (sb + sc));
    *u_beta_v = p->udc_v * PMSM_DQ_SQRT3_INV * (sb - sc);
}

/* ---------------------------------------------------------------------------
 * Right-hand side f(x) of the plant ODE, x = (i_d, i_q, omega_m, theta_e),
 * given cos/sin of the stage angle (plant-and-metrics.md "Plant", motor):
 *   u_d =  u_alpha*cos + u_beta*sin,  u_q = u_beta*cos - u_alpha*sin  (Park)
 *   di_d/dt = (u_d - Rs*i_d + w_e*Lq*i_q) / Ld
 *   di_q/dt = (u_q - Rs*i_q - w_e*Ld*i_d - w_e*psi_f) / Lq
 *   Te = 1.5*p*(psi_d*i_q - psi_q*i_d) = 1.5*p*(psi_f*i_q + (Ld - Lq)*i_d*i_q)
 *   dw_m/dt = (Te - T_L - B*w_m) / J     (0 when the speed is imposed)
 *   dtheta_e/dt = w_e = p*w_m
 * ------------------------------------------------------------------------- */
static inline void rhs(const rhs_t *c, double id, double iq, double wm, double cs, double sn,
                double *did, double *diq, double *dwm, double *dth)
{
    double ud = 0.0, uq = 0.0;
    if (!c->zero_u) {
        ud = c->u_alpha * cs + c->u_beta * sn;
        uq = c->u_beta * cs - c->u_alpha * sn;
    }
    pmsm_dq_derivs(&c->m, id, iq, wm, ud, uq, did, diq, dwm, dth);
}

double plant2l_wrap_angle(double x)
{
    return pmsm_dq_wrap_angle(x);
}

/* ---------------------------------------------------------------------------
 * One interval of constant inverter voltage, classic RK4 in `substeps` equal
 * sub-steps h = dt/substeps (plant-and-metrics.md "Integration": RK4 with
 * sub-steps of at most 1 us):
 *   k1 = f(x), k2 = f(x + h/2*k1), k3 = f(x + h/2*k2), k4 = f(x + h*k3)
 *   x <- x + h/6*(k1 + 2*k2 + 2*k3 + k4)
 * The angle used by Park at each stage is the stage's own theta_e:
 * theta + h/2*w_e1, theta + h/2*w_e2, theta + h*w_e3 (cos/sin by pmsm_dq_rotate()).
 * With the speed imposed, stages 2 and 3 share one angle and one rotation.
 * ------------------------------------------------------------------------- */
int plant2l_advance(plant2l_state_t *s, const plant2l_params_t *p, int sw,
                    double load_nm, double dt_s, int substeps, int speed_imposed)
{
    rhs_t c;
    double h, h2, h6;
    double id, iq, wm, th;
    int n;

    if (sw < 0 || sw > 7 || substeps < 1 || !(dt_s > 0.0) || !isfinite(dt_s)) {
        return -1;
    }

    plant2l_voltage_ab(p, sw, &c.u_alpha, &c.u_beta);
    c.zero_u = (sw == 0 || sw == 7);
    pmsm_dq_rhs_setup(&c.m, p->rs_ohm, p->ld_h, p->lq_h, p->psi_f_wb, p->pole_pairs, p->j_kgm2,
                      p->b_nms, load_nm, speed_imposed);

    h = dt_s / (double)substeps;
    h2 = 0.5 * h;
    h6 = h / 6.0;
    id = s->i_d_a;
    iq = s->i_q_a;
    wm = s->omega_m_rad_s;
    th = s->theta_e_rad;

    for (n = 0; n < substeps; ++n) {
        double d1, q1, w1, t1, d2, q2, w2, t2, d3, q3, w3, t3, d4, q4, w4, t4;
        double c0 = 1.0, s0 = 0.0, cs = 1.0, sn = 0.0;

        if (!c.zero_u) { /* the zero vector needs no Park rotation */
            c0 = cos(th);
            s0 = sin(th);
        }
        rhs(&c, id, iq, wm, c0, s0, &d1, &q1, &w1, &t1);

        if (!c.zero_u) {
            pmsm_dq_rotate(c0, s0, h2 * t1, &cs, &sn);
        }
        rhs(&c, id + h2 * d1, iq + h2 * q1, wm + h2 * w1, cs, sn, &d2, &q2, &w2, &t2);

        if (!c.zero_u && t2 != t1) { /* same angle as stage 2 when the speed is held */
            pmsm_dq_rotate(c0, s0, h2 * t2, &cs, &sn);
        }
        rhs(&c, id + h2 * d2, iq + h2 * q2, wm + h2 * w2, cs, sn, &d3, &q3, &w3, &t3);

        if (!c.zero_u) {
            pmsm_dq_rotate(c0, s0, h * t3, &cs, &sn);
        }
        rhs(&c, id + h * d3, iq + h * q3, wm + h * w3, cs, sn, &d4, &q4, &w4, &t4);

        id += h6 * (d1 + 2.0 * d2 + 2.0 * d3 + d4);
        iq += h6 * (q1 + 2.0 * q2 + 2.0 * q3 + q4);
        wm += h6 * (w1 + 2.0 * w2 + 2.0 * w3 + w4);
        th += h6 * (t1 + 2.0 * t2 + 2.0 * t3 + t4);
    }

    s->i_d_a = id;
    s->i_q_a = iq;
    s->omega_m_rad_s = wm;
    s->theta_e_rad = pmsm_dq_wrap_angle(th);
    return 0;
}

/* ---------------------------------------------------------------------------
 * Sampled quantities (mptc-two-level.md "Conventions"):
 *   inverse Park:   i_alpha = i_d*cos - i_q*sin,  i_beta = i_d*sin + i_q*cos
 *   inverse Clarke: i_a = i_alpha,  i_b = -i_alpha/2 + (sqrt(3)/2)*i_beta
 *   (so that Clarke i_beta = (i_a + 2*i_b)/sqrt(3) gives i_beta back)
 * ------------------------------------------------------------------------- */
void plant2l_phase_currents(const plant2l_state_t *s, double *ia_a, double *ib_a)
{
    pmsm_dq_phase_currents(s->i_d_a, s->i_q_a, s->theta_e_rad, ia_a, ib_a);
}

double plant2l_theta_e(const plant2l_state_t *s)
{
    return pmsm_dq_wrap_angle(s->theta_e_rad);
}

/* Te = 1.5*p*(psi_d*i_q - psi_q*i_d), psi_d = Ld*i_d + psi_f, psi_q = Lq*i_q. */
double plant2l_torque(const plant2l_state_t *s, const plant2l_params_t *p)
{
    return pmsm_dq_torque(s->i_d_a, s->i_q_a, p->ld_h, p->lq_h, p->psi_f_wb, p->pole_pairs);
}

/* |psi_s| = sqrt(psi_d^2 + psi_q^2) (the dq and alpha-beta magnitudes agree). */
double plant2l_flux(const plant2l_state_t *s, const plant2l_params_t *p)
{
    return pmsm_dq_flux(s->i_d_a, s->i_q_a, p->ld_h, p->lq_h, p->psi_f_wb);
}
