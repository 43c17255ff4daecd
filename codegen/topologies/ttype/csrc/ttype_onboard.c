/*
 * ttype_onboard.c -- the T-type three-level part of the firmware's on-board
 * loop (firmware/runtime/onboard.h, the serial HIL's mode onboard), float32:
 * the controller's u_c1, u_c2 (0.5*Udc +- V_o), prev_vector and t_n_prev_s,
 * the decision queue of ttype_sim.c, the decisions checked and converted by
 * ttype_decision.h and the plant of ttype_rhs.h (the host plant's
 * right-hand side with the neutral point, written once) over the acting
 * decision's seven segments, each in sub-steps of at most ONB_SUBSTEP_MAX_S.
 *
 * Timing (docs/simulation.md "Timing"): the decision of k acts during
 * [t_k+d, t_k+d+1), d = ONB_DELAY_PERIODS (the simulator's
 * Plant.delay_periods, 0..2); prev_vector / t_n_prev_s are those of the
 * decision of k - max(d, 1); OOO (T_N = 0) before the first decisions.  The
 * step's gates_off travels with its decision: when the acting one is 1 the
 * inverter is open over the period (sim_inverter.h "The open inverter",
 * V_o held, as the host simulator's).  No dead time, device drops or sensor
 * non-idealities on board.
 */
#include "onboard.h"
#include "plant_config.h"
#include "ttype_decision.h"
#include "ttype_rhs.h"

/* decisions: [0] of k (after the shift of onb_topo_apply), [1] of k-1, [2] of k-2; their gates_off */
static ttype_decision_t queue[3];
static uint16_t gates[3];

void onb_topo_reset(void)
{
    ttype_decision_idle(&queue[0], ONB_DT);
    queue[1] = queue[0];
    queue[2] = queue[0];
    gates[0] = 0u;
    gates[1] = 0u;
    gates[2] = 0u;
}

void onb_topo_input(const onb_plant_t *p, mpc_input_t *in)
{
    const ttype_decision_t *told = &queue[(ONB_DELAY_PERIODS >= 2) ? 1 : 0]; /* before the shift */
    in->uc1_v = MPC_ENCODE_uc1_v(SIM_R(0.5) * ONB_UDC + p->x[4]);
    in->uc2_v = MPC_ENCODE_uc2_v(SIM_R(0.5) * ONB_UDC - p->x[4]);
    in->prev_vector = (uint16_t)told->vector;
    in->t_n_prev_s = MPC_ENCODE_t_n_prev_s(told->t_n_s);
}

int16_t onb_topo_apply(onb_plant_t *p, const mpc_output_t *out, sim_real_t load_nm)
{
    ttype_decision_t dec;
    const ttype_decision_t *acting;
    int i;
    if (ttype_decision_take(out, ONB_DT, &dec) != 0) {
        return -3;
    }
    queue[2] = queue[1];
    queue[1] = queue[0];
    queue[0] = dec;
    if (onb_gates_open_period(gates, out->gates_off, p, load_nm, 5) != 0) {
        return 0; /* gates off: every switch off, the currents in the outer diodes, V_o held */
    }
    acting = &queue[ONB_DELAY_PERIODS];
    for (i = 0; i < TTYPE_DECISION_N_SEG; ++i) {
        const sim_real_t len_s = acting->seg_s[i];
        ttype_rhs_t c;
        int lv[3];
        if (len_s > SIM_R(0.0) && ttype_rhs_levels((int)acting->states[i], lv) == 0) {
            ttype_rhs_setup(&c, lv, ONB_UDC, ONB_C_F, SIM_R(0.0));
            pmsm_dq_rhs_setup(&c.m, ONB_RS, ONB_LD, ONB_LQ, ONB_PSI_F, ONB_POLE_PAIRS, ONB_J, ONB_B,
                              load_nm, ONB_SPEED_IMPOSED);
            ttype_rhs_interval(&c, p->x, len_s, sim_inverter_substeps(len_s, ONB_SUBSTEP_MAX_S));
        }
    }
    p->x[3] = pmsm_dq_wrap(p->x[3]);
    return 0;
}
