/*
 * hil_wire.h -- octets of the serial protocol (HIL builds), shared by every
 * port.  An octet array holds one octet per uint16_t word (its low 8 bits):
 * C28x has 16-bit char, so no byte pointer ever reaches into a struct, and
 * every multi-octet value is serialised explicitly, least significant octet
 * first (the canonical layout of codegen.records).
 */
#ifndef HIL_WIRE_H
#define HIL_WIRE_H

#include <stdint.h>

/* Little-endian 16- and 32-bit values at o[0..1] / o[0..3]. */
void hil_put_u16(uint16_t *o, uint16_t value);
void hil_put_u32(uint16_t *o, uint32_t value);
uint16_t hil_get_u16(const uint16_t *o);
uint32_t hil_get_u32(const uint16_t *o);

/* A float32 from its bits (the inverse of mpc_f32_bits). */
float hil_f32_from_bits(uint32_t bits);

/* An int32_t from its two's-complement bits (the inverse of mpc_i32_value; no
 * implementation-defined conversion). */
int32_t hil_i32_from_bits(uint32_t bits);

#endif /* HIL_WIRE_H */
