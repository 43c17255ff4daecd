/*
 * sim3l_api.h -- closed-loop simulator of a T-type three-level PMSM drive
 * (plant in float64 + the generated float32 controller step), driven from
 * Python.
 *
 * This header is written so that cffi's ffi.cdef() parses it as is: it has
 * no preprocessor lines at all (hence no include guard: include it once per
 * translation unit), no macros and only plain C types.
 *
 * Specification: shared/spec/plant-and-metrics.md ("Plant", "Sampling",
 * "Timing") and shared/spec/mpdtc-three-level.md (inverter, neutral point,
 * "one-step delay compensation", scenarios).  Implementation: sim3l.c;
 * plant: plant3l.c (model and V_o sign convention in plant3l.h); controller:
 * the generated step, reached through the generated mpc_binding.h
 * (mpc_input_t, mpc_output_t, MPC_STEP).
 *
 * Timing: the three-level controller always uses one-step delay
 * compensation: the decision computed from the samples at t_k is applied
 * during [t_k+1, t_k+2).  The state carries the decision to be applied in
 * the current period ("applied" below); before the first period that is
 * OOO (vector 13, states all 13, seg_s = {dt_s, 0, ..., 0}, T_N = 0).
 *
 * One period k (k = 0 .. n-1 over all chunks, t_k = k*dt_s):
 *  1. speed_imposed != 0: omega_m := speed_ref[k].
 *  2. Sample the plant at t_k: i_a, i_b, theta_e in [0, 2*pi), omega_e =
 *     p*omega_m, V_o; u_c1 = 0.5*Udc + V_o, u_c2 = 0.5*Udc - V_o (double).
 *  3. Torque reference T*(k): speed PI exactly as sim2l (sim2l_api.h step 3),
 *     or T* = load_nm[k] when the speed is imposed.
 *  4. Controller input (every field cast to float): ia_a, ib_a, theta_e_rad,
 *     omega_e_rad_s, uc1_v, uc2_v, torque_ref_nm, prev_vector = the vector
 *     applied during [t_k, t_k+1) (the decision of k-1; 13 = OOO at k = 0),
 *     t_n_prev_s = its T_N (0 at k = 0).  MPC_STEP(&in, &out).
 *  5. Record period k: sample-instant values, the decision, and the
 *     waveform of the applied period (its 7 segments).
 *  6. Check the decision: vector <= 62, states[i] <= 26, seg_s[i] finite and
 *     >= 0, |sum seg_s - dt_s| <= 1e-4*dt_s.  It is stored (for period k+1)
 *     in double with the last non-empty segment set to dt_s minus the sum of
 *     the others, so that the plant's period is dt_s (the float32 sum is
 *     off by ~1e-7 relative).
 *  7. plant3l_advance_segments over the applied 7 segments with
 *     substep_max_s and load_nm[k].
 *
 * Leg-level changes of period k: sum over the legs and over consecutive
 * NON-EMPTY applied segments of |S_x(i) - S_x(i-1)| (a P<->N jump counts
 * 2), including the boundary from the last non-empty segment of the
 * previous period (OOO before period 0).
 */

/* Parameters: motor, inverter, timing, speed loop (SI units). */
typedef struct {
    /* motor (dq model) */
    double rs_ohm;
    double ld_h;
    double lq_h;
    double psi_f_wb;
    int pole_pairs;
    double j_kgm2;
    double b_nms;
    /* inverter: ideal switches; stiff DC source across the two capacitors */
    double udc_v;
    double c_f;             /* each DC-link capacitor C1 = C2, F */
    /* timing */
    double dt_s;            /* control (sampling) period Ts */
    double substep_max_s;   /* largest RK4 sub-step (1e-6) */
    /* speed PI (mechanical speed error in rad/s -> torque reference in N*m) */
    double kp;
    double ki;
    double limit_nm;        /* output clamp and integrator clamp, +- */
    int speed_imposed;      /* 1: omega_m follows speed_ref, T* = load_nm */
} sim3l_params_t;

