/*
 * hil_cobs.h -- Consistent Overhead Byte Stuffing for the serial protocol
 * (HIL builds): a frame of octets becomes octets without 0x00, so 0x00 can
 * delimit frames.  Each block is a code octet c (1..255) followed by c - 1
 * non-zero octets; a block with c < 255 stands for its octets and one 0x00,
 * except the last block, whose 0x00 is dropped.  Octets are held one per
 * uint16_t word (hil_wire.h).
 */
#ifndef HIL_COBS_H
#define HIL_COBS_H

#include <stdint.h>

/* Returned by hil_cobs_decode for malformed input. */
#define HIL_COBS_BAD 0xFFFFu

/* Most encoded octets of an n-octet frame (without delimiters). */
#define HIL_COBS_MAX_ENCODED(n) ((n) + (n) / 254u + 1u)

/* Decode `n` encoded octets (no delimiter) in place; return the decoded
 * length (always < n), or HIL_COBS_BAD if a code runs past the end or an
 * octet is 0x00. */
uint16_t hil_cobs_decode(uint16_t *buf, uint16_t n);

/* Encode `n` octets of `src` and hand every encoded octet to `put`, in order
 * (no delimiters: the caller sends those). */
typedef void (*hil_put_fn)(uint16_t octet);
void hil_cobs_send(const uint16_t *src, uint16_t n, hil_put_fn put);

#endif /* HIL_COBS_H */
