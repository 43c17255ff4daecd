/*
 * selftest.h -- replay embedded controller input states, compare every
 * output value bit for bit with the embedded expected outputs of the Python
 * reference (codegen/topologies/twolevel/reference.py), time every step, and report
 * over the console.
 *
 * The generated mpc_values.h gives the value counts, the record sizes in
 * 32-bit words and the data's config hash; the generated mpc_values.c
 * describes every value of a record (name, kind, octet offset in the
 * canonical layout), flattens records into uint32_t values (a float or an
 * int32 as its bits, a uint16_t as its value) in interface order and builds
 * records back from such values; the generated mpc_selftest_data.c holds the
 * test sets.
 *
 * Embedded records are in the canonical layout (codegen/records.py
 * RecordLayout: the fields in order, little-endian, no padding), held as
 * uint32_t words, the n-th octet of a record being bits 8*(n%4).. of word
 * n/4, the last word zero-padded (MPC_INPUT_WORDS / MPC_OUTPUT_WORDS words a
 * record).  mpc_values_unpack() reads the values from there with the value
 * table's offsets: 32-bit arithmetic only, no byte pointers, so the same C
 * runs with CHAR_BIT 16 (C28x).  Every bit is kept (NaN payloads, -0.0,
 * infinities, int32 counts).
 *
 * Console lines (one per line, fields " key=value"):
 *   SET      name n expect              start of a set
 *   MISMATCH set i field got exp         one differing value (first states only)
 *   STATE    set i <input fields>        the input of a mismatching state (bits)
 *   CYC      v v v ...                   net cycles of each step (dump sets only)
 *   SUMMARY  set n mismatches crc_in crc_out cyc_min cyc_max cyc_mean overhead unit
 * crc_in / crc_out: CRC-32 (zlib) of every input / output value of the set in
 * order, floats and int32 as 4 and uint16_t as 2 little-endian octets; the host
 * recomputes crc_out from the reference, so an image that only claimed
 * success could not pass.  crc_in is taken from the decoded input records (the
 * step's actual inputs), so it also checks the decoding.
 */
#ifndef MPC_SELFTEST_H
#define MPC_SELFTEST_H

#include <stdint.h>

#include "mpc_binding.h"
#include "mpc_values.h"

/* Kind of a flattened value. */
#define MPC_VALUE_F32 1u
#define MPC_VALUE_U16 2u
#define MPC_VALUE_I32 3u /* an int32 (fixed point) as its two's complement bits */

/* Mismatching states reported in detail per set (all are counted). */
#ifndef MPC_SELFTEST_MAX_DETAILS
#define MPC_SELFTEST_MAX_DETAILS 8u
#endif

typedef struct {
    const char *name;   /* field name, "costs[3]" for array elements */
    uint16_t kind;      /* MPC_VALUE_F32, MPC_VALUE_I32 or MPC_VALUE_U16 */
    uint16_t offset;    /* octet offset of the value in the canonical record */
} mpc_value_desc_t;

extern const mpc_value_desc_t mpc_input_desc[MPC_INPUT_NVALUES];
extern const mpc_value_desc_t mpc_output_desc[MPC_OUTPUT_NVALUES];

/* Flatten one record into values (generated: mpc_values.c). */
void mpc_input_values(const mpc_input_t *in, uint32_t values[MPC_INPUT_NVALUES]);
void mpc_output_values(const mpc_output_t *out, uint32_t values[MPC_OUTPUT_NVALUES]);

/* One record from its values, the inverse of the above, bit for bit (generated: mpc_values.c). */
void mpc_input_from_values(const uint32_t values[MPC_INPUT_NVALUES], mpc_input_t *in);
void mpc_output_from_values(const uint32_t values[MPC_OUTPUT_NVALUES], mpc_output_t *out);

/* The `n` values described by `desc` of one record in the canonical layout
 * (`words`: its first word), in order: a 4-octet value as its bits, a
 * uint16_t as its value (see the header comment). */
void mpc_values_unpack(const uint32_t *words, const mpc_value_desc_t *desc, uint16_t n, uint32_t *values);

/* One record decoded from its canonical words (mpc_values_unpack, then
 * mpc_*_from_values); `values` receives the record's values. */
void mpc_input_decode(const uint32_t words[MPC_INPUT_WORDS], mpc_input_t *in, uint32_t values[MPC_INPUT_NVALUES]);
void mpc_output_decode(const uint32_t words[MPC_OUTPUT_WORDS], mpc_output_t *out,
                       uint32_t values[MPC_OUTPUT_NVALUES]);

typedef struct {
    const char *name;             /* "selftest", "bench" */
    const uint32_t *states;       /* n input records, MPC_INPUT_WORDS words each (canonical layout) */
    const uint32_t *expected;     /* n expected output records, MPC_OUTPUT_WORDS words each, or NULL (compact) */
    const uint32_t *expected_crc; /* compact: CRC-32 of each state's output values */
    uint32_t n;
    uint16_t dump_cycles;         /* nonzero: print every step's net cycles (CYC lines) */
} mpc_testset_t;

/* The embedded sets (generated: mpc_selftest_data.c). */
extern const mpc_testset_t mpc_testsets[MPC_N_TESTSETS];

/* Run one set; return its number of mismatching states.  `overhead` is the
 * empty-call measurement subtracted from every step's cycles. */
uint32_t mpc_selftest_run(const mpc_testset_t *set, uint32_t overhead);

/* CRC-32 of `n` flattened values continued from `crc` (see the header comment). */
uint32_t mpc_values_crc(uint32_t crc, const uint32_t *values, const mpc_value_desc_t *desc, uint16_t n);

#endif /* MPC_SELFTEST_H */
