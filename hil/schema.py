"""The serial protocol, defined once: message types, error codes, header records, limits, schema hash.

Every payload is fixed-width little-endian octets: the controller's input and
output records (``codegen.records.RecordLayout.pack``/``unpack``) and the small
header records below (``codegen.records.fields`` tables).  The firmware's codec
(``gen/hil_codec.[ch]``) is generated from the same records
(:mod:`hil.codecgen`), and the schema hash -- over every message layout's
``layout_hash``, the message and error codes and the limits -- travels in INFO
next to the controller's config hash: the harness refuses a board whose
hashes differ.

A frame, before COBS: frame head (``type`` u16, ``seq`` u16), payload, CRC-32
of head + payload (4 octets, little-endian; :mod:`hil.crc32`).  On the wire:
``0x00``, the COBS-encoded frame, ``0x00`` (the leading delimiter ends any
garbage before the frame).
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass
from enum import IntEnum
from functools import cached_property

from codegen.model import Model
from codegen.numfmt import number_format
from codegen.records import Record, RecordLayout, fields
from codegen.topology import topology_of

__all__ = ["PROTOCOL_VERSION", "MAX_FRAME", "MAX_BATCH", "MAX_STEPS", "TELEMETRY_SAMPLES", "Msg", "Err", "HEADER_RECORDS",
           "SAMPLE_TRACE_FIELDS", "telemetry_sample", "Schema", "hash_words", "words_hash", "text_words",
           "words_text"]

#: protocol version (bump on any change the schema hash does not see)
PROTOCOL_VERSION = 1
#: most octets of a decoded frame (head, payload, CRC)
MAX_FRAME = 1024
#: most states of one BATCH frame (fewer where the frame limit says so)
MAX_BATCH = 32
#: octets of the frame head and of the CRC trailer
HEAD_OCTETS = 4
CRC_OCTETS = 4


class Msg(IntEnum):
    """Message types (frame head ``type``)."""

    HELLO = 1   # host -> board, empty: answer with INFO
    INFO = 2    # board -> host, info record: sent at start-up, after RESET and for HELLO
    STEP = 3    # host -> board, one input record
    RESULT = 4  # board -> host, result head + output record (seq of the state)
    BATCH = 5   # host -> board, batch head + count input records (state i answered with seq + i)
    PING = 6    # host -> board, any payload
    PONG = 7    # board -> host, the PING's payload
    RESET = 8   # host -> board, empty: the protocol restarts, the board announces INFO
    ERROR = 9   # board -> host, error record
    SETPOINTS = 10   # host -> board, setpoints record: run plant and controller on board (mode onboard)
    TELEMETRY = 11   # board -> host, telemetry head + count samples (seq: SETPOINTS seq + frame index + 1, mod 2^16)
    RUN_END = 12     # board -> host, end-of-run record of mode onboard (seq of the SETPOINTS)


class Err(IntEnum):
    """Error codes of an ERROR message (``code``)."""

    CRC = 1       # CRC of a received frame wrong
    COBS = 2      # COBS encoding malformed
    SHORT = 3     # frame shorter than head + CRC
    OVERSIZE = 4  # frame longer than MAX_FRAME (discarded up to the next delimiter)
    TYPE = 5      # unknown or board-to-host message type
    LENGTH = 6    # payload length wrong for the type
    BATCH = 7     # batch count 0 or above max_batch
    SETPOINTS = 8  # setpoints invalid (detail: 1 periods, 2 decimation, 3 step count, 4 step order, 5 frame window)


#: header records (one definition; the C structs and codec are generated from them)
FRAME_HEAD = Record("hil_frame_head", fields("""
    type  u16  1  message type (Msg)
    seq   u16  1  sequence number: the request's, echoed in the answer
"""))
INFO = Record("hil_info", fields("""
    protocol_version  u16  1   protocol version (PROTOCOL_VERSION)
    schema_hash       u16  4   schema hash, 64 bits, least significant word first
    config_hash       u16  4   controller config hash, 64 bits, least significant word first
    core_clock_hz     i32  1   core clock in Hz (0: unknown)
    overhead_cycles   i32  1   measurement overhead subtracted from every step's cycles
    max_batch         u16  1   most states of one BATCH
    max_frame         u16  1   most octets of a decoded frame
    target            u16  16  board name, one ASCII character per word, NUL padded
    number_format     u16  8   number format of the records, as target
    cycle_unit        u16  16  unit of the cycles, as target
