/*
 * mpc_runtime.c -- timed controller call and the small helpers of
 * mpc_runtime.h.
 */
#include "mpc_runtime.h"

#include <string.h>

#include "port.h"

#if defined(__TI_COMPILER_VERSION__)
#define MPC_NOIPA /* cl2000: the call through a pointer is not inlined at -O2 */
#elif defined(__GNUC__) && !defined(__clang__)
#define MPC_NOIPA __attribute__((noipa))
#elif defined(__GNUC__)
#define MPC_NOIPA __attribute__((noinline))
#else
#define MPC_NOIPA
#endif

/* The step behind a call the compiler cannot inline or analyse. */
static MPC_NOIPA void mpc_call_step(const mpc_input_t *in, mpc_output_t *out)
{
    MPC_STEP(in, out);
}

/* An empty function, called exactly like mpc_call_step. */
static MPC_NOIPA void mpc_call_empty(const mpc_input_t *in, mpc_output_t *out)
{
    (void)in;
    (void)out;
}

typedef void (*mpc_step_fn)(const mpc_input_t *in, mpc_output_t *out);

/* The one timed sequence: both measurements run exactly this code, so the
 * difference of two measurements is the difference of the called functions
 * (mpc_call_step's tail call to the step replaces mpc_call_empty's return:
 * the difference is the step's own instructions/cycles). */
static MPC_NOIPA uint32_t mpc_timed_call(mpc_step_fn fn, const mpc_input_t *in, mpc_output_t *out)
{
    uint32_t t0, t1;
    MPC_BARRIER();
    t0 = port_cycles();
    MPC_BARRIER();
    fn(in, out);
    MPC_BARRIER();
    t1 = port_cycles();
    MPC_BARRIER();
    return (uint32_t)((t1 - t0) & (uint32_t)PORT_CYCLES_MASK);
}

uint32_t mpc_timed_step(const mpc_input_t *in, mpc_output_t *out)
{
    return mpc_timed_call(mpc_call_step, in, out);
}

uint32_t mpc_timed_empty(const mpc_input_t *in, mpc_output_t *out)
{
    return mpc_timed_call(mpc_call_empty, in, out);
}

uint32_t mpc_overhead(uint16_t n)
{
    static mpc_input_t in;
    static mpc_output_t out;
    uint32_t best = 0xFFFFFFFFu;
    uint16_t i;
    for (i = 0u; i < n; ++i) {
        uint32_t c = mpc_timed_empty(&in, &out);
        if (c < best) {
            best = c;
        }
    }
    return best;
}

uint32_t mpc_f32_bits(float value)
{
    uint32_t bits;
    memcpy(&bits, &value, sizeof bits);
    return bits;
}

uint32_t mpc_i32_value(int32_t value)
{
    /* int32 -> uint32 is defined (modulo 2^32); spelled out so -Wsign-conversion is satisfied */
    return (value < 0) ? (uint32_t)0xFFFFFFFFu - (uint32_t)(-(value + 1)) : (uint32_t)value;
}

uint32_t mpc_u16_value(uint16_t value)
{
    return (uint32_t)value;
}

float mpc_f32_from_bits(uint32_t bits)
{
    float value;
    memcpy(&value, &bits, sizeof value);
    return value;
}

int32_t mpc_i32_from_value(uint32_t value)
{
    /* uint32 -> int32 above INT32_MAX is implementation-defined: spelled out (the inverse of mpc_i32_value) */
    return (value <= 0x7FFFFFFFu) ? (int32_t)value : -(int32_t)(0xFFFFFFFFu - value) - 1;
}

uint16_t mpc_u16_from_value(uint32_t value)
{
    return (uint16_t)(value & 0xFFFFu);
}

uint32_t mpc_crc32(uint32_t crc, uint32_t value, uint16_t n_octets)
{
    /* nibble table of the reflected polynomial 0xEDB88320 */
    static const uint32_t table[16] = {
        0x00000000u, 0x1DB71064u, 0x3B6E20C8u, 0x26D930ACu,
        0x76DC4190u, 0x6B6B51F4u, 0x4DB26158u, 0x5005713Cu,
        0xEDB88320u, 0xF00F9344u, 0xD6D6A3E8u, 0xCB61B38Cu,
        0x9B64C2B0u, 0x86D3D2D4u, 0xA00AE278u, 0xBDBDF21Cu,
    };
    uint16_t i;
    crc = ~crc;
    for (i = 0u; i < n_octets; ++i) {
        uint32_t octet = (value >> (8u * (uint32_t)i)) & 0xFFu;
        crc ^= octet;
        crc = (crc >> 4) ^ table[crc & 0xFu];
        crc = (crc >> 4) ^ table[crc & 0xFu];
    }
    return ~crc;
}
