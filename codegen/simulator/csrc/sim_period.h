/*
 * sim_period.h -- the steps of one control period that every topology's
 * closed-loop simulator shares (hand-written runtime, float64).
 *
 * Specification: docs/simulation.md ("Plant", "Sampling", "Timing",
 * "Sensors") and docs/algorithms.md (two-level MPTC) ("Parameters and
 * scenarios": speed PI).  Structs: the generated sim_api.h (from the field
 * lists of codegen/simulator/records.py), included here once per
 * translation unit.
 *
 * One period k (t_k = k*dt_s) of every topology:
 *  1. speed_imposed != 0: omega_m := speed_ref[k] (the load machine holds
 *     the speed profile).                                    sim_period_sample
 *  2. The plant at t_k (trace): i_a, i_b (inverse Park, inverse Clarke),
 *     theta_e in [0, 2*pi).                                  sim_period_sample
 *     What the controller sees (sim_sensors.h): the plant at t_k - tau
 *     (tau = measurement_delay_s; the state kept from the previous period's
 *     integration, the plant at t_0 for k = 0), through the current sensors
 *     and the encoder; omega_e = p*omega_m,meas.  With every non-ideality
 *     off these are the values at t_k, bit for bit.
 *  3. Torque reference T*(k):                                sim_period_sample
 *     speed_imposed == 0: speed PI (speed_pi.h) in double on the measured
 *       mechanical speed error e = speed_ref[k] - omega_m,meas (rad/s), T*
 *       clamped to +-limit_nm with conditional-integration anti-windup;
 *     speed_imposed != 0: the speed loop is open; T*(k) = load_nm[k], read
 *       as the torque the drive must deliver against the load machine.
 *  4. Controller step with the topology's inputs, every field converted to
 *     the step's number format as a real controller sees them (the motor's:
 *     SIM_MOTOR_INPUTS, sim_motor_inputs.h; the rest: the topology's sim .c).
 *  5. Record the sample instant and the decision.  sim_period_record
 *  6./7. The topology's decision queue (actuation delay d = delay_periods:
 *     the decision of k acts during [t_k+d, t_k+d+1), and so does the
 *     step's gates_off of k: 1 opens the inverter, every switch off, the
 *     currents in the diodes, sim_inverter.h "The open inverter") and plant
 *     integration over [t_k, t_k+1) with its dead time and device drops
 *     (sim_inverter.h), load torque load_nm[k] (ignored when the speed is
 *     imposed); the plant state at t_k+1 - tau is kept for the next
 *     period's samples.
 *  Commit: the plant state, the mechanical angle, the encoder count, the
 *  kept samples, the PI integrator, k += 1.                  sim_period_commit
 *
 * C99, no dynamic memory, no global state.  Not part of any cffi cdef.
 */
#ifndef SIM_PERIOD_H
#define SIM_PERIOD_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "sim_api.h"
#include "sim_motor_inputs.h"

/* Largest actuation delay, periods (the depth of the topologies' decision queues). */
#define SIM_PERIOD_MAX_DELAY 2

/* Values of steps 1-3 of one period. */
typedef struct {
    double w_ref;     /* speed_ref[k], rad/s */
    double load;      /* load_nm[k], N*m */
    double ia, ib;    /* the controller's phase currents (sensor chain), A */
    double th;        /* the controller's electrical angle in [0, 2*pi), rad */
    double omega_m;   /* the controller's mechanical speed, rad/s (speed PI input) */
    double omega_e;   /* p*omega_m (the controller's), rad/s */
    double ia_plant, ib_plant; /* plant phase currents at t_k, A */
    double th_plant;  /* plant electrical angle at t_k in [0, 2*pi), rad */
    int64_t enc_count; /* encoder count of this sample (0 without an encoder) */
    double t_ref;     /* T*, N*m */
    double integral;  /* PI integrator after this period (committed with it), N*m */
} sim_sample_t;

/* Shared parameter checks (pmsm_dq_sim_params_valid, sim_period_plant_valid); 1 valid, 0 not
 * (p NULL: 0). */
int sim_period_params_valid(const sim_params_t *p);

/* Initial state: plant at rest, angles 0, PI integrator 0, k 0, encoder counts 0, the kept
 * samples equal to the plant. */
void sim_period_reset(sim_state_t *s);

/* Shared run-argument checks: state, n >= 0, arrays given when n > 0, k >= 0. 1 valid. */
int sim_period_args_valid(const sim_state_t *s, long n, const double *speed_ref_rad_s,
                          const double *load_nm);