"""))
RESULT_HEAD = Record("hil_result_head", fields("""
    cycles  i32  1  net cycles of the controller call (overhead subtracted, >= 0)
"""))
BATCH_HEAD = Record("hil_batch_head", fields("""
    count  u16  1  number of input records that follow
"""))
ERROR = Record("hil_error", fields("""
    code    u16  1  error code (Err)
    seq     u16  1  sequence number of the offending frame (0xFFFF: unknown)
    detail  u16  1  octets received (CRC, COBS, LENGTH, OVERSIZE) or the offending type / count
"""))
#: most piecewise-constant steps of one SETPOINTS profile
MAX_STEPS = 8
#: most samples of one TELEMETRY frame
TELEMETRY_SAMPLES = 16
#: An on-board run is deterministic (the same setpoints give the same samples and RUN_END, bar the cycle
#: counts): the harness asks for lost TELEMETRY frames again by sending the same setpoints with another
#: frame window (frame_first, frame_count), and checks that the second RUN_END equals the first.
SETPOINTS = Record("hil_setpoints", fields(f"""
    periods     i32  1  control periods to run (>= 1)
    decimation  u16  1  one telemetry sample every `decimation` periods (>= 1)
    n_steps     u16  1  steps of the profile used (1..{MAX_STEPS}), step_k[0] == 0, increasing
    step_k      i32  {MAX_STEPS}  period index where the step starts
    speed_rad_s f32  {MAX_STEPS}  mechanical speed reference from that period, rad/s
    load_nm     f32  {MAX_STEPS}  load torque from that period, N*m
    frame_first i32  1  first TELEMETRY frame sent (>= 0); frame i holds samples i*{TELEMETRY_SAMPLES} ..
    frame_count i32  1  TELEMETRY frames sent from frame_first (>= 0; 0: RUN_END only); the run is the same
"""))
TELEMETRY_HEAD = Record("hil_telemetry_head", fields("""
    count  u16  1  number of samples that follow
"""))
#: the TELEMETRY sample's fields at the sample instant, float32 on the wire; each named as the simulator's
#: trace names it (codegen.simulator.records.SIM_TRACE): one name per signal in Python, C, JSON and on
#: the wire
SAMPLE_TRACE_FIELDS = fields("""
    omega_m_rad_s  f32  1  plant mechanical speed, rad/s
    te_nm          f32  1  plant torque, N*m
    torque_ref_nm  f32  1  T* given to the controller, N*m
    ia_a           f32  1  plant phase current a, A
    ib_a           f32  1  plant phase current b, A
""")


def telemetry_sample(decision_field: str) -> Record:
    """The TELEMETRY sample record: the period index, :data:`SAMPLE_TRACE_FIELDS`, the controller's decision
    under the topology's name for it (``Topology.decision_field``, the output record's and the trace's)
    and its fault bits."""
    return Record("hil_sample", (
        *fields("k  i32  1  period index of the sample instant"), *SAMPLE_TRACE_FIELDS,
        *fields(f"{decision_field}  u16  1  the controller's decision (the topology's decision field)"),
        *fields("fault  u16  1  the controller's fault bits")))


RUN_END = Record("hil_run_end", fields("""
    periods      i32  1  periods run
    samples      i32  1  telemetry samples sent
    status       i32  1  0 ok, < 0 the plant diverged or a decision was invalid at period `periods`
    changes      i32  1  periods whose decision differs from the previous period's (full rate)
    cycles_min   i32  1  fewest net cycles of a controller call
    cycles_max   i32  1  most net cycles of a controller call
    cycles_sum   u16  4  sum of the net cycles, 64 bits, least significant word first
    hist         i32  8  controller calls per cycle bin: bin b counts cycles in [b*w, (b+1)*w), last bin open
    hist_width   i32  1  bin width w (cycles)
