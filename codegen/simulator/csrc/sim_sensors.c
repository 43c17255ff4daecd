/*
 * sim_sensors.c -- current sensors and encoder of the closed-loop simulators
 * (see sim_sensors.h for the models and docs/simulation.md "Sensors").
 */
#include "sim_sensors.h"

#include <math.h>

#include "pmsm_dq.h"

#define SIM_SENSORS_GOLDEN UINT64_C(0x9E3779B97F4A7C15)

/* The carried count history (codegen/simulator/records.py ENCODER_WINDOW) holds the window:
 * a compile error (negative array size) otherwise. */
typedef char sim_sensors_window_check[(sizeof(((sim_state_t *)0)->enc_counts)
                                       == SIM_SENSORS_ENC_WINDOW * sizeof(int64_t)) ? 1 : -1];

/* splitmix64's output function (Steele, Lea, Flood 2014). */
static uint64_t splitmix64_mix(uint64_t z)
{
    z = (z ^ (z >> 30)) * UINT64_C(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94D049BB133111EB);
    return z ^ (z >> 31);
}

/* The n-th output of splitmix64 seeded with seed (n >= 1). */
static uint64_t splitmix64_nth(uint64_t seed, uint64_t n)
{
    return splitmix64_mix(seed + n * SIM_SENSORS_GOLDEN);
}

int sim_sensors_current_active(const sim_params_t *p)
{
    return p->current_gain_error != 0.0 || p->current_offset_a != 0.0 || p->noise_a != 0.0
           || p->adc_bits > 0;
}

void sim_sensors_noise_pair(int64_t seed, int64_t k, double *z_a, double *z_b)
{
    const uint64_t n = 2u * (uint64_t)k;
    const uint64_t a = splitmix64_nth((uint64_t)seed, n + 1u);
    const uint64_t b = splitmix64_nth((uint64_t)seed, n + 2u);
    const double u1 = ((double)(a >> 11) + 1.0) * 0x1.0p-53; /* (0, 1] */
    const double u2 = (double)(b >> 11) * 0x1.0p-53;         /* [0, 1) */
    const double r = sqrt(-2.0 * log(u1));
    *z_a = r * cos(PMSM_DQ_TWO_PI * u2);
    *z_b = r * sin(PMSM_DQ_TWO_PI * u2);
}

double sim_sensors_current(const sim_params_t *p, double i_a, double z)
{
    double i = (1.0 + p->current_gain_error) * i_a + p->current_offset_a + p->noise_a * z;
    if (p->adc_bits > 0) {
        const double half = ldexp(1.0, p->adc_bits - 1); /* 2^(b-1) codes each side */
        const double q = p->adc_full_scale_a / half;     /* 2*FS/2^b */
        double code = floor(i / q + 0.5);
        if (code < -half) {
            code = -half;
        } else if (code > half - 1.0) {
            code = half - 1.0;
        }
        i = code * q;
    }
    return i;
}

int64_t sim_sensors_encoder_count(const sim_params_t *p, double theta_m_rad)
{
    const double n = ldexp(1.0, p->encoder_bits);
    return (int64_t)floor(theta_m_rad * (n / PMSM_DQ_TWO_PI));
}

double sim_sensors_encoder_angle(const sim_params_t *p, int64_t count)
{
    const double step = PMSM_DQ_TWO_PI / ldexp(1.0, p->encoder_bits);
    return pmsm_dq_wrap_angle((double)p->pole_pairs * ((double)count * step));
}

double sim_sensors_encoder_speed(const sim_params_t *p, const sim_state_t *s, int64_t count,
                                 double omega_now_rad_s)
{
    const int64_t w = s->k < SIM_SENSORS_ENC_WINDOW ? s->k : SIM_SENSORS_ENC_WINDOW;
    int64_t old;
    if (w == 0) {
        return omega_now_rad_s;
    }
    old = s->enc_counts[(s->k - w) % SIM_SENSORS_ENC_WINDOW];
    return (double)(count - old) * (PMSM_DQ_TWO_PI / ldexp(1.0, p->encoder_bits))
           / ((double)w * p->dt_s);
}
