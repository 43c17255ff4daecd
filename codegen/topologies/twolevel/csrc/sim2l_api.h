/*
 * sim2l_api.h -- closed-loop simulator of a two-level PMSM drive (plant in
 * float64 + the generated float32 controller step), driven from Python.
 *
 * This header is written so that cffi's ffi.cdef() parses it as is: it has
 * no preprocessor lines at all (hence no include guard: include it once per
 * translation unit), no macros and only plain C types.
 *
 * Specification: shared/spec/plant-and-metrics.md ("Plant", "Sampling",
 * "Timing") and shared/spec/mptc-two-level.md ("Parameters and scenarios").
 * Implementation: sim2l.c; plant: plant2l.c; controller: the generated step,
 * reached through the generated mpc_binding.h (MPC_STEP).
 *
 * One period k (k = 0 .. n-1 over all chunks, t_k = k*dt_s):
 *  1. speed_imposed != 0: omega_m := speed_ref[k] (the load machine holds
 *     the speed profile).
 *  2. Sample the plant at t_k: i_a, i_b, theta_e in [0, 2*pi), omega_e =
 *     p*omega_m, Udc.
 *  3. Torque reference T*(k):
 *     speed_imposed == 0: speed PI in double on the mechanical speed error
 *       e = speed_ref[k] - omega_m (rad/s):  u = kp*e + I;  T* = clamp(u,
 *       +-limit_nm).  Anti-windup by conditional integration: I += ki*e*dt_s
 *       unless u is saturated and e drives it further into saturation; I is
 *       then also clamped to +-limit_nm.
 *     speed_imposed != 0: the speed loop is open (its error would be zero);
 *       T*(k) = load_nm[k], read as the torque the drive must deliver
 *       against the load machine (the steady-state equilibrium).
 *  4. Controller input (every field cast to float): ia_a, ib_a, theta_e_rad,
 *     omega_e_rad_s, udc_v, torque_ref_nm, prev_sw = the decision of period
 *     k-1 (0 = 000 before the first period).  MPC_STEP(&in, &out).
 *  5. Record period k in the trace (sample-instant values).
 *  6. Switching state applied during [t_k, t_k+1):
 *       delay_compensation == 0: out.sw (decision of k acts in the same period)
 *       delay_compensation != 0: prev_sw (decision of k-1; the decision of k
 *       acts during [t_k+1, t_k+2)).  In both cases prev_sw, as given to the
 *       step, is the state the inverter holds at the sample instant.
 *  7. plant2l_advance over dt_s with `substeps` RK4 sub-steps and the load
 *     torque load_nm[k] (ignored when the speed is imposed).
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
    /* inverter: ideal switches, stiff DC link */
    double udc_v;
    /* timing */
    double dt_s;            /* control (sampling) period */
    int substeps;           /* RK4 sub-steps per period (dt_s/substeps <= 1 us) */
    /* speed PI (mechanical speed error in rad/s -> torque reference in N*m) */
    double kp;
    double ki;
    double limit_nm;        /* output clamp and integrator clamp, +- */
    int speed_imposed;      /* 1: omega_m follows speed_ref, T* = load_nm */
    int delay_compensation; /* 0/1, see step 6 above */
} sim2l_params_t;

/* Everything carried from one sim2l_run call to the next (chunked runs). */
typedef struct {
    double i_d_a;           /* plant: d-axis current, A */
    double i_q_a;           /* plant: q-axis current, A */
    double omega_m_rad_s;   /* plant: mechanical speed, rad/s */
    double theta_e_rad;     /* plant: electrical angle, rad, in [0, 2*pi) */
    double pi_integral_nm;  /* speed PI integrator, N*m */
    int prev_sw;            /* decision of the previous period, Sa*4+Sb*2+Sc */
    long k;                 /* index of the next period (t = k*dt_s) */
} sim2l_state_t;

/*
 * Trace: caller-allocated arrays of at least n elements, index j = period
 * k0 + j of the call (k0 = state->k on entry).  Any pointer may be NULL
 * (that quantity is not recorded).  Values are taken at the sample instant.
 */
typedef struct {
    double *t_s;              /* k*dt_s */
    double *speed_ref_rad_s;  /* mechanical speed reference */
    double *omega_m_rad_s;    /* plant mechanical speed */
    double *te_nm;            /* plant torque */
    double *torque_ref_nm;    /* T* given to the controller (double, before the float cast) */
    double *psi_wb;           /* plant stator-flux magnitude */
    double *ia_a;             /* plant phase current a */
    double *ib_a;             /* plant phase current b */
    double *theta_e_rad;      /* plant electrical angle in [0, 2*pi) */
    unsigned short *sw;       /* controller decision out.sw */
    unsigned short *applied_sw; /* state applied by the inverter during [t_k, t_k+1) */
    unsigned short *vector;   /* out.vector, 0..6 */
    unsigned short *n_eval;   /* out.n_eval (Cal of this step) */
    unsigned short *fault;    /* out.fault bits */
    float *te_est_nm;         /* out.te_est_nm (controller estimate) */
    float *psi_est_wb;        /* out.psi_est_wb (controller estimate) */
} sim2l_trace_t;

/*
 * Validate p and set the initial state: currents 0, speed 0, angle 0, PI
 * integrator 0, prev_sw 0 (000), k 0.  The caller may change the state's
 * fields afterwards (e.g. an initial speed).  Returns 0, or -1 if p is
 * invalid (non-positive inductance, dt_s or Udc, J <= 0 without imposed
 * speed, substeps < 1, pole_pairs < 1, limit_nm < 0, non-finite values).
 */
int sim2l_init(const sim2l_params_t *p, sim2l_state_t *state);

/*
 * Run n periods from *state (updated in place: a later call continues
 * exactly where this one stopped, so chunked runs equal one long run bit
 * for bit).  speed_ref_rad_s[j], load_nm[j] (j < n) hold for period k0 + j.
 * Returns 0 on success; -1 invalid arguments (nothing done); -2 the plant
 * state became non-finite (state->k is the period that failed, the trace is
 * filled up to and including it); -3 the controller returned a switching
 * state outside 0..7 (state->k is that period; its trace entry is filled).
 */
int sim2l_run(const sim2l_params_t *p, const double *speed_ref_rad_s, const double *load_nm,
              long n, sim2l_trace_t *trace, sim2l_state_t *state);
