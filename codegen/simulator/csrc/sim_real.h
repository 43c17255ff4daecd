/*
 * sim_real.h -- the real type of the plant's C, chosen once per translation
 * unit (hand-written runtime).
 *
 * The plant core -- the dq motor (pmsm_dq.h), RK4 (pmsm_rk4.h), the
 * inverter non-idealities (sim_inverter.h), the speed PI (speed_pi.h), the
 * controller's motor inputs (sim_motor_inputs.h) and each topology's
 * right-hand side (<topology>_rhs.h) -- is written once on sim_real_t and
 * compiled twice:
 *   - float64 for the host simulator (the default): sim_real_t is double,
 *     SIM_R(x) is the literal x, the libm functions are the double ones, so
 *     every expression is the double code's, token for token;
 *   - float32 for the firmware's on-board loop (firmware/runtime/onboard.h
 *     defines SIM_REAL_F32 before its first include): float, x##f literals,
 *     the float libm functions (C28x-safe: no double arithmetic).
 * SIM_REAL_IS_F32 says which one a translation unit has.
 *
 * C99.  Not part of any cffi cdef.
 */
#ifndef SIM_REAL_H
#define SIM_REAL_H

#include <math.h>

#ifdef SIM_REAL_F32
typedef float sim_real_t;
#define SIM_REAL_IS_F32 1
#define SIM_R(x) x##f
#define SIM_COS cosf
#define SIM_SIN sinf
#define SIM_FABS fabsf
#define SIM_FMOD fmodf
#define SIM_CEIL ceilf
/* relative tolerance of a piece's sub-step count (sim_inverter_substeps): a few float ulps */
#define SIM_SUBSTEP_TOL 1e-4f
/* relative tolerance of a zero phase current of the open inverter (sim_inverter.h): a few float ulps */
#define SIM_ZERO_TOL 1e-4f
/* most sub-steps of one piece (a 16-bit int holds it) */
#define SIM_SUBSTEP_MAX 10000
#else
typedef double sim_real_t;
#define SIM_REAL_IS_F32 0
#define SIM_R(x) x
#define SIM_COS cos
#define SIM_SIN sin
#define SIM_FABS fabs
#define SIM_FMOD fmod
#define SIM_CEIL ceil
#define SIM_SUBSTEP_TOL 1e-9
#define SIM_ZERO_TOL 1e-9
#define SIM_SUBSTEP_MAX 100000000
#endif

#endif /* SIM_REAL_H */
