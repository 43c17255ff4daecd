"""The firmware's protocol codec, generated from the schema's records.

:func:`protocol_files` renders ``templates/firmware/hil_codec.[ch].j2``
(formatting only) into ``gen/hil_codec.[ch]``: the protocol constants, a C
struct for each header record and, for every record (header records and the
controller's input and output), an encoder and a decoder that go field by
field, element by element, little-endian, one octet per ``uint16_t`` word.
:func:`protocol_build` wraps them for ``codegen.stages.firmware``.
"""
from __future__ import annotations

from dataclasses import dataclass

from codegen import __version__
from codegen.errors import Unsupported
from codegen.model import Model
from codegen.records import F32, I32, REAL, U16, Field, RecordLayout
from codegen.render import environment
from codegen.stages.firmware import ProtocolBuild

from .schema import MAX_FRAME, PROTOCOL_VERSION, Err, Msg, Schema, hash_words

__all__ = ["protocol_files", "protocol_build"]


@dataclass(frozen=True)
class Op:
    """One element of a field on the wire."""

    offset: int  # octet offset in the record's wire layout
    member: str  # C member expression ("schema_hash[2]")
    wire: str  # "u16" | "f32" | "i32"


def _wire(lay: RecordLayout, f: Field) -> str:
    if f.kind == U16:
        return "u16"
    if f.kind == I32:
        return "i32"
    if f.kind == F32 or (f.kind == REAL and lay.nf.name == "float32"):
        return "f32"
    raise Unsupported(f"the serial protocol has no codec for {lay.record.name}.{f.name} "
                      f"(kind {f.kind}, number format {lay.nf.name})")


def _ops(lay: RecordLayout) -> list[Op]:
    ops, offset = [], 0
    for f in lay.fields:
        size = lay.np_type(f).itemsize
        for j in range(f.length):
            ops.append(Op(offset, f"{f.name}[{j}]" if f.length > 1 else f.name, _wire(lay, f)))
            offset += size
    if offset != lay.packed_dtype.itemsize:
        raise AssertionError(f"{lay.record.name}: codec covers {offset} octets, layout has {lay.packed_dtype.itemsize}")
    return ops


def _record(name: str, lay: RecordLayout, ctype: str, define: bool) -> dict:
    return {"name": name, "record": lay.record.name, "ctype": ctype, "define": define,
            "members": lay.members, "octets": lay.packed_dtype.itemsize, "ops": _ops(lay)}


def protocol_files(model: Model, schema: Schema | None = None) -> dict[str, str]:
    """Project-relative path -> text of the generated protocol codec of ``model``."""
    s = schema or Schema.of(model)
    records = [_record(name, lay, f"hil_{name}_t", True) for name, lay in
               (("frame_head", s.head), ("info", s.info), ("result_head", s.result_head),
                ("batch_head", s.batch_head), ("error", s.error))]
    records += [_record("input", s.input, "mpc_input_t", False), _record("output", s.output, "mpc_output_t", False)]
    ctx = {"model_name": model.name, "config_hash": s.config_hash, "version": __version__,
           "schema_hash": s.schema_hash, "protocol_version": PROTOCOL_VERSION, "max_frame": MAX_FRAME,
           "max_batch": s.max_batch, "number_format": s.number_format,
           "schema_words": hash_words(s.schema_hash), "config_words": hash_words(s.config_hash),
           "messages": list(Msg), "errors": list(Err), "records": records}
    env = environment()
    return {f"gen/hil_codec.{ext}": env.get_template(f"firmware/hil_codec.{ext}.j2").render(ctx) for ext in ("h", "c")}


def protocol_build(model: Model, schema: Schema | None = None) -> ProtocolBuild:
    """What ``write_firmware_project`` adds for a serial protocol build of ``model``."""
    return ProtocolBuild(protocol_files(model, schema))
