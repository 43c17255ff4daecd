/*
 * speed_pi.c -- speed PI with conditional-integration anti-windup (see
 * speed_pi.h).  C99; warning-free under the strict host flags.
 */
#include "speed_pi.h"

double speed_pi_step(double kp, double ki, double dt_s, double limit_nm, double *integral,
                     double w_ref, double w_m)
{
    const double lim = limit_nm;
    const double e = w_ref - w_m;
    const double u = kp * e + *integral;
    double t_ref = u;
    if (t_ref > lim) {
        t_ref = lim;
    } else if (t_ref < -lim) {
        t_ref = -lim;
    }
    if (!((u > lim && e > 0.0) || (u < -lim && e < 0.0))) {
        double i_new = *integral + ki * e * dt_s;
        if (i_new > lim) {
            i_new = lim;
        } else if (i_new < -lim) {
            i_new = -lim;
        }
        *integral = i_new;
    }
    return t_ref;
}