/* Everything carried from one sim3l_run call to the next (chunked runs). */
typedef struct {
    double i_d_a;                 /* plant: d-axis current, A */
    double i_q_a;                 /* plant: q-axis current, A */
    double omega_m_rad_s;         /* plant: mechanical speed, rad/s */
    double theta_e_rad;           /* plant: electrical angle, rad, in [0, 2*pi) */
    double vo_v;                  /* plant: neutral-point voltage (u_c1 - u_c2)/2, V */
    double pi_integral_nm;        /* speed PI integrator, N*m */
    int applied_vector;           /* vector (0..62) applied in the current period */
    double applied_t_n_s;         /* its T_N, s (as the controller gave it) */
    unsigned short applied_states[7]; /* its states per segment, 0..26 */
    double applied_seg_s[7];      /* its segment durations, s (sum = dt_s) */
    int last_state;               /* state at the end of the previous period (13 = OOO) */
    long k;                       /* index of the next period (t = k*dt_s) */
} sim3l_state_t;

/*
 * Trace: caller-allocated arrays, index j = period k0 + j of the call
 * (k0 = state->k on entry); per-period arrays hold n elements, per-segment
 * arrays (uab_v, seg_s, seg_states) 7*n, segment i of period j at 7*j + i.
 * Any pointer may be NULL (not recorded).
 */
typedef struct {
    /* sample instant t_k (plant values in double) */
    double *t_s;              /* k*dt_s */
    double *speed_ref_rad_s;  /* mechanical speed reference */
    double *omega_m_rad_s;    /* plant mechanical speed */
    double *te_nm;            /* plant torque */
    double *torque_ref_nm;    /* T* given to the controller (before the float cast) */
    double *psi_wb;           /* plant stator-flux magnitude */
    double *ia_a;             /* plant phase currents */
    double *ib_a;
    double *ic_a;
    double *theta_e_rad;      /* plant electrical angle in [0, 2*pi) */
    double *vo_v;             /* plant neutral-point voltage */
    /* decision of period k (controller outputs, C types kept) */
    unsigned short *vector;   /* out.vector, 0..62 */
    unsigned short *n_eval;   /* out.n_eval */
    unsigned short *fault;    /* out.fault */
    float *t_n_s;             /* out.t_n_s */
    float *te_est_nm;         /* out.te_est_nm */
    float *psi_est_wb;        /* out.psi_est_wb */
    float *psi_ref_wb;        /* out.psi_ref_wb (controller's flux reference) */
    float *vo_est_v;          /* out.vo_v */
    /* the period actually applied during [t_k, t_k+1) (decision of k-1) */
    unsigned short *applied_vector;
    unsigned short *leg_changes;  /* one-level leg changes, see above */
    double *uab_v;            /* 7*n: u_ab per segment (V_o at the segment start) */
    double *seg_s;            /* 7*n: applied segment durations, s (0: skipped) */
    unsigned short *seg_states; /* 7*n: applied states per segment */
} sim3l_trace_t;

/*
 * Validate p and set the initial state: currents, speed, angle, V_o and PI
 * integrator 0, applied period OOO (see "Timing"), last_state 13, k 0.  The
 * caller may change the state's fields afterwards.  Returns 0, or -1 if p is
 * invalid (non-positive inductance, dt_s, Udc, C or substep_max_s, J <= 0
 * without imposed speed, pole_pairs < 1, limit_nm < 0, non-finite values).
 */
int sim3l_init(const sim3l_params_t *p, sim3l_state_t *state);

/*
 * Run n periods from *state (updated in place: chunked runs equal one long
 * run bit for bit).  speed_ref_rad_s[j], load_nm[j] (j < n) hold for period
 * k0 + j.  Returns 0 on success; -1 invalid arguments (nothing done); -2 the
 * plant state became non-finite (state->k is the period that failed, the
 * trace is filled up to and including it); -3 the controller returned an
 * invalid decision (state->k is that period; its trace entry is filled).
 */
int sim3l_run(const sim3l_params_t *p, const double *speed_ref_rad_s, const double *load_nm,
              long n, sim3l_trace_t *trace, sim3l_state_t *state);
