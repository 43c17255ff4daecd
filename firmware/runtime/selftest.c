/*
 * selftest.c -- replay, compare, time and report (see selftest.h).
 */
#include "selftest.h"

#include <stddef.h>

#include "console.h"
#include "mpc_runtime.h"
#include "port.h"

/* Values per CYC line. */
#define MPC_CYC_PER_LINE 16u

uint32_t mpc_values_crc(uint32_t crc, const uint32_t *values, const mpc_value_desc_t *desc, uint16_t n)
{
    uint16_t k;
    for (k = 0u; k < n; ++k) {
        crc = mpc_crc32(crc, values[k], (desc[k].kind == MPC_VALUE_U16) ? 2u : 4u);
    }
    return crc;
}

/* `octets` (2 or 4) octets at octet `offset` of a canonical record, least significant first. */
static uint32_t canonical_read(const uint32_t *words, uint16_t offset, uint16_t octets)
{
    uint32_t at = (uint32_t)offset >> 2;
    uint32_t shift = 8u * ((uint32_t)offset & 3u);
    uint32_t value = words[at] >> shift;
    if (shift != 0u && shift + 8u * (uint32_t)octets > 32u) {
        value |= words[at + 1u] << (32u - shift); /* the value continues in the next word */
    }
    return (octets == 2u) ? (value & 0xFFFFu) : value;
}

void mpc_values_unpack(const uint32_t *words, const mpc_value_desc_t *desc, uint16_t n, uint32_t *values)
{
    uint16_t k;
    for (k = 0u; k < n; ++k) {
        values[k] = canonical_read(words, desc[k].offset, (desc[k].kind == MPC_VALUE_U16) ? 2u : 4u);
    }
}

void mpc_input_decode(const uint32_t words[MPC_INPUT_WORDS], mpc_input_t *in, uint32_t values[MPC_INPUT_NVALUES])
{
    mpc_values_unpack(words, mpc_input_desc, MPC_INPUT_NVALUES, values);
    mpc_input_from_values(values, in);
}

void mpc_output_decode(const uint32_t words[MPC_OUTPUT_WORDS], mpc_output_t *out,
                       uint32_t values[MPC_OUTPUT_NVALUES])
{
    mpc_values_unpack(words, mpc_output_desc, MPC_OUTPUT_NVALUES, values);
    mpc_output_from_values(values, out);
}

static void put_value(const mpc_value_desc_t *d, uint32_t v)
{
    if (d->kind != MPC_VALUE_U16) {
        console_put_hex32(v);
    } else {
        console_put_u32(v);
    }
}

static void report_state(const char *set, uint32_t i, const mpc_input_t *in)
{
    uint32_t iv[MPC_INPUT_NVALUES];
    uint16_t k;
    mpc_input_values(in, iv);
    console_puts("STATE");
    console_kv_str("set", set);
    console_kv_u32("i", i);
    for (k = 0u; k < MPC_INPUT_NVALUES; ++k) {
        console_putc((uint16_t)' ');
        console_puts(mpc_input_desc[k].name);
        console_putc((uint16_t)'=');
        put_value(&mpc_input_desc[k], iv[k]);
    }
    console_eol();
}

static void report_value(const char *set, uint32_t i, const mpc_value_desc_t *d, uint32_t got, uint32_t exp)
{
    console_puts("MISMATCH");
    console_kv_str("set", set);
    console_kv_u32("i", i);
    console_kv_str("field", d->name);
    console_puts(" got=");
    put_value(d, got);
    console_puts(" exp=");
    put_value(d, exp);
    console_eol();
}

