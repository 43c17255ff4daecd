/*
 * speed_pi.c -- the float64 speed PI of the host simulators: speed_pi.h's
 * speed_pi_update (written once on sim_real_t) by name.  C99; warning-free
 * under the strict host flags.
 */
#include "speed_pi.h"

double speed_pi_step(double kp, double ki, double dt_s, double limit_nm, double *integral,
                     double w_ref, double w_m)
{
    return speed_pi_update(kp, ki, dt_s, limit_nm, integral, w_ref, w_m);
}
