/*
 * mpc_runtime.h -- the controller call with cycle measurement around it,
 * shared by every port.  The generated controller is reached only through
 * the generated mpc_binding.h (mpc_input_t, mpc_output_t, MPC_STEP).
 *
 * Timing (the HIL protocol "Timing"): the port's up-counting counter
 * port_cycles() is read immediately before and after the call; compiler
 * barriers keep the call from being moved across the reads, and the step is
 * reached through a non-inlined wrapper.  mpc_timed_empty() measures the
 * same sequence around an empty function: the step's own cost is the
 * difference (its unit is PORT_CYCLE_UNIT).
 */
#ifndef MPC_RUNTIME_H
#define MPC_RUNTIME_H

#include <stdint.h>

#include "mpc_binding.h"

/* Compiler barrier: no memory access is moved across it. */
#if defined(__GNUC__) && !defined(__TI_COMPILER_VERSION__)
#define MPC_BARRIER() __asm__ volatile("" ::: "memory")
#else
#define MPC_BARRIER() ((void)0)
#endif

/* One controller step with the elapsed port cycles (raw, overhead included). */
uint32_t mpc_timed_step(const mpc_input_t *in, mpc_output_t *out);

/* The same measurement around an empty function (the overhead). */
uint32_t mpc_timed_empty(const mpc_input_t *in, mpc_output_t *out);

/* Smallest of `n` overhead measurements (n >= 1). */
uint32_t mpc_overhead(uint16_t n);

/* Bits of a float32 (no byte pointers: the object is copied whole). */
uint32_t mpc_f32_bits(float value);

/* Bits of an int32 (two's complement), as a uint32 without undefined or
 * implementation-defined behaviour (fixed-point records). */
uint32_t mpc_i32_value(int32_t value);

/* A uint16 field as a 32-bit value. */
uint32_t mpc_u16_value(uint16_t value);

/* The inverses, bit for bit (decoding the embedded test records): the float32
 * of bits `bits` (NaN payloads, -0.0 and infinities kept: the object is
 * copied whole), the int32 of two's complement bits, the uint16 of a value's
 * low 16 bits. */
float mpc_f32_from_bits(uint32_t bits);
int32_t mpc_i32_from_value(uint32_t value);
uint16_t mpc_u16_from_value(uint32_t value);

/* CRC-32 (IEEE 802.3, reflected, init/xorout 0xFFFFFFFF as zlib.crc32):
 * feed `n_octets` (1..4) octets of `value`, least significant first (the
 * canonical little-endian serialisation, independent of CHAR_BIT).
 * Start with crc = 0, the running value is the finished CRC after each call. */
uint32_t mpc_crc32(uint32_t crc, uint32_t value, uint16_t n_octets);

#endif /* MPC_RUNTIME_H */
