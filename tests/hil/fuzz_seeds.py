"""The seed corpus of the firmware's fuzz target (tests/hil/fuzz/corpus/), written from the protocol.

Each seed is one input of tests/hil/fuzz/fuzz_frame.c for the fuzz test's
model (the two-level example, strategy s1): every message the board takes
and every error path of firmware/runtime/hil_proto.c and onboard_check --
a bad CRC, malformed COBS, a short frame, both oversize paths, an unknown
type, the LENGTH errors of STEP, BATCH (no head, count and length
differ) and SETPOINTS, BATCH counts 0 and above the maximum, and every
SETPOINTS detail -- plus valid SETPOINTS runs (all frames, a frame window).
tests/hil/test_fuzz.py checks that the files equal :func:`seeds` (the
corpus follows the protocol) and that running them reaches every error
path.  Write them after a protocol change with

    PYTHONPATH=. .venv/bin/python tests/hil/fuzz_seeds.py
"""
from __future__ import annotations

import sys
from pathlib import Path

CORPUS = Path(__file__).resolve().parent / "fuzz" / "corpus"


def seeds() -> dict[str, bytes]:
    """Seed name -> input octets."""
    if str(Path(__file__).resolve().parent.parent) not in sys.path:
        sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
    from hil.framing import encode_frame, max_encoded
    from hil.messages import batch_payload, setpoints_payload, step_payload
    from hil.schema import Msg, Schema

    from conftest import example

    m, _ = example("spmsm", "s1")
    s = Schema.of(m)
    states = s.input.zeros(2)
    for i, f in enumerate(s.input.fields):
        states[f.name] = (0.25 * (i + 1), -0.5 * (i + 1)) if f.kind == "real" else (1, 2)
    steps = [(0, 10.0, 1.0), (20, -10.0, 2.0)]

    def setpoints(periods: int = 40, decimation: int = 3, first: int = 0, count: int = 3, **change: object) -> bytes:
        rec = s.setpoints.unpack(setpoints_payload(s, periods, decimation, steps, first, count))
        for name, value in change.items():
            field = rec[name]
            if isinstance(value, tuple):
                field[0, :len(value)] = value
            else:
                rec[name] = value
        return encode_frame(Msg.SETPOINTS, 40, s.setpoints.pack(rec).tobytes())

    hello = encode_frame(Msg.HELLO, 1)
    bad_crc = bytearray(hello)
    bad_crc[-2] ^= 0x10
    step = step_payload(s, states[:1])
    head = s.batch_head.zeros(1)
    return {
        "hello": hello,
        "ping": encode_frame(Msg.PING, 0x0A01, b"abc"),
        "reset_hello": encode_frame(Msg.RESET, 5) + encode_frame(Msg.HELLO, 6),
        "step": encode_frame(Msg.STEP, 2, step),
        "batch2": encode_frame(Msg.BATCH, 3, batch_payload(s, states)),
        "bad_crc": bytes(bad_crc),
        "bad_cobs": b"\x00\x05ab\x00",  # a block running past the end
        "short": b"\x00\x04\x01\x02\x03\x00",  # 3 octets: less than head + CRC
        "unknown_type": encode_frame(0x77, 7, b"x"),
        "oversize": b"\xff" + b"A" * 200,  # 3200 octets: more than the receive buffer
        # max_encoded octets of 0x01: the buffer holds them, they decode to more than MAX_FRAME zeros
        "oversize_decoded": b"\xfe" + max_encoded().to_bytes(2, "little") + b"\x01",
        "step_length": encode_frame(Msg.STEP, 8, step[:-1]),
        "batch_no_head": encode_frame(Msg.BATCH, 9, b"\x01"),
        "batch_count_zero": encode_frame(Msg.BATCH, 10, s.batch_head.pack(head).tobytes()),
        "batch_count_big": encode_frame(Msg.BATCH, 11, (s.max_batch + 1).to_bytes(2, "little")),
        "batch_length": encode_frame(Msg.BATCH, 12, batch_payload(s, states)[:-1]),
        "setpoints_run": setpoints(),
        "setpoints_window": setpoints(decimation=1, first=1, count=2),
        "setpoints_length": encode_frame(Msg.SETPOINTS, 13, setpoints_payload(s, 40, 3, steps)[:-4]),
        "setpoints_periods": setpoints(periods=0),
        "setpoints_decimation": setpoints(decimation=0),
        "setpoints_steps": setpoints(n_steps=0),
        "setpoints_first_step": setpoints(step_k=(5,)),
        "setpoints_order": setpoints(step_k=(0, 20, 20), n_steps=3),
        "setpoints_window_bad": setpoints(first=-1),
    }


def write(folder: Path = CORPUS) -> None:
    """Replace the corpus in ``folder`` with :func:`seeds`."""
    folder.mkdir(parents=True, exist_ok=True)
    for old in folder.iterdir():
        old.unlink()
    for name, data in seeds().items():
        (folder / name).write_bytes(data)


if __name__ == "__main__":
    write()
    print(f"wrote {len(list(CORPUS.iterdir()))} seeds to {CORPUS}")