/* Shared parameter checks of the plant timing and non-idealities: delay_periods
 * 0..SIM_PERIOD_MAX_DELAY, 0 <= dead_time_s < dt_s, device_drop_v >= 0, gain error > -1,
 * adc_bits 0..30 with adc_full_scale_a > 0 when on, noise_a >= 0, encoder_bits 0..30,
 * 0 <= measurement_delay_s <= dt_s, all finite; integrator SIM_INTEGRATOR_RK4 or _EXACT (sim_exact.h).
 * 1 valid. */
int sim_period_plant_valid(const sim_params_t *p);

/* 1 if period k's samples come from the kept state at t_k - tau (tau > 0, k > 0). */
int sim_period_delayed(const sim_params_t *p, const sim_state_t *s);

/* Offset into the period of the instant whose plant state the next period samples
 * (dt_s - measurement_delay_s), or -1 without a measurement delay. */
double sim_period_snap_offset(const sim_params_t *p);

/* Length of the part of the piece [t0, t0 + len) before the snapshot offset t_snap, or -1 if
 * the snapshot instant is not in the piece (t_snap < 0: none). */
static inline double sim_period_snap_split(double t0, double len, double t_snap)
{
    return (t_snap >= 0.0 && t_snap >= t0 && t_snap < t0 + len) ? t_snap - t0 : -1.0;
}

/* Steps 1-3 on the plant motor state x (step 1 may set its speed). */
void sim_period_sample(const sim_params_t *p, const sim_state_t *s, pmsm_state_t *x,
                       double w_ref, double load, sim_sample_t *out);

/* Step 5, shared trace members of period j: the sample instant (plant
 * torque and flux of x), what the controller saw, and its vector, n_eval,
 * fault, gates_off and estimates; open: the inverter open during [t_k, t_k+1). */
void sim_period_record(const sim_trace_t *tr, long j, const sim_params_t *p, const sim_state_t *s,
                       const pmsm_state_t *x, const sim_sample_t *v, uint16_t vector,
                       uint16_t n_eval, uint16_t fault, uint16_t gates_off, int open,
                       float te_est_nm, float psi_est_wb);

/* 1 if every motor state value is finite. */
int sim_period_finite(const pmsm_state_t *x);

/* The motor state as the first four entries of an RK4 state vector
 * (pmsm_rk4.h: i_d, i_q, omega_m, theta_e), and back. */
static inline void sim_period_motor_load(const pmsm_state_t *s, double *x)
{
    x[0] = s->i_d_a;
    x[1] = s->i_q_a;
    x[2] = s->omega_m_rad_s;
    x[3] = s->theta_e_rad;
}

static inline void sim_period_motor_store(pmsm_state_t *s, const double *x)
{
    s->i_d_a = x[0];
    s->i_q_a = x[1];
    s->omega_m_rad_s = x[2];
    s->theta_e_rad = x[3];
}

/* Commit period k: plant motor state x (at t_k+1), its mechanical angle, the encoder count of v,
 * the kept plant state at t_k+1 - tau (snap; NULL without a measurement delay), the PI
 * integrator, k += 1. */
void sim_period_commit(const sim_params_t *p, sim_state_t *s, const pmsm_state_t *x,
                       const pmsm_state_t *snap, const sim_sample_t *v);

/*
 * The entry points every topology's simulator has (declared in sim_api.h):
 * api##_run, api##_hil_input and api##_hil_finish, defined by
 * SIM_PERIOD_ENTRY_POINTS(api, plant_t) in the topology's sim .c, after its
 * mpc_binding.h and these static functions of that file (P, S, T the api's
 * params, state and trace types, x the topology's plant_t):
 *   int  params_valid(const P *p)        the parameters (p may be NULL), 1 valid
 *   int  state_valid(const S *state)     the topology's carried state, 1 valid
 *   void plant_load(const S *state, plant_t *x)
 *                                        the plant at the sample instant of
 *                                        period state->common.k
 *   void period_input(const P *p, const S *state, plant_t *x, double w_ref,
 *                     double load, sim_sample_t *v, mpc_input_t *in)
 *                                        steps 1.-4. (step 1 may set x's speed)
 *   int  period_finish(const P *p, S *state, plant_t *x, const sim_sample_t *v,
 *                      const mpc_output_t *out, const T *tr, long j)
 *                                        steps 5.-7. with the decision out and
 *                                        the commit of the period (trace entry j)
 * Every period of api##_run and of api##_hil_finish runs the same
 * sim_period_one (the plant reloaded from the committed state), so a run
 * through the HIL entry points with the compiled step's decisions equals
 * api##_run bit for bit.
 */
