/*
 * onboard.c -- see onboard.h.
 */
#include "onboard.h"

#include <math.h>

#include "hil_wire.h"
#include "mpc_runtime.h"
#include "onboard_config.h"

#define ONB_TWO_PI 6.2831853f
#define ONB_SQRT3_HALF 0.8660254f
/* Largest |state| still taken as finite (divergence check). */
#define ONB_HUGE 1.0e30f

static float wrap(float th)
{
    while (th >= ONB_TWO_PI) {
        th -= ONB_TWO_PI;
    }
    while (th < 0.0f) {
        th += ONB_TWO_PI;
    }
    return th;
}

/* cos/sin of theta + d from cos/sin of theta, |d| small (Taylor to d^4). */
static void rotate(float c0, float s0, float d, float *cs, float *sn)
{
    const float d2 = d * d;
    const float sd = d * (1.0f - d2 * (1.0f / 6.0f));
    const float cd = 1.0f - d2 * 0.5f * (1.0f - d2 * (1.0f / 12.0f));
    *cs = c0 * cd - s0 * sd;
    *sn = s0 * cd + c0 * sd;
}

/* Right-hand side at one stage (pmsm_dq.h, in float32). */
static void rhs(const onb_segment_t *c, float load_nm, const float *x, float cs, float sn, float *dx)
{
    float ud = 0.0f, uq = 0.0f;
    const float we = ONB_POLE_PAIRS * x[2];
    if (c->zero == 0u) {
        const float ua = c->ua0 + c->ua1 * x[4];
        const float ub = c->ub0 + c->ub1 * x[4];
        const float ial = x[0] * cs - x[1] * sn;
        const float ibe = x[0] * sn + x[1] * cs;
        ud = ua * cs + ub * sn;
        uq = ub * cs - ua * sn;
        dx[4] = c->ka * ial + c->kb * ibe;
    } else {
        dx[4] = 0.0f;
    }
    dx[0] = (ud - ONB_RS * x[0] + we * ONB_LQ * x[1]) * (1.0f / ONB_LD);
    dx[1] = (uq - ONB_RS * x[1] - we * ONB_LD * x[0] - we * ONB_PSI_F) * (1.0f / ONB_LQ);
    if (ONB_SPEED_IMPOSED != 0) {
        dx[2] = 0.0f;
    } else {
        const float te = 1.5f * ONB_POLE_PAIRS * (ONB_PSI_F * x[1] + (ONB_LD - ONB_LQ) * x[0] * x[1]);
        dx[2] = (te - load_nm - ONB_B * x[2]) * (1.0f / ONB_J);
    }
    dx[3] = we;
}

void onb_advance(onb_plant_t *p, const onb_segment_t *seg, float load_nm, float dt_s, uint16_t substeps)
{
    const float h = dt_s / (float)substeps;
    const float h2 = 0.5f * h;
    uint16_t n, i;
    for (n = 0u; n < substeps; ++n) {
        float k1[5], k2[5], k3[5], k4[5], xs[5];
        float c0 = 1.0f, s0 = 0.0f, cs = 1.0f, sn = 0.0f;
        if (seg->zero == 0u) {
            c0 = cosf(p->x[3]);
            s0 = sinf(p->x[3]);
        }
        rhs(seg, load_nm, p->x, c0, s0, k1);
        if (seg->zero == 0u) {
            rotate(c0, s0, h2 * k1[3], &cs, &sn);
        }
        for (i = 0u; i < 5u; ++i) {
            xs[i] = p->x[i] + h2 * k1[i];
        }
        rhs(seg, load_nm, xs, cs, sn, k2);
        if (seg->zero == 0u) {
            rotate(c0, s0, h2 * k2[3], &cs, &sn);
        }
        for (i = 0u; i < 5u; ++i) {
            xs[i] = p->x[i] + h2 * k2[i];
        }
        rhs(seg, load_nm, xs, cs, sn, k3);
        if (seg->zero == 0u) {
            rotate(c0, s0, h * k3[3], &cs, &sn);
        }
        for (i = 0u; i < 5u; ++i) {
            xs[i] = p->x[i] + h * k3[i];
        }
        rhs(seg, load_nm, xs, cs, sn, k4);
        for (i = 0u; i < 5u; ++i) {
            p->x[i] += (h / 6.0f) * (k1[i] + 2.0f * k2[i] + 2.0f * k3[i] + k4[i]);
        }
        p->x[3] = wrap(p->x[3]);
    }
}

/* Speed PI, float32, conditional-integration anti-windup (speed_pi.c). */
static float speed_pi(float *integral, float w_ref, float w_m)
{
    const float lim = ONB_LIMIT;
    const float e = w_ref - w_m;
    const float u = ONB_KP * e + *integral;
    float t_ref = u;
    if (t_ref > lim) {
        t_ref = lim;
    } else if (t_ref < -lim) {
        t_ref = -lim;
    }
    if (!((u > lim && e > 0.0f) || (u < -lim && e < 0.0f))) {
        float i_new = *integral + ONB_KI * e * ONB_DT;
        if (i_new > lim) {
            i_new = lim;
        } else if (i_new < -lim) {
            i_new = -lim;
        }
        *integral = i_new;
    }
    return t_ref;
}

uint16_t onboard_check(const hil_setpoints_t *sp)
{
    uint16_t i;
    if (sp->periods < 1) {
        return 1u;
    }
    if (sp->decimation < 1u) {
        return 2u;
    }
    if (sp->n_steps < 1u || sp->n_steps > HIL_MAX_STEPS) {
        return 3u;
    }
    if (sp->step_k[0] != 0) {
        return 4u;
    }
    for (i = 1u; i < sp->n_steps; ++i) {
        if (sp->step_k[i] <= sp->step_k[i - 1u]) {
            return 4u;
        }
    }
    return 0u;
}

