/*
 * sim_motor_inputs.h -- step 4 of a period, the controller inputs every
 * topology fills alike, shared by the host simulators (sim_period.h) and
 * the firmware's on-board loop (firmware/runtime/onboard.c) (hand-written
 * runtime).
 *
 * The motor measurements (codegen.records.MOTOR_INPUT_FIELDS) and T*, each
 * converted to the step's number format as a real controller sees them
 * (MPC_ENCODE_*, the generated mpc_binding.h: a float cast, or a
 * fixed-point count).  `in` is the topology's mpc_input_t (a macro: the
 * input type is the generated binding's), `v` any struct with the SI values
 * ia, ib (A), th (rad, [0, 2*pi)), omega_e (rad/s) and t_ref (N*m): the
 * host's sim_sample_t, the on-board loop's sample.
 *
 * C99.  Not part of any cffi cdef.
 */
#ifndef SIM_MOTOR_INPUTS_H
#define SIM_MOTOR_INPUTS_H

#define SIM_MOTOR_INPUTS(in, v)                                 \
    do {                                                        \
        (in).ia_a = MPC_ENCODE_ia_a((v).ia);                    \
        (in).ib_a = MPC_ENCODE_ib_a((v).ib);                    \
        (in).theta_e_rad = MPC_ENCODE_theta_e_rad((v).th);      \
        (in).omega_e_rad_s = MPC_ENCODE_omega_e_rad_s((v).omega_e); \
        (in).torque_ref_nm = MPC_ENCODE_torque_ref_nm((v).t_ref); \
    } while (0)

#endif /* SIM_MOTOR_INPUTS_H */
