/*
 * fuzz_frame.c -- libFuzzer target of the firmware's receive path
 * (firmware/runtime/hil_proto.c: gathering up to 0x00, COBS decode, length
 * and CRC checks, message dispatch, BATCH/STEP through the generated
 * controller, SETPOINTS through the on-board loop of onboard.c), built with
 * AddressSanitizer and UBSan (tests/hil/test_fuzz.py).
 *
 * A stub port stands in for the board: port_read() hands out the fuzz input,
 * port_putc() collects what the firmware sends.  Each input is followed by a
 * 0x00 delimiter, so every run ends with the receive state restarted (runs
 * are independent).  An input starting with 0xFF stands for the rest
 * repeated REPEAT times, one starting with 0xFE, L0, L1 for the rest repeated
 * up to L0 + 256 * L1 octets (at most MAX_FED), so that short inputs (the
 * test runs with a small -max_len, for speed) still reach both oversize
 * paths (more than the receive buffer; a buffer that decodes to more than
 * HIL_MAX_FRAME).  Every
 * frame the firmware sends must itself be a valid frame: COBS-decodable, at
 * least head + CRC long, CRC-32 correct; anything else aborts (a finding).
 *
 * hil_proto.c is used unchanged, compiled with -Donboard_run=fuzz_onboard_run:
 * an on-board run goes through fuzz_onboard_run below, which runs at most
 * MAX_RUN_PERIODS periods (the fuzzer does find valid SETPOINTS frames, and
 * 2^31 periods would hang it).
 *
 * At exit the target prints what it sent, one line on stderr:
 * "fuzz_frame sent: msg:T=N ... err:C=N ... sp:D=N ... batch:zero=N batch:big=N"
 * (frames per message type T, ERROR frames per code C, ERROR SETPOINTS per
 * detail D, ERROR BATCH for a count of 0 and above the maximum): the test
 * asserts that the corpus reaches every error code.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "hil_codec.h"
#include "hil_proto.h"
#include "mpc_runtime.h"
#include "onboard.h"
#include "port.h"

/* Times the rest of an input starting with 0xFF is fed. */
#define REPEAT 16u
/* Most octets an input starting with 0xFE stands for (two receive buffers). */
#define MAX_FED 2048u
/* Most periods of an on-board run here. */
#define MAX_RUN_PERIODS 64
/* Counters kept per message type / error code / SETPOINTS detail (larger values share the last). */
#define N_COUNT 16u
/* Octets of a sent frame kept for checking (larger frames are a finding). */
#define TX_CAP 4096u

static const uint8_t *in_data;
static size_t in_len;
static size_t in_pos;
static size_t in_total; /* octets to feed: in_len, or in_len * REPEAT */
static uint16_t tx[TX_CAP];
static size_t tx_len;
static uint32_t clock_now;
static unsigned long sent_msg[N_COUNT];
static unsigned long sent_err[N_COUNT];
static unsigned long sent_sp[N_COUNT];
static unsigned long batch_zero, batch_big;

static size_t clamp(size_t v)
{
    return (v < N_COUNT) ? v : N_COUNT - 1u;
}

static void print_counts(void)
{
    size_t i;
    fprintf(stderr, "fuzz_frame sent:");
    for (i = 0u; i < N_COUNT; ++i) {
        if (sent_msg[i] != 0u) {
            fprintf(stderr, " msg:%u=%lu", (unsigned)i, sent_msg[i]);
        }
    }
    for (i = 0u; i < N_COUNT; ++i) {
        if (sent_err[i] != 0u) {
            fprintf(stderr, " err:%u=%lu", (unsigned)i, sent_err[i]);
        }
    }
    for (i = 0u; i < N_COUNT; ++i) {
        if (sent_sp[i] != 0u) {
            fprintf(stderr, " sp:%u=%lu", (unsigned)i, sent_sp[i]);
        }
    }
    fprintf(stderr, " batch:zero=%lu batch:big=%lu\n", batch_zero, batch_big);
}

/* The on-board run of hil_proto.c (renamed there by -Donboard_run=fuzz_onboard_run): at most
 * MAX_RUN_PERIODS periods of the real one. */
void fuzz_onboard_run(const hil_setpoints_t *sp, uint32_t overhead, onb_emit_fn emit, hil_run_end_t *end);