static uint16_t finite_state(const onb_plant_t *p)
{
    uint16_t i;
    for (i = 0u; i < 5u; ++i) {
        const float v = p->x[i];
        if (!(v > -ONB_HUGE && v < ONB_HUGE)) {
            return 0u;
        }
    }
    return 1u;
}

void onboard_run(const hil_setpoints_t *sp, uint32_t overhead, onb_emit_fn emit, hil_onboard_end_t *end)
{
    static hil_sample_t buf[HIL_TELEMETRY_SAMPLES];
    static mpc_input_t in;
    static mpc_output_t out;
    onb_plant_t p;
    float integral = 0.0f;
    uint32_t sum_lo = 0u, sum_hi = 0u, cmin = 0xFFFFFFFFu, cmax = 0u, width = 0u;
    uint32_t hist[8];
    int32_t k, samples = 0, changes = 0, status = 0;
    uint16_t nbuf = 0u, s = 0u, prev_dec = 0u, i;

    for (i = 0u; i < 5u; ++i) {
        p.x[i] = 0.0f;
    }
    for (i = 0u; i < 8u; ++i) {
        hist[i] = 0u;
    }
    onb_topo_reset();
    for (k = 0; k < sp->periods; ++k) {
        float w_ref, load, cs, sn, ial, ibe, t_ref;
        uint32_t raw, cyc, bin;
        uint16_t dec;
        while ((uint16_t)(s + 1u) < sp->n_steps && sp->step_k[s + 1u] <= k) {
            ++s;
        }
        w_ref = sp->speed_rad_s[s];
        load = sp->load_nm[s];
        /* 1.-3. imposed speed, sampling, torque reference */
        if (ONB_SPEED_IMPOSED != 0) {
            p.x[2] = w_ref;
        }
        cs = cosf(p.x[3]);
        sn = sinf(p.x[3]);
        ial = p.x[0] * cs - p.x[1] * sn;
        ibe = p.x[0] * sn + p.x[1] * cs;
        t_ref = (ONB_SPEED_IMPOSED != 0) ? load : speed_pi(&integral, w_ref, p.x[2]);
        /* 4. controller */
        in.ia_a = MPC_ENCODE_ia_a(ial);
        in.ib_a = MPC_ENCODE_ib_a(-0.5f * ial + ONB_SQRT3_HALF * ibe);
        in.theta_e_rad = MPC_ENCODE_theta_e_rad(p.x[3]);
        in.omega_e_rad_s = MPC_ENCODE_omega_e_rad_s(ONB_POLE_PAIRS * p.x[2]);
        in.torque_ref_nm = MPC_ENCODE_torque_ref_nm(t_ref);
        onb_topo_input(&p, &in);
        raw = mpc_timed_step(&in, &out);
        cyc = (raw > overhead) ? raw - overhead : 0u;
        cyc &= 0x7FFFFFFFu;
        if (cyc < cmin) {
            cmin = cyc;
        }
        if (cyc > cmax) {
            cmax = cyc;
        }
        sum_lo += cyc;
        if (sum_lo < cyc) {
            ++sum_hi;
        }
        if (width == 0u) {
            width = 1u;
            while (width * 4u < cyc + 1u) {
                width *= 2u;
            }
        }
        bin = cyc / width;
        ++hist[(bin < 7u) ? bin : 7u];
        dec = onb_topo_decision(&out);
        if (k > 0 && dec != prev_dec) {
            ++changes;
        }
        prev_dec = dec;
        /* 5. the sample */
        if (k % (int32_t)sp->decimation == 0) {
            hil_sample_t *r = &buf[nbuf];
            r->k = k;
            r->omega_m = p.x[2];
            r->te_nm = 1.5f * ONB_POLE_PAIRS * (ONB_PSI_F * p.x[1] + (ONB_LD - ONB_LQ) * p.x[0] * p.x[1]);
            r->torque_ref = t_ref;
            r->ia_a = (float)MPC_DECODE_ia_a(in.ia_a);
            r->ib_a = (float)MPC_DECODE_ib_a(in.ib_a);
            r->decision = dec;
            r->fault = out.fault;
            ++nbuf;
            ++samples;
            if (nbuf == HIL_TELEMETRY_SAMPLES) {
                emit(buf, nbuf);
                nbuf = 0u;
            }
        }
        /* 6.-7. timing rule and plant */
        if (onb_topo_apply(&p, &out, load) != 0) {
            status = -3;
            break;
        }
        if (finite_state(&p) == 0u) {
            status = -2;
            break;
        }
    }
    if (nbuf != 0u) {
        emit(buf, nbuf);
    }
    end->periods = k;
    end->samples = samples;
    end->status = status;
    end->changes = changes;
    end->cycles_min = hil_i32_from_bits((k > 0) ? cmin : 0u);
    end->cycles_max = hil_i32_from_bits(cmax);
    end->cycles_sum[0] = (uint16_t)(sum_lo & 0xFFFFu);
    end->cycles_sum[1] = (uint16_t)(sum_lo >> 16);
    end->cycles_sum[2] = (uint16_t)(sum_hi & 0xFFFFu);
    end->cycles_sum[3] = (uint16_t)(sum_hi >> 16);
    for (i = 0u; i < 8u; ++i) {
        end->hist[i] = hil_i32_from_bits(hist[i] & 0x7FFFFFFFu);
    }
    end->hist_width = hil_i32_from_bits(width);
}
