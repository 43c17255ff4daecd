/*
 * fuzz_frame.c -- libFuzzer target of the firmware's receive path
 * (firmware/runtime/hil_proto.c: gathering up to 0x00, COBS decode, length
 * and CRC checks, message dispatch, BATCH/STEP through the generated
 * controller), built with AddressSanitizer and UBSan (tests/hil/test_fuzz.py).
 *
 * A stub port stands in for the board: port_read() hands out the fuzz input,
 * port_putc() collects what the firmware sends.  Each input is followed by a
 * 0x00 delimiter, so every run ends with the receive state restarted (runs
 * are independent).  An input starting with 0xFF stands for the rest
 * repeated REPEAT times, so that short inputs (the test runs with a small
 * -max_len, for speed) still reach the oversize path.  Every frame the firmware sends must itself be a valid
 * frame: COBS-decodable, at least head + CRC long, CRC-32 correct; anything
 * else aborts (a finding).  hil_proto.c is used unchanged.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include "hil_proto.h"
#include "mpc_runtime.h"
#include "port.h"

/* Times the rest of an input starting with 0xFF is fed. */
#define REPEAT 16u
/* Octets of a sent frame kept for checking (larger frames are a finding). */
#define TX_CAP 4096u

static const uint8_t *in_data;
static size_t in_len;
static size_t in_pos;
static size_t in_total; /* octets to feed: in_len, or in_len * REPEAT */
static uint16_t tx[TX_CAP];
static size_t tx_len;
static uint32_t clock_now;

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
        hil_start();
    }
    in_data = data;
    in_len = size;
    in_total = size;
    if (size > 1u && data[0] == 0xFFu) {
        in_data = data + 1;
        in_len = size - 1u;
        in_total = in_len * REPEAT;
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
