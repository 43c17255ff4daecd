/*
 * hil_proto.h -- the serial hardware-in-the-loop protocol, board side
 * (HIL builds: MPC_HIL defined), shared by every port.
 *
 * The protocol is defined once in Python (hil/schema.py); the generated
 * gen/hil_codec.[ch] gives its constants, header records and the codec of
 * every record (field by field, little-endian).  A frame: head (type, seq),
 * payload, CRC-32 (mpc_crc32) of head + payload; on the wire 0x00,
 * COBS(frame), 0x00 (hil_cobs.h).
 *
 * Receive: port_read() is polled for whatever octets are waiting; they are
 * gathered in a bounded buffer up to the next 0x00.  Longer input is
 * discarded up to the next delimiter (ERROR OVERSIZE); a malformed, short
 * or corrupted frame is answered with ERROR and dropped.  Requests are
 * answered in order: HELLO -> INFO, STEP -> RESULT, BATCH of n -> n RESULTs
 * (seq, seq + 1, ...), PING -> PONG (same payload), RESET -> INFO (the
 * protocol state restarts), SETPOINTS -> an on-board run of plant and
 * controller (onboard.h): TELEMETRY frame i as seq + 1 + i (mod 2^16) for
 * the frames of the SETPOINTS' window (frame_first, frame_count: the run is
 * deterministic, so the harness asks for lost frames again with a window
 * of those), then RUN_END (seq); input is not read during the run.  INFO
 * is also sent once at start-up (seq 0).
 * Cycles: only the controller call is timed (mpc_timed_step), the
 * measurement overhead (mpc_overhead) subtracted.
 */
#ifndef HIL_PROTO_H
#define HIL_PROTO_H

#include <stdint.h>

/* Start the protocol: measure the overhead, announce INFO. */
void hil_start(void);

/* Handle whatever input is waiting (never blocks longer than port_read). */
void hil_poll(void);

/* hil_start(), then hil_poll() for ever. */
void hil_serve(void);

#endif /* HIL_PROTO_H */
