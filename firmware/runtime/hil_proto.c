/*
 * hil_proto.c -- see hil_proto.h.
 */
#include "hil_proto.h"

#include "hil_codec.h"
#include "hil_cobs.h"
#include "hil_wire.h"
#include "mpc_runtime.h"
#include "onboard.h"
#include "port.h"

/* Octets of the frame head and the CRC trailer. */
#define HIL_HEAD HIL_FRAME_HEAD_OCTETS
#define HIL_CRC 4u
/* Encoded octets the receive buffer holds (a full frame and its COBS overhead). */
#define HIL_RX_CAP HIL_COBS_MAX_ENCODED(HIL_MAX_FRAME)
/* Octets taken from the port per call. */
#define HIL_CHUNK 64u
/* seq of an ERROR whose frame's seq is unknown. */
#define HIL_SEQ_UNKNOWN 0xFFFFu

static uint16_t rx[HIL_RX_CAP];
static uint16_t rx_len;
static uint16_t rx_skipped; /* nonzero: octets of an oversize frame being discarded */
static uint16_t tx[HIL_MAX_FRAME];
static uint32_t overhead;

static void put_octet(uint16_t octet)
{
    port_putc(octet);
}

/* Send tx[HIL_HEAD .. HIL_HEAD + n_payload) as a frame of `type`. */
static void send_frame(uint16_t type, uint16_t seq, uint16_t n_payload)
{
    hil_frame_head_t head;
    uint32_t crc = 0u;
    uint16_t n = (uint16_t)(HIL_HEAD + n_payload);
    uint16_t i;
    head.type = type;
    head.seq = seq;
    hil_encode_frame_head(&head, tx);
    for (i = 0u; i < n; ++i) {
        crc = mpc_crc32(crc, (uint32_t)tx[i], 1u);
    }
    hil_put_u32(&tx[n], crc);
    port_putc(0u);
    hil_cobs_send(tx, (uint16_t)(n + HIL_CRC), put_octet);
    port_putc(0u);
}

static void send_error(uint16_t code, uint16_t seq, uint16_t detail)
{
    hil_error_t e;
    e.code = code;
    e.seq = seq;
    e.detail = detail;
    hil_encode_error(&e, &tx[HIL_HEAD]);
    send_frame(HIL_MSG_ERROR, seq, HIL_ERROR_OCTETS);
}

static void put_text(uint16_t *words, uint16_t n, const char *text)
{
    uint16_t i;
    for (i = 0u; i < n; ++i) {
        words[i] = (uint16_t)((uint16_t)*text & 0x7Fu);
        if (*text != '\0') {
            ++text;
        }
    }
}

static void send_info(uint16_t seq)
{
    static const uint16_t schema_hash[4] = HIL_SCHEMA_HASH_WORDS;
    static const uint16_t config_hash[4] = HIL_CONFIG_HASH_WORDS;
    hil_info_t info;
    uint16_t i;
    info.protocol_version = HIL_PROTOCOL_VERSION;
    for (i = 0u; i < 4u; ++i) {
        info.schema_hash[i] = schema_hash[i];
        info.config_hash[i] = config_hash[i];
    }
    info.core_clock_hz = hil_i32_from_bits((uint32_t)PORT_CORE_CLOCK_HZ & 0x7FFFFFFFu);
    info.overhead_cycles = hil_i32_from_bits(overhead & 0x7FFFFFFFu);
    info.max_batch = HIL_MAX_BATCH;
    info.max_frame = HIL_MAX_FRAME;
    put_text(info.target, 16u, PORT_BOARD);
    put_text(info.number_format, 8u, HIL_NUMBER_FORMAT);
    put_text(info.cycle_unit, 16u, PORT_CYCLE_UNIT);
    hil_encode_info(&info, &tx[HIL_HEAD]);
    send_frame(HIL_MSG_INFO, seq, HIL_INFO_OCTETS);
}