void fuzz_onboard_run(const hil_setpoints_t *sp, uint32_t overhead, onb_emit_fn emit, hil_run_end_t *end)
{
    hil_setpoints_t bounded = *sp;
    if (bounded.periods > MAX_RUN_PERIODS) {
        bounded.periods = MAX_RUN_PERIODS;
    }
    onboard_run(&bounded, overhead, emit, end);
}

/* Decode buf[0..n) (COBS, no delimiters) in place; the decoded length, or SIZE_MAX if malformed. */
static size_t cobs_decode(uint16_t *buf, size_t n)
{
    size_t r = 0u, w = 0u;
    while (r < n) {
        size_t code = buf[r];
        size_t k;
        if (code == 0u || r + code > n) { /* a zero inside, or a group running past the end */
            return SIZE_MAX;
        }
        ++r;
        for (k = 1u; k < code; ++k) {
            buf[w++] = buf[r++];
        }
        if (code != 0xFFu && r < n) {
            buf[w++] = 0u;
        }
    }
    return w;
}

static void check_sent_frame(void)
{
    size_t n = cobs_decode(tx, tx_len);
    uint32_t crc = 0u, got;
    size_t i;
    if (n == SIZE_MAX || n < 4u + 4u) {
        abort();
    }
    for (i = 0u; i < n - 4u; ++i) {
        crc = mpc_crc32(crc, (uint32_t)tx[i], 1u);
    }
    got = (uint32_t)tx[n - 4u] | ((uint32_t)tx[n - 3u] << 8) | ((uint32_t)tx[n - 2u] << 16)
          | ((uint32_t)tx[n - 1u] << 24);
    if (crc != got) {
        abort();
    }
    {
        const size_t type = (size_t)(tx[0] | (tx[1] << 8));
        ++sent_msg[clamp(type)];
        if (type == HIL_MSG_ERROR && n >= 4u + HIL_ERROR_OCTETS + 4u) {
            const size_t code = (size_t)(tx[4] | (tx[5] << 8));
            const size_t detail = (size_t)(tx[8] | (tx[9] << 8));
            ++sent_err[clamp(code)];
            if (code == HIL_ERR_SETPOINTS) {
                ++sent_sp[clamp(detail)];
            }
            if (code == HIL_ERR_BATCH) {
                if (detail == 0u) {
                    ++batch_zero;
                } else {
                    ++batch_big;
                }
            }
        }
    }
}

void port_init(void)
{
}

void port_putc(uint16_t c)
{
    uint16_t octet = (uint16_t)(c & 0xFFu);
    if (octet == 0u) {
        if (tx_len != 0u) {
            check_sent_frame();
        }
        tx_len = 0u;
        return;
    }
    if (tx_len >= TX_CAP) {
        abort();
    }
    tx[tx_len++] = octet;
}

uint32_t port_cycles(void)
{
    clock_now += 7u;
    return clock_now;
}

void port_report(void)
{
}

void port_exit(uint16_t code)
{
    (void)code;
    abort();
}

uint16_t port_read(uint16_t *octets, uint16_t max)
{
    uint16_t n = 0u;
    while (n < max && in_pos <= in_total) {
        octets[n++] = (in_pos < in_total) ? (uint16_t)in_data[in_pos % in_len] : 0u; /* then the delimiter */
        ++in_pos;
    }
    return n;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static int started;
    if (started == 0) {
        started = 1;
        in_len = 0u;
        in_total = 0u;
        in_pos = 1u; /* nothing to read */
        atexit(print_counts);
        hil_start();
    }
    in_data = data;
    in_len = size;
    in_total = size;
    if (size > 1u && data[0] == 0xFFu) {
        in_data = data + 1;
        in_len = size - 1u;
        in_total = in_len * REPEAT;
    } else if (size > 3u && data[0] == 0xFEu) {
        in_data = data + 3;
        in_len = size - 3u;
        in_total = (size_t)data[1] | ((size_t)data[2] << 8);
        if (in_total > MAX_FED) {
            in_total = MAX_FED;
        }
    }
    in_pos = 0u;
    while (in_pos <= in_total) {
        hil_poll();
    }
    if (tx_len != 0u) { /* every sent frame is closed by its delimiter */
        abort();
    }
    return 0;
}
