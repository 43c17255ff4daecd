/*
 * hil_cobs.c -- see hil_cobs.h.
 */
#include "hil_cobs.h"

uint16_t hil_cobs_decode(uint16_t *buf, uint16_t n)
{
    uint16_t r = 0u; /* read position: the next code octet */
    uint16_t w = 0u; /* write position (w <= r: decoding in place is safe) */
    while (r < n) {
        uint16_t code = (uint16_t)(buf[r] & 0xFFu);
        uint16_t k;
        if (code == 0u || (uint32_t)r + (uint32_t)code > (uint32_t)n) {
            return HIL_COBS_BAD;
        }
        ++r;
        for (k = 1u; k < code; ++k) {
            uint16_t octet = (uint16_t)(buf[r] & 0xFFu);
            if (octet == 0u) {
                return HIL_COBS_BAD;
            }
            buf[w] = octet;
            ++w;
            ++r;
        }
        if (code != 0xFFu && r < n) {
            buf[w] = 0u;
            ++w;
        }
    }
    return w;
}

void hil_cobs_send(const uint16_t *src, uint16_t n, hil_put_fn put)
{
    uint16_t start = 0u;
    for (;;) {
        uint16_t len = 0u; /* non-zero octets of this block */
        uint16_t k;
        while ((uint16_t)(start + len) < n && (src[start + len] & 0xFFu) != 0u && len < 254u) {
            ++len;
        }
        put((uint16_t)(len + 1u));
        for (k = 0u; k < len; ++k) {
            put((uint16_t)(src[start + k] & 0xFFu));
        }
        start = (uint16_t)(start + len);
        if (start >= n) {
            break;
        }
        if (len < 254u) {
            ++start; /* the 0x00 that ended the block */
        }
    }
}
