"""The firmware's protocol codec, generated from the schema's records, and the on-board plant's files.

:func:`protocol_files` renders ``templates/firmware/hil_codec.[ch].j2``
(formatting only) into ``gen/hil_codec.[ch]``: the protocol constants, a C
struct for each header record and, for every record (header records and the
controller's input and output), an encoder and a decoder that go field by
field, element by element, little-endian, one octet per ``uint16_t`` word.
For mode onboard it adds the on-board plant: the C files the topology names
(``Topology.firmware_plant``: the simulator's plant core, compiled there in
float32, and the topology's part of the loop) under ``firmware/runtime/``,
and ``gen/plant_config.h`` with the constants of :func:`plant_constants`,
each printed exactly through the float32 number format's literal.
:func:`protocol_build` wraps them for ``codegen.stages.firmware``.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from codegen import __version__
from codegen.errors import Unsupported
from codegen.model import Model, Plant
from codegen.numfmt.float32 import FLOAT32
from codegen.records import Field, RecordLayout
from codegen.render import environment
from codegen.stages.firmware import ProtocolBuild
from codegen.topology import topology_of

from .schema import MAX_FRAME, MAX_STEPS, PROTOCOL_VERSION, TELEMETRY_SAMPLES, Err, Msg, Schema, hash_words

__all__ = ["protocol_files", "protocol_build", "PlantConst", "plant_constants", "board_model", "ONBOARD_SUBSTEPS",
           "PLANT_FORMAT"]

#: RK4 sub-steps of the on-board plant per control period: its largest sub-step is dt_s / ONBOARD_SUBSTEPS
#: (a 7-segment period: each segment in sub-steps of at most that)
ONBOARD_SUBSTEPS = 10
#: the number format of the on-board plant (the plant core's sim_real_t there): its constants' literals
PLANT_FORMAT = FLOAT32


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


def _record(name: str, lay: RecordLayout, ctype: str, define: bool) -> dict[str, Any]:
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
                 ("run_end", s.run_end))]
    records += [_record("input", s.input, "mpc_input_t", False), _record("output", s.output, "mpc_output_t", False)]
    ctx = {"model_name": model.name, "config_hash": s.config_hash, "version": __version__,
           "schema_hash": s.schema_hash, "protocol_version": PROTOCOL_VERSION, "max_frame": MAX_FRAME,
           "max_batch": s.max_batch, "number_format": s.number_format, "decision_field": s.decision_field,
           "schema_words": hash_words(s.schema_hash), "config_words": hash_words(s.config_hash),
           "max_steps": MAX_STEPS, "telemetry_samples": TELEMETRY_SAMPLES,
           "messages": list(Msg), "errors": list(Err), "records": records}
    env = environment()
    files = {f"gen/hil_codec.{ext}": env.get_template(f"firmware/hil_codec.{ext}.j2").render(ctx) for ext in ("h", "c")}
    files["gen/plant_config.h"] = env.get_template("firmware/plant_config.h.j2").render(
        {**ctx, "constants": plant_constants(model)})
    files.update({f"firmware/runtime/{name}": text for name, text in topology_of(model).firmware_plant(model).items()})
    return files


def board_model(model: Model) -> Model:
    """The model the board simulates: ``model`` with the ideal plant (``Plant()``: the controller's motor and
    DC link, no non-idealities, the actuation delay the controller assumes), since a ``[plant]`` section is
    not modelled on board.  Its actuation delay is the simulator's rule on it,
    ``plant.delay_periods(controller.delay_compensation)`` (:func:`plant_constants`); the host's comparison
    runs ``simulate`` on the same model (:mod:`hil.onboard`)."""
    return model.replace(plant=Plant())


@dataclass(frozen=True)
class PlantConst:
    """One constant of ``gen/plant_config.h``: C name, C literal, doc."""

    name: str
    value: str
    doc: str


def _real(x: float) -> str:
    """``x`` rounded once to the on-board plant's format, as its exact C literal."""
    return PLANT_FORMAT.literal(PLANT_FORMAT.const(x))


def plant_constants(model: Model) -> list[PlantConst]:
    """Every constant of the on-board plant and speed loop (the controller's motor and DC link, its period,
    the speed loop, the scenario's speed mode, the actuation delay of :func:`board_model`'s plant by the
    simulator's rule, the largest RK4 sub-step): reals in the on-board plant's format, rounded once."""
    m, inv, c, sl = model.motor, model.inverter, model.controller, model.speed_loop
    delay = board_model(model).plant.delay_periods(c.delay_compensation)
    return [
        PlantConst("ONB_RS", _real(m.rs_ohm), "stator resistance, ohm"),
        PlantConst("ONB_LD", _real(m.ld_h), "d-axis inductance, H"),
        PlantConst("ONB_LQ", _real(m.lq_h), "q-axis inductance, H"),
        PlantConst("ONB_PSI_F", _real(m.psi_f_wb), "magnet flux linkage, Wb"),
        PlantConst("ONB_POLE_PAIRS", str(int(m.pole_pairs)), "pole pairs"),
        PlantConst("ONB_J", _real(m.j_kgm2), "inertia, kg*m^2"),
        PlantConst("ONB_B", _real(m.b_nms), "viscous friction, N*m*s/rad"),
        PlantConst("ONB_UDC", _real(inv.udc_v), "DC-link voltage, V"),
        PlantConst("ONB_C_F", _real(inv.c_f), "each DC-link capacitor (three-level neutral point), F"),
        PlantConst("ONB_DT", _real(c.dt_s), "control period, s"),
        PlantConst("ONB_KP", _real(sl.kp), "speed PI proportional gain, N*m*s/rad"),
        PlantConst("ONB_KI", _real(sl.ki), "speed PI integral gain, N*m/rad"),
        PlantConst("ONB_LIMIT", _real(sl.limit_nm), "speed PI clamp, +-N*m"),
        PlantConst("ONB_SPEED_IMPOSED", "1" if model.scenario.speed_mode == "imposed" else "0",
                   "1: the speed follows the reference, T* = load"),
        PlantConst("ONB_DELAY_PERIODS", str(delay),
                   "actuation delay d: the decision of k acts during [t_k+d, t_k+d+1) (Plant.delay_periods)"),
        PlantConst("ONB_SUBSTEP_MAX_S", _real(c.dt_s / ONBOARD_SUBSTEPS),
                   f"largest RK4 sub-step, s (dt_s / {ONBOARD_SUBSTEPS})"),
    ]


def protocol_build(model: Model, schema: Schema | None = None) -> ProtocolBuild:
    """What ``write_firmware_project`` adds for a serial protocol build of ``model``."""
    return ProtocolBuild(protocol_files(model, schema))