/* One controller step on the input record at `octets`, answered with RESULT `seq`. */
static void step_one(const uint16_t *octets, uint16_t seq)
{
    static mpc_input_t in;
    static mpc_output_t out;
    hil_result_head_t head;
    uint32_t raw;
    hil_decode_input(octets, &in);
    raw = mpc_timed_step(&in, &out);
    head.cycles = hil_i32_from_bits(((raw > overhead) ? raw - overhead : 0u) & 0x7FFFFFFFu);
    hil_encode_result_head(&head, &tx[HIL_HEAD]);
    hil_encode_output(&out, &tx[HIL_HEAD + HIL_RESULT_HEAD_OCTETS]);
    send_frame(HIL_MSG_RESULT, seq, (uint16_t)(HIL_RESULT_HEAD_OCTETS + HIL_OUTPUT_OCTETS));
}

/* The on-board run: its SETPOINTS' seq, the index of its next TELEMETRY frame and the window of
 * frames sent (frame_first .. frame_first + frame_count - 1; the others are computed, not sent). */
static uint16_t run_seq;
static int32_t run_frame;
static int32_t run_first;
static int32_t run_count;

static void emit_telemetry(const hil_sample_t *samples, uint16_t n)
{
    hil_telemetry_head_t head;
    const int32_t idx = run_frame;
    uint16_t i;
    ++run_frame;
    if (idx < run_first || idx - run_first >= run_count) {
        return;
    }
    head.count = n;
    hil_encode_telemetry_head(&head, &tx[HIL_HEAD]);
    for (i = 0u; i < n; ++i) {
        hil_encode_sample(&samples[i], &tx[HIL_HEAD + HIL_TELEMETRY_HEAD_OCTETS + i * HIL_SAMPLE_OCTETS]);
    }
    send_frame(HIL_MSG_TELEMETRY, (uint16_t)(run_seq + 1u + (uint16_t)((uint32_t)idx & 0xFFFFu)),
               (uint16_t)(HIL_TELEMETRY_HEAD_OCTETS + n * HIL_SAMPLE_OCTETS));
}

/* SETPOINTS: run plant and controller on board (onboard.h), TELEMETRY frame i (seq + 1 + i) for the
 * frames of the window, then RUN_END (seq).  A frame of the wrong length or invalid setpoints: ERROR
 * (LENGTH, SETPOINTS), nothing run. */
static void handle_setpoints(const uint16_t *p, uint16_t n, uint16_t seq)
{
    static hil_setpoints_t sp;
    static hil_run_end_t end;
    uint16_t bad;
    if (n != HIL_SETPOINTS_OCTETS) {
        send_error(HIL_ERR_LENGTH, seq, n);
        return;
    }
    hil_decode_setpoints(p, &sp);
    bad = onboard_check(&sp);
    if (bad != 0u) {
        send_error(HIL_ERR_SETPOINTS, seq, bad);
        return;
    }
    run_seq = seq;
    run_frame = 0;
    run_first = sp.frame_first;
    run_count = sp.frame_count;
    onboard_run(&sp, overhead, emit_telemetry, &end);
    hil_encode_run_end(&end, &tx[HIL_HEAD]);
    send_frame(HIL_MSG_RUN_END, seq, HIL_RUN_END_OCTETS);
}

static void restart(void)
{
    rx_len = 0u;
    rx_skipped = 0u;
}

static void handle_batch(const uint16_t *p, uint16_t n, uint16_t seq)
{
    hil_batch_head_t head;
    uint16_t i;
    if (n < HIL_BATCH_HEAD_OCTETS) {
        send_error(HIL_ERR_LENGTH, seq, n);
        return;
    }
    hil_decode_batch_head(p, &head);
    if (head.count == 0u || head.count > HIL_MAX_BATCH) {
        send_error(HIL_ERR_BATCH, seq, head.count);
        return;
    }
    if ((uint32_t)n != (uint32_t)HIL_BATCH_HEAD_OCTETS + (uint32_t)head.count * (uint32_t)HIL_INPUT_OCTETS) {
        send_error(HIL_ERR_LENGTH, seq, n);
        return;
    }
    for (i = 0u; i < head.count; ++i) {
        step_one(&p[HIL_BATCH_HEAD_OCTETS + i * HIL_INPUT_OCTETS], (uint16_t)(seq + i));
    }
}