"""))
#: the header records every schema has (and the TELEMETRY sample, :func:`telemetry_sample`)
HEADER_RECORDS: tuple[Record, ...] = (FRAME_HEAD, INFO, RESULT_HEAD, BATCH_HEAD, ERROR, SETPOINTS, TELEMETRY_HEAD,
                                      RUN_END)


def hash_words(hex16: str) -> list[int]:
    """A 64-bit hex hash as four u16 words, least significant first."""
    v = int(hex16, 16)
    return [(v >> (16 * i)) & 0xFFFF for i in range(4)]


def words_hash(words: list[int]) -> str:
    """Inverse of :func:`hash_words`."""
    return f"{sum(int(w) << (16 * i) for i, w in enumerate(words)):016x}"


def text_words(text: str, n: int) -> list[int]:
    """ASCII text as ``n`` words, NUL padded."""
    codes = [ord(c) for c in text[:n]]
    return codes + [0] * (n - len(codes))


def words_text(words: list[int]) -> str:
    """Inverse of :func:`text_words` (up to the first NUL)."""
    out = []
    for w in words:
        if w == 0:
            break
        out.append(chr(int(w) & 0x7F))
    return "".join(out)


@dataclass(frozen=True)
class Schema:
    """Every message layout of one controller config, and the hashes the board must match."""

    input: RecordLayout
    output: RecordLayout
    config_hash: str
    number_format: str
    #: the output record's (and the trace's) field holding the decision (``Topology.decision_field``)
    decision_field: str

    @classmethod
    def of(cls, model: Model) -> Schema:
        """The schema of ``model``'s controller (its topology's records in its number format)."""
        topo = topology_of(model)
        nf = number_format(model.controller.number_format)
        return cls(topo.input_record.bind(nf), topo.output_record(model).bind(nf), model.config_hash(), nf.name,
                   topo.decision_field)

    def header(self, record: Record) -> RecordLayout:
        """A header record bound like the controller records."""
        return record.bind(self.input.nf)

    @cached_property
    def head(self) -> RecordLayout:
        return self.header(FRAME_HEAD)

    @cached_property
    def info(self) -> RecordLayout:
        return self.header(INFO)

    @cached_property
    def result_head(self) -> RecordLayout:
        return self.header(RESULT_HEAD)

    @cached_property
    def batch_head(self) -> RecordLayout:
        return self.header(BATCH_HEAD)

    @cached_property
    def error(self) -> RecordLayout:
        return self.header(ERROR)

    @cached_property
    def setpoints(self) -> RecordLayout:
        return self.header(SETPOINTS)

    @cached_property
    def telemetry_head(self) -> RecordLayout:
        return self.header(TELEMETRY_HEAD)

    @cached_property
    def sample(self) -> RecordLayout:
        return self.header(telemetry_sample(self.decision_field))

    @cached_property
    def run_end(self) -> RecordLayout:
        return self.header(RUN_END)

    @property
    def layouts(self) -> tuple[RecordLayout, ...]:
        """Every message layout, header records first."""
        return (self.head, self.info, self.result_head, self.batch_head, self.error, self.setpoints,
                self.telemetry_head, self.sample, self.run_end, self.input, self.output)

    @cached_property
    def schema_hash(self) -> str:
        """SHA-256 (hex, 16 chars) of the protocol version, the number format, the limits, the codes and
        every layout hash (a real field's C type is its format's: a float32 board and a fixed-point
        host never match)."""
        parts = [f"v{PROTOCOL_VERSION}", f"format={self.number_format}", f"frame{MAX_FRAME}", f"batch{MAX_BATCH}", f"steps{MAX_STEPS}",
                 f"telemetry{TELEMETRY_SAMPLES}",
                 ",".join(f"{m.name}={m.value}" for m in Msg), ",".join(f"{e.name}={e.value}" for e in Err)]
        parts += [f"{lay.record.name}:{lay.layout_hash}" for lay in self.layouts]
        return hashlib.sha256(";".join(parts).encode()).hexdigest()[:16]

    @property
    def input_octets(self) -> int:
        return self.input.packed_dtype.itemsize

    @property
    def output_octets(self) -> int:
        return self.output.packed_dtype.itemsize

    @property
    def result_octets(self) -> int:
        """Octets of a RESULT payload."""
        return self.result_head.packed_dtype.itemsize + self.output_octets

    @cached_property
    def max_batch(self) -> int:
        """Most states of one BATCH frame: MAX_BATCH, fewer where MAX_FRAME says so."""
        room = MAX_FRAME - HEAD_OCTETS - CRC_OCTETS - self.batch_head.packed_dtype.itemsize
        n = min(MAX_BATCH, room // self.input_octets)
        if n < 1:
            raise ValueError(f"an input record of {self.input_octets} octets does not fit a {MAX_FRAME}-octet frame")
        return n
