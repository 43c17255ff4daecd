/*
 * onboard.c -- see onboard.h: the on-board loop, the host simulator's period
 * (codegen/simulator/csrc/sim_period.h steps 1.-7.) in float32 on the
 * simulator's own plant core.
 */
#include "onboard.h"

#include "hil_wire.h"
#include "mpc_runtime.h"
#include "plant_config.h"
#include "pmsm_dq.h"
#include "sim_inverter.h"
#include "sim_motor_inputs.h"
#include "speed_pi.h"

/* Largest |state| still taken as finite (divergence check). */
#define ONB_HUGE SIM_R(1.0e30)

/* What the controller sees at the sample instant (SI units, SIM_MOTOR_INPUTS' fields): the plant's
 * values (no sensor non-idealities on board). */
typedef struct {
    sim_real_t ia, ib;   /* phase currents, A */
    sim_real_t th;       /* electrical angle in [0, 2*pi), rad */
    sim_real_t omega_e;  /* p*omega_m, rad/s */
    sim_real_t t_ref;    /* T*, N*m */
} onb_sample_t;

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
    if (sp->frame_first < 0 || sp->frame_count < 0) {
        return 5u;
    }
    return 0u;
}

int onb_gates_open_period(uint16_t gates[3], uint16_t gates_off, onb_plant_t *p, sim_real_t load_nm, int nx)
{
    sim_open_t o;
    gates[2] = gates[1];
    gates[1] = gates[0];
    gates[0] = (gates_off != 0u) ? 1u : 0u;
    if (gates[ONB_DELAY_PERIODS] == 0u) {
        return 0;
    }
    sim_open_setup(&o, ONB_UDC, SIM_R(0.0), nx);
    pmsm_dq_rhs_setup(&o.m, ONB_RS, ONB_LD, ONB_LQ, ONB_PSI_F, ONB_POLE_PAIRS, ONB_J, ONB_B, load_nm,
                      ONB_SPEED_IMPOSED);
    sim_open_interval(&o, p->x, ONB_DT, sim_inverter_substeps(ONB_DT, ONB_SUBSTEP_MAX_S));
    p->x[3] = pmsm_dq_wrap(p->x[3]);
    return 1;
}

static uint16_t finite_state(const onb_plant_t *p)
{
    uint16_t i;
    for (i = 0u; i < 5u; ++i) {
        const sim_real_t v = p->x[i];
        if (!(v > -ONB_HUGE && v < ONB_HUGE)) {
            return 0u;
        }
    }
    return 1u;
}

/* Steps 1.-3. of period k: the imposed speed, the sample, the torque reference (speed PI). */
static void sample_period(onb_plant_t *p, sim_real_t w_ref, sim_real_t load, sim_real_t *integral,
                          onb_sample_t *v)
{
    if (ONB_SPEED_IMPOSED != 0) {
        p->x[2] = w_ref;
    }
    pmsm_dq_currents(p->x[0], p->x[1], p->x[3], &v->ia, &v->ib);
    v->th = p->x[3];
    v->omega_e = (sim_real_t)ONB_POLE_PAIRS * p->x[2];
    v->t_ref = (ONB_SPEED_IMPOSED != 0)
                   ? load
                   : speed_pi_update(ONB_KP, ONB_KI, ONB_DT, ONB_LIMIT, integral, w_ref, p->x[2]);
}

void onboard_run(const hil_setpoints_t *sp, uint32_t overhead, onb_emit_fn emit, hil_run_end_t *end)
{
    static hil_sample_t buf[HIL_TELEMETRY_SAMPLES];
    static mpc_input_t in;
    static mpc_output_t out;
    onb_plant_t p;
    sim_real_t integral = SIM_R(0.0);
    uint32_t sum_lo = 0u, sum_hi = 0u, cmin = 0xFFFFFFFFu, cmax = 0u, width = 0u;
    uint32_t hist[8];
    int32_t k, samples = 0, changes = 0, status = 0;
    uint16_t nbuf = 0u, s = 0u, prev_dec = 0u, i;

    for (i = 0u; i < 5u; ++i) {
        p.x[i] = SIM_R(0.0);
    }
    for (i = 0u; i < 8u; ++i) {
        hist[i] = 0u;
    }
    onb_topo_reset();
    for (k = 0; k < sp->periods; ++k) {
        onb_sample_t v;
        uint32_t raw, cyc, bin;
        uint16_t dec;
        while ((uint16_t)(s + 1u) < sp->n_steps && sp->step_k[s + 1u] <= k) {
            ++s;
        }
        /* 1.-3. imposed speed, sampling, torque reference */
        sample_period(&p, sp->speed_rad_s[s], sp->load_nm[s], &integral, &v);
        /* 4. controller */
        SIM_MOTOR_INPUTS(in, v);
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
        dec = (uint16_t)out.HIL_DECISION_FIELD;
        if (k > 0 && dec != prev_dec) {
            ++changes;
        }
        prev_dec = dec;
        /* 5. the sample (the simulator trace's fields) */
        if (k % (int32_t)sp->decimation == 0) {
            hil_sample_t *r = &buf[nbuf];
            r->k = k;
            r->omega_m_rad_s = p.x[2];
            r->te_nm = pmsm_dq_te(p.x[0], p.x[1], ONB_LD, ONB_LQ, ONB_PSI_F, ONB_POLE_PAIRS);
            r->torque_ref_nm = v.t_ref;
            r->ia_a = v.ia;
            r->ib_a = v.ib;
            r->HIL_DECISION_FIELD = dec;
            r->fault = out.fault;
            ++nbuf;
            ++samples;
            if (nbuf == HIL_TELEMETRY_SAMPLES) {
                emit(buf, nbuf);
                nbuf = 0u;
            }
        }
        /* 6.-7. the decision queue and the plant over [t_k, t_k+1) */
        if (onb_topo_apply(&p, &out, sp->load_nm[s]) != 0) {
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