#define SIM_PERIOD_ENTRY_POINTS(api, plant_t)                                                      \
    /* The given trace, or one that records nothing. */                                            \
    static void sim_period_trace(const api##_trace_t *trace, api##_trace_t *tr)                    \
    {                                                                                              \
        if (trace != NULL) {                                                                       \
            *tr = *trace;                                                                          \
        } else {                                                                                   \
            memset(tr, 0, sizeof *tr);                                                             \
        }                                                                                          \
    }                                                                                              \
                                                                                                   \
    /* p and the carried state are valid (state may be NULL). */                                   \
    static int sim_period_valid(const api##_params_t *p, const api##_state_t *state)               \
    {                                                                                              \
        return params_valid(p) && state != NULL && state->common.k >= 0 && state_valid(state);     \
    }                                                                                              \
                                                                                                   \
    /* Period state->common.k (trace entry j) with the decision out, or (out NULL) the step's. */  \
    static int sim_period_one(const api##_params_t *p, api##_state_t *state, double w_ref,         \
                              double load, const mpc_output_t *out, const api##_trace_t *tr,       \
                              long j)                                                              \
    {                                                                                              \
        plant_t x;                                                                                 \
        sim_sample_t v;                                                                            \
        mpc_input_t in;                                                                            \
        mpc_output_t step_out;                                                                     \
                                                                                                   \
        plant_load(state, &x);                                                                     \
        period_input(p, state, &x, w_ref, load, &v, &in);                                          \
        if (out == NULL) {                                                                         \
            memset(&step_out, 0, sizeof step_out);                                                 \
            MPC_STEP(&in, &step_out);                                                              \
            out = &step_out;                                                                       \
        }                                                                                          \
        return period_finish(p, state, &x, &v, out, tr, j);                                        \
    }                                                                                              \
                                                                                                   \
    int api##_run(const api##_params_t *p, const double *speed_ref_rad_s, const double *load_nm,   \
                  long n, api##_trace_t *trace, api##_state_t *state)                              \
    {                                                                                              \
        api##_trace_t tr;                                                                          \
        long j;                                                                                    \
                                                                                                   \
        if (!sim_period_valid(p, state)                                                            \
            || !sim_period_args_valid(&state->common, n, speed_ref_rad_s, load_nm)) {              \
            return -1;                                                                             \
        }                                                                                          \
        sim_period_trace(trace, &tr);                                                              \
        for (j = 0; j < n; ++j) {                                                                  \
            const int rc = sim_period_one(p, state, speed_ref_rad_s[j], load_nm[j], NULL, &tr, j); \
            if (rc != 0) {                                                                         \
                return rc;                                                                         \
            }                                                                                      \
        }                                                                                          \
        return 0;                                                                                  \
    }                                                                                              \
                                                                                                   \
    int api##_hil_input(const api##_params_t *p, const api##_state_t *state,                       \
                        double speed_ref_rad_s, double load_nm, void *in)                          \
    {                                                                                              \
        plant_t x;                                                                                 \
        sim_sample_t v;                                                                            \
                                                                                                   \
        if (!sim_period_valid(p, state) || in == NULL) {                                           \
            return -1;                                                                             \
        }                                                                                          \
        plant_load(state, &x);                                                                     \
        period_input(p, state, &x, speed_ref_rad_s, load_nm, &v, (mpc_input_t *)in);              \
        return 0;                                                                                  \
    }                                                                                              \
                                                                                                   \
    int api##_hil_finish(const api##_params_t *p, api##_state_t *state, double speed_ref_rad_s,    \
                         double load_nm, const void *out, const api##_trace_t *trace, long j)      \
    {                                                                                              \
        api##_trace_t tr;                                                                          \
                                                                                                   \
        if (!sim_period_valid(p, state) || out == NULL || j < 0) {                                 \
            return -1;                                                                             \
        }                                                                                          \
        sim_period_trace(trace, &tr);                                                              \
        return sim_period_one(p, state, speed_ref_rad_s, load_nm, (const mpc_output_t *)out, &tr,  \
                              j);                                                                  \
    }

#endif /* SIM_PERIOD_H */
