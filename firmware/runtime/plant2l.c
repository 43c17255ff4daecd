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

#define PLANT2L_TWO_PI 6.283185307179586476925286766559
#define PLANT2L_SQRT3_INV 0.57735026918962576450914878050196 /* 1/sqrt(3) */
#define PLANT2L_SQRT3_HALF 0.86602540378443864676372317075294 /* sqrt(3)/2 */

/* Constants of the right-hand side, computed once per plant2l_advance call. */
typedef struct {
    double u_alpha, u_beta;   /* inverter voltage, stationary frame, V */
    double inv_ld, rs_ld, lq_ld;             /* d-axis current equation */
    double inv_lq, rs_lq, ld_lq, psif_lq;    /* q-axis current equation */
    double p;                                /* pole pairs (as double) */
    double kt, psi_f, dl;                    /* torque: 1.5p, psi_f, Ld - Lq */
    double inv_j, b_j, load_j;               /* mechanical equation */
    int mech;                                /* 1: integrate omega_m, 0: held */
    int zero_u;                              /* 1: zero vector, u_dq = 0 */
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
    *u_beta_v = p->udc_v * PLANT2L_SQRT3_INV * (sb - sc);
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
    const double we = c->p * wm;
    double ud = 0.0, uq = 0.0;
    if (!c->zero_u) {
        ud = c->u_alpha * cs + c->u_beta * sn;
        uq = c->u_beta * cs - c->u_alpha * sn;
    }
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
static inline void rotate(double c0, double s0, double d, double *cs, double *sn)
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

double plant2l_wrap_angle(double x)
{
    double y = fmod(x, PLANT2L_TWO_PI);
    if (y < 0.0) {
        y += PLANT2L_TWO_PI;
    }
    if (y >= PLANT2L_TWO_PI) { /* -tiny + 2*pi rounds up to 2*pi */
        y = 0.0;
    }
    return y;
}

/* ---------------------------------------------------------------------------
 * One interval of constant inverter voltage, classic RK4 in `substeps` equal
 * sub-steps h = dt/substeps (plant-and-metrics.md "Integration": RK4 with
 * sub-steps of at most 1 us):
 *   k1 = f(x), k2 = f(x + h/2*k1), k3 = f(x + h/2*k2), k4 = f(x + h*k3)
 *   x <- x + h/6*(k1 + 2*k2 + 2*k3 + k4)
 * The angle used by Park at each stage is the stage's own theta_e:
 * theta + h/2*w_e1, theta + h/2*w_e2, theta + h*w_e3 (cos/sin by rotate()).
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
    c.inv_ld = 1.0 / p->ld_h;
    c.rs_ld = p->rs_ohm / p->ld_h;
    c.lq_ld = p->lq_h / p->ld_h;
    c.inv_lq = 1.0 / p->lq_h;
    c.rs_lq = p->rs_ohm / p->lq_h;
    c.ld_lq = p->ld_h / p->lq_h;
    c.psif_lq = p->psi_f_wb / p->lq_h;
    c.p = (double)p->pole_pairs;
    c.kt = 1.5 * c.p;
    c.psi_f = p->psi_f_wb;
    c.dl = p->ld_h - p->lq_h;
    c.mech = speed_imposed ? 0 : 1;
    if (c.mech) {
        c.inv_j = 1.0 / p->j_kgm2;
        c.b_j = p->b_nms / p->j_kgm2;
        c.load_j = load_nm / p->j_kgm2;
    } else {
        c.inv_j = 0.0;
        c.b_j = 0.0;
        c.load_j = 0.0;
    }

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
            rotate(c0, s0, h2 * t1, &cs, &sn);
        }
        rhs(&c, id + h2 * d1, iq + h2 * q1, wm + h2 * w1, cs, sn, &d2, &q2, &w2, &t2);

        if (!c.zero_u && t2 != t1) { /* same angle as stage 2 when the speed is held */
            rotate(c0, s0, h2 * t2, &cs, &sn);
        }
        rhs(&c, id + h2 * d2, iq + h2 * q2, wm + h2 * w2, cs, sn, &d3, &q3, &w3, &t3);

        if (!c.zero_u) {
            rotate(c0, s0, h * t3, &cs, &sn);
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
    s->theta_e_rad = plant2l_wrap_angle(th);
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
    const double cs = cos(s->theta_e_rad);
    const double sn = sin(s->theta_e_rad);
    const double i_alpha = s->i_d_a * cs - s->i_q_a * sn;
    const double i_beta = s->i_d_a * sn + s->i_q_a * cs;
    *ia_a = i_alpha;
    *ib_a = -0.5 * i_alpha + PLANT2L_SQRT3_HALF * i_beta;
}

double plant2l_theta_e(const plant2l_state_t *s)
{
    return plant2l_wrap_angle(s->theta_e_rad);
}

/* Te = 1.5*p*(psi_d*i_q - psi_q*i_d), psi_d = Ld*i_d + psi_f, psi_q = Lq*i_q. */
double plant2l_torque(const plant2l_state_t *s, const plant2l_params_t *p)
{
    const double psi_d = p->ld_h * s->i_d_a + p->psi_f_wb;
    const double psi_q = p->lq_h * s->i_q_a;
    return 1.5 * (double)p->pole_pairs * (psi_d * s->i_q_a - psi_q * s->i_d_a);
}

/* |psi_s| = sqrt(psi_d^2 + psi_q^2) (the dq and alpha-beta magnitudes agree). */
double plant2l_flux(const plant2l_state_t *s, const plant2l_params_t *p)
{
    const double psi_d = p->ld_h * s->i_d_a + p->psi_f_wb;
    const double psi_q = p->lq_h * s->i_q_a;
    return sqrt(psi_d * psi_d + psi_q * psi_q);
}