/* A decoded frame of `n` octets in rx. */
static void handle_frame(uint16_t n)
{
    hil_frame_head_t head;
    uint32_t crc = 0u;
    uint16_t i, plen;
    const uint16_t *p = &rx[HIL_HEAD];
    if (n < HIL_HEAD + HIL_CRC) {
        send_error(HIL_ERR_SHORT, HIL_SEQ_UNKNOWN, n);
        return;
    }
    plen = (uint16_t)(n - HIL_HEAD - HIL_CRC);
    for (i = 0u; i < (uint16_t)(n - HIL_CRC); ++i) {
        crc = mpc_crc32(crc, (uint32_t)rx[i], 1u);
    }
    if (crc != hil_get_u32(&rx[n - HIL_CRC])) {
        send_error(HIL_ERR_CRC, HIL_SEQ_UNKNOWN, n);
        return;
    }
    hil_decode_frame_head(rx, &head);
    switch (head.type) {
    case HIL_MSG_HELLO:
        send_info(head.seq);
        break;
    case HIL_MSG_STEP:
        if (plen != HIL_INPUT_OCTETS) {
            send_error(HIL_ERR_LENGTH, head.seq, plen);
        } else {
            step_one(p, head.seq);
        }
        break;
    case HIL_MSG_BATCH:
        handle_batch(p, plen, head.seq);
        break;
    case HIL_MSG_SETPOINTS:
        handle_setpoints(p, plen, head.seq);
        break;
    case HIL_MSG_PING:
        for (i = 0u; i < plen; ++i) {
            tx[HIL_HEAD + i] = p[i];
        }
        send_frame(HIL_MSG_PONG, head.seq, plen);
        break;
    case HIL_MSG_RESET:
        restart();
        send_info(head.seq);
        break;
    default:
        send_error(HIL_ERR_TYPE, head.seq, head.type);
        break;
    }
}

/* The octets gathered up to a delimiter. */
static void end_of_frame(void)
{
    uint16_t n;
    if (rx_skipped != 0u) {
        send_error(HIL_ERR_OVERSIZE, HIL_SEQ_UNKNOWN, rx_skipped);
    } else if (rx_len != 0u) {
        n = hil_cobs_decode(rx, rx_len);
        if (n == HIL_COBS_BAD) {
            send_error(HIL_ERR_COBS, HIL_SEQ_UNKNOWN, rx_len);
        } else if (n > HIL_MAX_FRAME) {
            send_error(HIL_ERR_OVERSIZE, HIL_SEQ_UNKNOWN, n);
        } else {
            handle_frame(n);
        }
    }
    restart();
}

void hil_start(void)
{
    overhead = mpc_overhead(16u);
    restart();
    send_info(0u);
}

void hil_poll(void)
{
    uint16_t chunk[HIL_CHUNK];
    uint16_t n = port_read(chunk, HIL_CHUNK);
    uint16_t i;
    for (i = 0u; i < n; ++i) {
        uint16_t octet = (uint16_t)(chunk[i] & 0xFFu);
        if (octet == 0u) {
            end_of_frame();
        } else if (rx_skipped != 0u) {
            if (rx_skipped < 0xFFFFu) {
                ++rx_skipped;
            }
        } else if (rx_len < HIL_RX_CAP) {
            rx[rx_len] = octet;
            ++rx_len;
        } else {
            rx_skipped = (uint16_t)(rx_len + 1u);
            rx_len = 0u;
        }
    }
}

void hil_serve(void)
{
    hil_start();
    for (;;) {
        hil_poll();
    }
}
