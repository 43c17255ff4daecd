/*
 * hil_wire.c -- see hil_wire.h.
 */
#include "hil_wire.h"

void hil_put_u16(uint16_t *o, uint16_t value)
{
    o[0] = (uint16_t)(value & 0xFFu);
    o[1] = (uint16_t)((value >> 8) & 0xFFu);
}

void hil_put_u32(uint16_t *o, uint32_t value)
{
    hil_put_u16(o, (uint16_t)(value & 0xFFFFu));
    hil_put_u16(o + 2, (uint16_t)((value >> 16) & 0xFFFFu));
}

uint16_t hil_get_u16(const uint16_t *o)
{
    return (uint16_t)(((uint16_t)(o[0] & 0xFFu)) | (uint16_t)((uint16_t)(o[1] & 0xFFu) << 8));
}

uint32_t hil_get_u32(const uint16_t *o)
{
    return (uint32_t)hil_get_u16(o) | ((uint32_t)hil_get_u16(o + 2) << 16);
}

float hil_f32_from_bits(uint32_t bits)
{
    union { uint32_t bits; float value; } pun; /* C99 6.5.2.3: reading the other member reinterprets */
    pun.bits = bits;
    return pun.value;
}

int32_t hil_i32_from_bits(uint32_t bits)
{
    if (bits <= 0x7FFFFFFFu) {
        return (int32_t)bits;
    }
    return (int32_t)(-(int32_t)(~bits & 0x7FFFFFFFu)) - 1;
}
