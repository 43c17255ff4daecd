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

import numpy as np

from codegen import __version__
from codegen.errors import Unsupported
from codegen.model import Model
from codegen.records import Field, RecordLayout
from codegen.render import environment
from codegen.resources import firmware_dir
from codegen.stages.firmware import ProtocolBuild
from codegen.topology import topology_of

from .schema import MAX_FRAME, MAX_STEPS, PROTOCOL_VERSION, TELEMETRY_SAMPLES, Err, Msg, Schema, hash_words

__all__ = ["protocol_files", "protocol_build", "onboard_constants", "onboard_topology_file", "ONBOARD_SUBSTEPS"]

#: RK4 sub-steps of the on-board plant per control period (per 7-segment period: the same
#: largest sub-step dt_s / ONBOARD_SUBSTEPS, each segment split accordingly)
ONBOARD_SUBSTEPS = 10


@dataclass(frozen=True)
class Op:
    """One element of a field on the wire."""

    offset: int  # octet offset in the record's wire layout
    member: str  # C member expression ("schema_hash[2]")
    wire: str  # "u16" | "f32" | "i32"


#: numpy storage type of a field -> its wire codec (a real field: its number format's storage type)
WIRE = {np.dtype(np.uint16): "u16", np.dtype(np.int32): "i32", np.dtype(np.float32): "f32"}


def _wire(lay: RecordLayout, f: Field) -> str:
    try:
        return WIRE[np.dtype(lay.np_type(f)).newbyteorder("=")]
    except KeyError:
        raise Unsupported(f"the serial protocol has no codec for {lay.record.name}.{f.name} "
                          f"(kind {f.kind}, number format {lay.nf.name})") from None


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
    records += [_record(name, lay, f"hil_{name}_t", True) for name, lay in
                (("setpoints", s.setpoints), ("telemetry_head", s.telemetry_head), ("sample", s.sample),
                 ("onboard_end", s.onboard_end))]
    records += [_record("input", s.input, "mpc_input_t", False), _record("output", s.output, "mpc_output_t", False)]
    ctx = {"model_name": model.name, "config_hash": s.config_hash, "version": __version__,
           "schema_hash": s.schema_hash, "protocol_version": PROTOCOL_VERSION, "max_frame": MAX_FRAME,
           "max_batch": s.max_batch, "number_format": s.number_format,
           "schema_words": hash_words(s.schema_hash), "config_words": hash_words(s.config_hash),
           "max_steps": MAX_STEPS, "telemetry_samples": TELEMETRY_SAMPLES,
           "messages": list(Msg), "errors": list(Err), "records": records}
    env = environment()
    files = {f"gen/hil_codec.{ext}": env.get_template(f"firmware/hil_codec.{ext}.j2").render(ctx) for ext in ("h", "c")}
    files["gen/onboard_config.h"] = env.get_template("firmware/onboard_config.h.j2").render(
        {**ctx, "constants": onboard_constants(model)})
    name = onboard_topology_file(model)
    files[f"firmware/runtime/{name}"] = (firmware_dir() / "runtime" / name).read_text()
    return files


def onboard_topology_file(model: Model) -> str:
    """The runtime file with the topology's part of the on-board plant: ``onboard_<package>.c``, named after
    the package of the model's topology plugin (``codegen.topologies.<package>``)."""
    plugin = topology_of(model)
    return f"onboard_{plugin.__name__.split('.')[-2]}.c"  # type: ignore[attr-defined]


def _f32(x: float) -> str:
    return f"{float(x)!r}f".replace("inf", "INFINITY")


def onboard_constants(model: Model) -> list[tuple[str, str, str]]:
    """(C name, C literal, doc) of every constant of the on-board plant and speed loop."""
    m, inv, c, sl = model.motor, model.inverter, model.controller, model.speed_loop
    return [
        ("ONB_RS", _f32(m.rs_ohm), "stator resistance, ohm"),
        ("ONB_LD", _f32(m.ld_h), "d-axis inductance, H"),
        ("ONB_LQ", _f32(m.lq_h), "q-axis inductance, H"),
        ("ONB_PSI_F", _f32(m.psi_f_wb), "magnet flux linkage, Wb"),
        ("ONB_POLE_PAIRS", _f32(float(m.pole_pairs)), "pole pairs"),
        ("ONB_J", _f32(m.j_kgm2), "inertia, kg*m^2"),
        ("ONB_B", _f32(m.b_nms), "viscous friction, N*m*s/rad"),
        ("ONB_UDC", _f32(inv.udc_v), "DC-link voltage, V"),
        ("ONB_C_F", _f32(inv.c_f), "each DC-link capacitor (three-level neutral point), F"),
        ("ONB_DT", _f32(c.dt_s), "control period, s"),
        ("ONB_KP", _f32(sl.kp), "speed PI proportional gain"),
        ("ONB_KI", _f32(sl.ki), "speed PI integral gain"),
        ("ONB_LIMIT", _f32(sl.limit_nm), "speed PI clamp, +-N*m"),
        ("ONB_SPEED_IMPOSED", "1" if model.scenario.speed_mode == "imposed" else "0",
         "1: the speed follows the reference, T* = load"),
        ("ONB_DELAY_COMPENSATION", "1" if c.delay_compensation else "0",
         "two-level: 1 the decision acts one period later"),
        ("ONB_SUBSTEPS", str(ONBOARD_SUBSTEPS), "RK4 sub-steps per control period"),
    ]


def protocol_build(model: Model, schema: Schema | None = None) -> ProtocolBuild:
    """What ``write_firmware_project`` adds for a serial protocol build of ``model``."""
    return ProtocolBuild(protocol_files(model, schema))
