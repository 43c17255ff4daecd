/*
 * twolevel_onboard.c -- the two-level part of the firmware's on-board loop
 * (firmware/runtime/onboard.h, the serial HIL's mode onboard), float32: the
 * controller's udc_v and prev_sw, the decision queue of twolevel_sim.c and
 * the plant of twolevel_rhs.h (the host plant's right-hand side, written
 * once) holding the acting switching state over the whole period.
 *
 * Timing (docs/simulation.md "Timing"): the decision of k acts during
 * [t_k+d, t_k+d+1), d = ONB_DELAY_PERIODS (the simulator's
 * Plant.delay_periods, 0..2); prev_sw is the state the inverter applies
 * during [t_k, t_k+1), the decision of k - max(d, 1) (for d = 0 the state
 * held at the sample instant); 000 before the first decisions.  The step's
 * gates_off travels with its decision: when the acting one is 1 the
 * inverter is open over the period (sim_inverter.h "The open inverter",
 * as the host simulator's).  No dead time, device drops or sensor
 * non-idealities on board.
 */
#include "onboard.h"
#include "plant_config.h"
#include "twolevel_rhs.h"

/* decisions: [0] of k (after the shift of onb_topo_apply), [1] of k-1, [2] of k-2; their gates_off */
static uint16_t queue[3];
static uint16_t gates[3];

void onb_topo_reset(void)
{
    int i;
    for (i = 0; i < 3; ++i) {
        queue[i] = 0u;
        gates[i] = 0u;
    }
}

void onb_topo_input(const onb_plant_t *p, mpc_input_t *in)
{
    (void)p;
    in->udc_v = MPC_ENCODE_udc_v(ONB_UDC);
    in->prev_sw = queue[(ONB_DELAY_PERIODS >= 2) ? 1 : 0]; /* of k - max(d, 1), before the shift */
}

int16_t onb_topo_apply(onb_plant_t *p, const mpc_output_t *out, sim_real_t load_nm)
{
    twolevel_rhs_t c;
    int lv[3];
    if (out->sw > 7u) {
        return -3;
    }
    queue[2] = queue[1];
    queue[1] = queue[0];
    queue[0] = out->sw;
    if (onb_gates_open_period(gates, out->gates_off, p, load_nm, 4) != 0) {
        return 0; /* gates off: every switch off, the currents in the diodes */
    }
    twolevel_rhs_levels((int)queue[ONB_DELAY_PERIODS], lv);
    twolevel_rhs_setup(&c, lv, ONB_UDC, SIM_R(0.0));
    pmsm_dq_rhs_setup(&c.m, ONB_RS, ONB_LD, ONB_LQ, ONB_PSI_F, ONB_POLE_PAIRS, ONB_J, ONB_B, load_nm,
                      ONB_SPEED_IMPOSED);
    twolevel_rhs_interval(&c, p->x, ONB_DT, sim_inverter_substeps(ONB_DT, ONB_SUBSTEP_MAX_S));
    return 0;
}
