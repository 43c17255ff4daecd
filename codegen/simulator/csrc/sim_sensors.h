/*
 * sim_sensors.h -- what the controller's sensors make of the plant: current
 * sensors (gain error, offset, Gaussian noise, ADC quantisation) and the
 * shaft encoder (quantised mechanical angle, speed from its counts), float64
 * (hand-written runtime).
 *
 * Specification: docs/simulation.md "Sensors".  Every non-ideality is off at
 * 0 (sim_params_t, the generated sim_api.h); with all of them off the
 * measurement is the plant value itself, bit for bit.
 *
 * Current sensor of phase x (a, b), in this order:
 *   analog   i_s = (1 + g)*i_x + i_off + n_x,   n_x ~ N(0, noise_a^2)
 *   ADC      code = clamp(floor(i_s/q + 1/2), -2^(b-1), 2^(b-1) - 1),
 *            q = 2*FS/2^b (b = adc_bits, FS = adc_full_scale_a), i_meas = code*q
 * (a mid-tread converter: 0 A reads 0; the grid spans [-FS, FS - q]).
 *
 * Noise: counter-based, so that a period's noise depends only on (seed, k):
 * the n-th output of splitmix64 seeded with `seed` is
 *   mix(seed + n*0x9E3779B97F4A7C15)          (Steele, Lea, Flood 2014)
 * and period k takes outputs n = 2k+1, 2k+2 as two uniforms u1 in (0, 1],
 * u2 in [0, 1) (their top 53 bits), turned into two independent standard
 * normals by Box-Muller:
 *   z_a = sqrt(-2 ln u1) cos(2 pi u2),  z_b = sqrt(-2 ln u1) sin(2 pi u2).
 * The same seed gives the same run bit for bit, chunked or not, and the
 * period-by-period (HIL) entry points draw the same values.
 *
 * Encoder: N = 2^encoder_bits counts per mechanical revolution, zero at
 * theta_e = 0; count = floor(theta_m*N/(2 pi)) of the unwrapped mechanical
 * angle; theta_e,meas = wrap(p*count*2 pi/N); the speed is the count
 * difference over the last W = min(k, SIM_SENSORS_ENC_WINDOW) periods,
 *   omega_m,meas = (count_k - count_{k-W})*(2 pi/N)/(W*dt)
 * (at k = 0, no history: the plant's speed, as an estimator that has settled).
 *
 * C99, no dynamic memory, no global state.  Not part of any cffi cdef.
 */
#ifndef SIM_SENSORS_H
#define SIM_SENSORS_H

#include <stdint.h>

#include "sim_period.h" /* sim_api.h (it has no include guard: always through sim_period.h) */

/* Periods of the encoder speed difference (= the length of sim_state_t.enc_counts). */
#define SIM_SENSORS_ENC_WINDOW 16

/* 1 if any current-sensor non-ideality (gain, offset, noise, ADC) is on. */
int sim_sensors_current_active(const sim_params_t *p);

/* Two independent standard normal values of period k (see the header comment). */
void sim_sensors_noise_pair(int64_t seed, int64_t k, double *z_a, double *z_b);

/* The current sensor of one phase: true current i_a (A) and its noise draw z (standard normal). */
double sim_sensors_current(const sim_params_t *p, double i_a, double z);

/* The encoder count of the unwrapped mechanical angle theta_m_rad (encoder_bits > 0). */
int64_t sim_sensors_encoder_count(const sim_params_t *p, double theta_m_rad);

/* The electrical angle in [0, 2*pi) of an encoder count. */
double sim_sensors_encoder_angle(const sim_params_t *p, int64_t count);

/* The speed from the count of period k and the carried counts of periods k-1 .. k-W (rad/s);
 * omega_now_rad_s at k = 0. */
double sim_sensors_encoder_speed(const sim_params_t *p, const sim_state_t *s, int64_t count,
                                 double omega_now_rad_s);

#endif /* SIM_SENSORS_H */
