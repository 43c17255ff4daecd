"""The protocol schema: hashes follow the records; the generated codec compiles strictly everywhere."""
from __future__ import annotations

import dataclasses
import re
import subprocess
from pathlib import Path

import pytest
from hil_support import ROOT, example

from codegen.hostbuild import STRICT_CFLAGS
from codegen.records import Field, Record
from codegen.stages import firmware
from codegen.stages.firmware import ARM_CFLAGS
from codegen.topology import topology_of
from hil import schema as sch
from hil.codecgen import protocol_build
from hil.messages import info_payload, parse_info
from hil.schema import Schema, hash_words, words_hash

MODEL_H = ROOT / "tests" / "firmware" / "c28x_type_model.h"
C28X_FLAGS = ("-DMPC_C28X_TYPE_MODEL", "--param=min-pagesize=0", "-include", str(MODEL_H))
PROTOCOL_C = ("gen/hil_codec.c", "firmware/runtime/hil_proto.c", "firmware/runtime/hil_cobs.c",
              "firmware/runtime/hil_wire.c", "firmware/runtime/main.c")


def _with_field(rec: Record, index: int, **change: object) -> Record:
    fields = list(rec.fields)
    fields[index] = dataclasses.replace(fields[index], **change)
    return Record(rec.name, tuple(fields))


def test_schema_hash_changes_when_a_record_changes():
    m, _ = example("spmsm", "conventional")
    s = Schema.of(m)
    assert s.schema_hash == Schema.of(m).schema_hash and len(s.schema_hash) == 16
    for change in ({"name": "renamed"}, {"kind": "f32"}, {"length": 2}):
        other = dataclasses.replace(s, output=_with_field(s.output.record, 0, **change).bind(s.output.nf))
        assert other.schema_hash != s.schema_hash, change
    grown = Record(s.input.record.name, (*s.input.record.fields, Field("extra", "u16", 1, "x")))
    assert dataclasses.replace(s, input=grown.bind(s.input.nf)).schema_hash != s.schema_hash
    t, _ = example("tlevel", "mpdtc27")
    assert Schema.of(t).schema_hash != s.schema_hash


def test_header_record_change_changes_the_hash(monkeypatch):
    m, _ = example("spmsm", "conventional")
    before = Schema.of(m).schema_hash
    monkeypatch.setattr(sch, "RESULT_HEAD", _with_field(sch.RESULT_HEAD, 0, kind="u16"))
    monkeypatch.setattr(Schema, "result_head", property(lambda self: self.header(sch.RESULT_HEAD)))
    assert Schema.of(m).schema_hash != before


def test_info_round_trip_and_hash_words():
    m, _ = example("tlevel", "mpdtc63")
    s = Schema.of(m)
    assert words_hash(hash_words(s.schema_hash)) == s.schema_hash
    info = parse_info(s, info_payload(s, "qemu-m7", clock_hz=25_000_000, overhead=12, cycle_unit="ticks"))
    assert (info.schema_hash, info.config_hash, info.target, info.cycle_unit) == \
        (s.schema_hash, s.config_hash, "qemu-m7", "ticks")
    assert (info.core_clock_hz, info.overhead_cycles, info.number_format) == (25_000_000, 12, "float32")
    assert s.max_batch * s.input_octets + 10 <= sch.MAX_FRAME and s.result_octets + 8 <= sch.MAX_FRAME


PROJECTS = [("stm32h743", "tlevel", "mpdtc27"), ("tms320f28377", "tlevel", "mpdtc27"),
            ("tms320f28377", "spmsm", "conventional")]


@pytest.fixture(scope="module", params=PROJECTS, ids=[f"{b}-{c}" for b, c, _ in PROJECTS])
def project(request, tmp_path_factory) -> tuple[str, Path, list[str]]:
    """A protocol project and its on-board loop's C: onboard.c and the topology's on-board plant sources."""
    board, config, strategy = request.param
    m, t = example(config, strategy)
    out = tmp_path_factory.mktemp(board)
    firmware.write_firmware_project(m, t, board, out, 16, n_bench=0, protocol=protocol_build(m))
    plant_c = [f"firmware/runtime/{name}" for name in topology_of(m).firmware_plant(m) if name.endswith(".c")]
    assert plant_c and all((out / src).is_file() for src in plant_c)
    return board, out, ["firmware/runtime/onboard.c", *plant_c]


def test_protocol_c_compiles_strictly(project):
    """The protocol's C and the on-board loop's (the plant core in float32), with the board's flags: the
    Arm ones (-Wdouble-promotion: no float literal or value promoted to double), or the C28x type model
    (double poisoned)."""
    board, out, onboard_c = project
    incs = [f"-I{out / d}" for d in ("gen", "firmware/runtime", f"firmware/ports/{board}")]
    if board == "stm32h743":
        cc = ["arm-none-eabi-gcc", *ARM_CFLAGS]
    else:
        cc = ["gcc", *STRICT_CFLAGS, *C28X_FLAGS]
    for src in (*PROTOCOL_C, *onboard_c):
        r = subprocess.run([*cc, "-DMPC_HIL", *incs, "-c", str(out / src), "-o", "/dev/null"],
                           capture_output=True, text=True, cwd=out)  # -fstack-usage files land in the project
        assert r.returncode == 0, f"{board} {src}:\n{r.stderr}"
    assert "-DMPC_HIL" in (out / "Makefile").read_text()


def test_protocol_c_has_no_8bit_types_double_or_byte_pointers(project):
    _, out, onboard_c = project
    bad = re.compile(r"\bu?int8_t\b|\bdouble\b|\bchar\s*\*\s*\)")
    for src in [*PROTOCOL_C, *onboard_c, "gen/hil_codec.h", "gen/plant_config.h", "firmware/runtime/hil_proto.h",
                "firmware/runtime/hil_cobs.h", "firmware/runtime/hil_wire.h", "firmware/runtime/onboard.h"]:
        code = re.sub(r"/\*.*?\*/", " ", (out / src).read_text(), flags=re.S)
        assert not bad.search(code), src


def test_generated_codec_covers_every_field():
    m, t = example("tlevel", "mpdtc27")
    s = Schema.of(m)
    codec = protocol_build(m).files["gen/hil_codec.c"]
    for f in s.output.fields:
        assert f"rec->{f.name}" in codec
    assert f"#define HIL_OUTPUT_OCTETS {s.output_octets}u" in protocol_build(m).files["gen/hil_codec.h"]