/* Compare one state's outputs; print details if `detail`; return 1 on mismatch. */
static uint16_t check_state(const mpc_testset_t *set, uint32_t i, const mpc_input_t *in,
                            const uint32_t gv[MPC_OUTPUT_NVALUES], uint16_t detail)
{
    static mpc_output_t expected; /* static: keeps the stack small on every board */
    uint16_t bad = 0u;
    uint16_t k;
    if (set->expected != NULL) {
        uint32_t ev[MPC_OUTPUT_NVALUES];
        /* decoded into the record and flattened again: every run checks the output decoder too */
        mpc_output_decode(&set->expected[i * MPC_OUTPUT_WORDS], &expected, ev);
        mpc_output_values(&expected, ev);
        for (k = 0u; k < MPC_OUTPUT_NVALUES; ++k) {
            if (gv[k] != ev[k]) {
                bad = 1u;
                if (detail != 0u) {
                    report_value(set->name, i, &mpc_output_desc[k], gv[k], ev[k]);
                }
            }
        }
    } else {
        uint32_t crc = mpc_values_crc(0u, gv, mpc_output_desc, MPC_OUTPUT_NVALUES);
        if (crc != set->expected_crc[i]) {
            static const mpc_value_desc_t crc_desc = {"output_crc", MPC_VALUE_F32, 0u};
            bad = 1u;
            if (detail != 0u) {
                report_value(set->name, i, &crc_desc, crc, set->expected_crc[i]);
                for (k = 0u; k < MPC_OUTPUT_NVALUES; ++k) {
                    console_puts("OUT");
                    console_kv_str("set", set->name);
                    console_kv_u32("i", i);
                    console_kv_str("field", mpc_output_desc[k].name);
                    console_puts(" got=");
                    put_value(&mpc_output_desc[k], gv[k]);
                    console_eol();
                }
            }
        }
    }
    if (bad != 0u && detail != 0u) {
        report_state(set->name, i, in);
    }
    return bad;
}

uint32_t mpc_selftest_run(const mpc_testset_t *set, uint32_t overhead)
{
    static mpc_input_t state; /* static: keeps the stack small on every board */
    static mpc_output_t got;
    uint32_t gv[MPC_OUTPUT_NVALUES];
    uint32_t iv[MPC_INPUT_NVALUES];
    uint32_t i, mismatches = 0u, crc_in = 0u, crc_out = 0u;
    uint32_t cyc_min = 0xFFFFFFFFu, cyc_max = 0u;
    uint64_t cyc_sum = 0u;
    uint16_t on_line = 0u;

    console_puts("SET");
    console_kv_str("name", set->name);
    console_kv_u32("n", set->n);
    console_kv_str("expect", (set->expected != NULL) ? "full" : "crc");
    console_eol();
    for (i = 0u; i < set->n; ++i) {
        uint32_t raw, net;
        mpc_input_decode(&set->states[i * MPC_INPUT_WORDS], &state, iv);
        raw = mpc_timed_step(&state, &got);
        net = (raw > overhead) ? (raw - overhead) : 0u;
        if (net < cyc_min) {
            cyc_min = net;
        }
        if (net > cyc_max) {
            cyc_max = net;
        }
        cyc_sum += net;
        mpc_output_values(&got, gv);
        mpc_input_values(&state, iv); /* the step's actual input: crc_in checks the decoding */
        crc_out = mpc_values_crc(crc_out, gv, mpc_output_desc, MPC_OUTPUT_NVALUES);
        crc_in = mpc_values_crc(crc_in, iv, mpc_input_desc, MPC_INPUT_NVALUES);
        if (check_state(set, i, &state, gv, (uint16_t)(mismatches < MPC_SELFTEST_MAX_DETAILS)) != 0u) {
            ++mismatches;
        }
        if (set->dump_cycles != 0u) {
            if (on_line == 0u) {
                console_puts("CYC");
            }
            console_putc((uint16_t)' ');
            console_put_u32(net);
            ++on_line;
            if (on_line == MPC_CYC_PER_LINE || i + 1u == set->n) {
                console_eol();
                on_line = 0u;
            }
        }
    }
    console_puts("SUMMARY");
    console_kv_str("set", set->name);
    console_kv_u32("n", set->n);
    console_kv_u32("mismatches", mismatches);
    console_kv_hex32("crc_in", crc_in);
    console_kv_hex32("crc_out", crc_out);
    console_kv_u32("cyc_min", (set->n > 0u) ? cyc_min : 0u);
    console_kv_u32("cyc_max", cyc_max);
    console_kv_u32("cyc_mean", (set->n > 0u) ? (uint32_t)(cyc_sum / set->n) : 0u);
    console_kv_u32("overhead", overhead);
    console_kv_str("unit", PORT_CYCLE_UNIT);
    console_eol();
    return mismatches;
}
