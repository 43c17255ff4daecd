/*
 * sim_inverter.h -- the inverter non-idealities every topology's plant
 * shares: dead time and device voltage drops, on leg LEVELS (two-level:
 * 0 = lower rail, 1 = upper; T-type: -1 = N, 0 = O, +1 = P) (hand-written
 * runtime, written once on sim_real_t: float64 on the host, float32 on
 * board, sim_real.h).
 *
 * Specification: docs/simulation.md "Inverter non-idealities".
 *
 * Dead time (sim_inverter_dead_levels): at an edge of leg x from level a to
 * level b the switch being turned off opens at once and the one being turned
 * on closes dead_time_s later; in between the phase current i_x freewheels
 * through a diode, so the leg sits at
 *   min(a, b) if i_x > 0 (current out of the leg: drawn from the lower level),
 *   max(a, b) if i_x < 0 (current into the leg: pushed to the higher level),
 *   a         if i_x == 0,
 * with i_x taken at the edge and held for the dead time (the current moves
 * by a few mA in 1 us).  A rising edge with i_x > 0 therefore loses
 * (b - a)*dead_time volt-seconds, a falling edge with i_x < 0 gains them;
 * the other two lose nothing: the error follows the current's sign.  (Two-level:
 * the upper/lower pair; T-type: P<->O through T1/T3, O<->N through T2/T4,
 * the middle pair holding the freewheeling path.)
 *
 * Device drops (sim_inverter_drop_ab): each conducting device (IGBT or
 * diode) drops device_drop_v against the phase current, so the leg voltage
 * is u_x - n_x*V_d*sign(i_x), n_x the devices in the leg's conducting path
 * (the topology's: two-level 1; T-type 1 at P/N, 2 at O).  Evaluated at
 * every RK4 stage from the stage's currents (the drop flips with the
 * current's sign).  Its alpha-beta part (the common mode cancels):
 *   du_alpha = (2/3)*(d_a - (d_b + d_c)/2),  du_beta = (d_b - d_c)/sqrt(3).
 *
 * C99, no dynamic memory, no global state.  Not part of any cffi cdef.
 */
#ifndef SIM_INVERTER_H
#define SIM_INVERTER_H

#include "pmsm_dq.h"
#include "sim_real.h"

/* sign(x) in {-1, 0, +1} */
static inline sim_real_t sim_inverter_sign(sim_real_t x)
{
    return (x > SIM_R(0.0)) ? SIM_R(1.0) : ((x < SIM_R(0.0)) ? SIM_R(-1.0) : SIM_R(0.0));
}

/* Levels of the three legs during the dead time of the edges from[] -> to[]
 * (legs without an edge: to[x]) given the phase currents i_abc[] (A). */
static inline void sim_inverter_dead_levels(const int from[3], const int to[3],
                                            const sim_real_t i_abc[3], int out[3])
{
    int x;
    for (x = 0; x < 3; ++x) {
        const int lo = from[x] < to[x] ? from[x] : to[x];
        const int hi = from[x] < to[x] ? to[x] : from[x];
        if (from[x] == to[x]) {
            out[x] = to[x];
        } else if (i_abc[x] > SIM_R(0.0)) {
            out[x] = lo;
        } else if (i_abc[x] < SIM_R(0.0)) {
            out[x] = hi;
        } else {
            out[x] = from[x];
        }
    }
}

/* 1 if any leg changes level. */
static inline int sim_inverter_edges(const int from[3], const int to[3])
{
    return from[0] != to[0] || from[1] != to[1] || from[2] != to[2];
}

/* Alpha-beta voltage of the device drops (V) at the stage currents i_d, i_q
 * and cos/sin of the stage angle; n_dev[x]: devices in leg x's path. */
static inline void sim_inverter_drop_ab(sim_real_t drop_v, const sim_real_t n_dev[3], sim_real_t id,
                                        sim_real_t iq, sim_real_t cs, sim_real_t sn,
                                        sim_real_t *du_alpha, sim_real_t *du_beta)
{
    const sim_real_t i_al = id * cs - iq * sn;
    const sim_real_t i_be = id * sn + iq * cs;
    const sim_real_t ia = i_al;
    const sim_real_t ib = -SIM_R(0.5) * i_al + PMSM_DQ_SQRT3_HALF * i_be;
    const sim_real_t ic = -ia - ib;
    const sim_real_t da = -drop_v * n_dev[0] * sim_inverter_sign(ia);
    const sim_real_t db = -drop_v * n_dev[1] * sim_inverter_sign(ib);
    const sim_real_t dc = -drop_v * n_dev[2] * sim_inverter_sign(ic);
    *du_alpha = (SIM_R(2.0) / SIM_R(3.0)) * (da - SIM_R(0.5) * (db + dc));
    *du_beta = PMSM_DQ_SQRT3_INV * (db - dc);
}

/* The device drops of n_dev[] devices per leg added to the dq voltage (ud, uq) at the stage
 * currents (id, iq) and cos/sin of the stage angle: u_dq += Park(du_alpha, du_beta). */
static inline void sim_inverter_add_drops(sim_real_t drop_v, const sim_real_t n_dev[3], sim_real_t id,
                                          sim_real_t iq, sim_real_t cs, sim_real_t sn,
                                          sim_real_t *ud, sim_real_t *uq)
{
    sim_real_t dua, dub, dud, duq;
    sim_inverter_drop_ab(drop_v, n_dev, id, iq, cs, sn, &dua, &dub);
    pmsm_dq_park(dua, dub, cs, sn, &dud, &duq);
    *ud += dud;
    *uq += duq;
}

/* Phase currents (i_a, i_b, i_c) of a motor state, A. */
static inline void sim_inverter_phase_currents(sim_real_t id, sim_real_t iq, sim_real_t theta_e_rad,
                                               sim_real_t i_abc[3])
{
    pmsm_dq_currents(id, iq, theta_e_rad, &i_abc[0], &i_abc[1]);
    i_abc[2] = -i_abc[0] - i_abc[1];
}

/*
 * Sub-steps of a piece of length len_s of a constant-voltage interval whose
 * largest sub-step is h_max_s: ceil(len_s/h_max_s) with a relative
 * tolerance SIM_SUBSTEP_TOL (float64 1e-9; so that len_s = n*h_max_s gives
 * n), at least 1, at most SIM_SUBSTEP_MAX.
 */
static inline int sim_inverter_substeps(sim_real_t len_s, sim_real_t h_max_s)
{
    const sim_real_t nd = SIM_CEIL(len_s / h_max_s - SIM_SUBSTEP_TOL);
    return (nd < SIM_R(1.0)) ? 1 : (nd > (sim_real_t)SIM_SUBSTEP_MAX ? SIM_SUBSTEP_MAX : (int)nd);
}

#endif /* SIM_INVERTER_H */
