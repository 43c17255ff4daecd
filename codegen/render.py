"""Rendering derived tables into C through jinja2 (templates only format).

The environment, the target profiles and the context every generated file
shares (banner, prefix, config hash); each topology builds the rest of its
context from its own derived tables.  Target profiles differ only in
placement attributes and comments; the arithmetic is identical for every
target.
"""
from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import jinja2

from codegen import __version__
from codegen.kernels.consts import Const
from codegen.kernels.trig import cos_names, horner_order, poly_text, sin_names, table_index_bound
from codegen.model import Model
from codegen.numfmt import NumberFormat, number_format
from codegen.numfmt.float32 import FLOAT32
from codegen.numfmt.interface import field_formats
from codegen.outputs import output_error, write_atomic
from codegen.records import REAL, Record
from codegen.resources import templates_dir
from codegen.templatecache import SealedBytecodeCache


@dataclass(frozen=True)
class Profile:
    """What a target changes in the emitted C."""

    name: str
    code_attr: str  # attribute placing the step (e.g. in ITCM)
    data_attr: str  # attribute placing the tables (e.g. in DTCM)
    description: str
    placed: bool = True  # False: target.placement = "default", no section attribute or pragma


def placed_profile(target: str, placement: str) -> Profile:
    """The profile of ``target`` under ``target.placement``: "tcm" keeps its sections (ITCM/DTCM,
    .TI.ramfunc); "default" drops every section attribute and pragma (the linker's defaults)."""
    p = PROFILES[target]
    if placement == "default":
        return dataclasses.replace(p, code_attr="", data_attr="", placed=False,
                                   description=p.description.split(":")[0] + ": default sections (target.placement)")
    return p


#: the profile of every ``target.name`` (codegen.model.TARGETS), by its name
PROFILES: dict[str, Profile] = {p.name: p for p in (
    Profile("host", "", "", "x86-64 host (cffi build, verification)"),
    Profile(
        "stm32h743",
        '__attribute__((section(".itcm_text")))',
        '__attribute__((section(".dtcm_rodata")))',
        "STM32H743 Cortex-M7: step in ITCM, tables in DTCM (RM0433 memory map)",
    ),
    Profile(
        "tms320f28377",
        "",
        "",
        "TMS320F28377 C28x+FPU32: 16-bit char/int, no double; step in .TI.ramfunc",
    ),
)}


@dataclass(frozen=True)
class TableRow:
    """One row of a generated C table: its cells and the comment naming them."""

    cells: tuple[int, ...]
    label: str


@functools.cache
def environment(format_name: str | None = None) -> jinja2.Environment:
    """The jinja2 environment: strict undefined, no autoescape, the ``interleave`` filter and, with a
    number format's name, its ``real_literal`` filter (exact C literal of a value in the format).  One per
    format and process (jinja2 keeps the compiled templates, reloading a template whose file changed); the
    compiled code is kept across processes (:mod:`codegen.templatecache`)."""
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(templates_dir())),
        undefined=jinja2.StrictUndefined,
        keep_trailing_newline=True,
        autoescape=False,
        bytecode_cache=SealedBytecodeCache(),
    )
    env.filters["interleave"] = interleave_lines
    if format_name is not None:
        env.filters["real_literal"] = number_format(format_name).literal
    return env


def interleave_lines(blocks: list[str]) -> list[str]:
    """Independent statement lists, one statement a line, interleaved statement by statement (first
    lines of every block, then second lines, ...; a shorter block drops out): the ``interleave``
    filter, for chains the compiler should overlap.  Lines are stripped, empty ones dropped."""
    lines = [[ln.strip() for ln in b.split("\n") if ln.strip()] for b in blocks]
    return [ls[i] for i in range(max(map(len, lines), default=0)) for ls in lines if i < len(ls)]


def base_context(model: Model, target: str) -> dict[str, Any]:
    """Context every generated file of ``model`` shares (with the number format's macro library)."""
    if target not in PROFILES:
        raise ValueError(f"unknown target {target!r}; allowed: {', '.join(PROFILES)}")
    nf = number_format(model.controller.number_format)
    return {
        "model_name": model.name,
        "config_hash": model.config_hash(),
        "version": __version__,
        "prefix": model.prefix,
        "PREFIX": model.prefix.upper(),
        "profile": placed_profile(target, model.placement),
        "number_format": nf.name,
        "numfmt": nf.macros,
    }


def render_files(templates: dict[str, str], ctx: dict[str, Any]) -> dict[str, str]:
    """File name -> rendered text, for file name -> template path (in the context's number format)."""
    env = environment(ctx.get("number_format"))
    return {name: env.get_template(tpl).render(ctx) for name, tpl in templates.items()}


def sincos_bound(nf: NumberFormat, what: str, extra_rad: float = 0.0) -> str:
    """The comment on the sin/cos table index: the largest |n| = round(|x| N/(2 pi)) for |x| up to the
    format's angle guard plus ``extra_rad`` (``what`` says where that bound comes from)."""
    x = nf.angle_guard_rad + extra_rad
    return f"|n| <= {table_index_bound(nf, x)}: |x| <= {what} = {x:.6g} rad"


def sincos_context(nf: NumberFormat) -> dict[str, object]:
    """What the sin/cos macros print (``templates/common/kernels.j2``): the table size and index mask,
    the coefficient names in Horner order (``trig.horner_order``) and the polynomials as text."""
    form = nf.sincos_form
    sin_lead, sin_rest = horner_order(sin_names(form))
    cos_lead, cos_rest = horner_order(cos_names(form))
    sin_poly, cos_poly = poly_text(form)
    return {"sincos_n": form.table_n, "sincos_mask": form.table_n - 1, "sin_lead": sin_lead, "sin_rest": sin_rest,
            "cos_lead": cos_lead, "cos_rest": cos_rest, "sin_poly": sin_poly, "cos_poly": cos_poly}


def step_context(model: Model, target: str, records: tuple[Record, Record],
                 faults: tuple[tuple[str, int, str], ...], **values: object) -> dict[str, Any]:
    """Context of a topology's step templates: the shared part (banner, number format, records,
    fault bits) plus the topology's own ``values`` (constants, tables, guard checks ...)."""
    nf = number_format(model.controller.number_format).scaled(values.get("scaling"))
    real = [f for r in records for f in r.fields if f.kind == REAL]
    limits = {name for c in values.get("guard", ()) for name in (c.limit, c.lo) if name}  # type: ignore[attr-defined]
    guard_bits = {c.name: nf.guard_bits(c.value) for c in values.get("consts", ())  # type: ignore[attr-defined]
                  if c.name in limits}
    return {
        **base_context(model, target),
        **nf.template_values(),
        "real_fields": [{"name": f.name, "q": nf.scaling.q(f.unit) if nf.scaling else 0}
                        for f in real],
        # fixed point: each real field's Q format (the header's comments and defines, the binding's helpers)
        "field_formats": field_formats(nf.scaling, real, [f.name for f in records[0].fields]),
        "faults": faults,
        "guard_bits": {name: bits for name, bits in guard_bits.items() if bits is not None},
        "dt_s": model.controller.dt_s,
        "angle_guard_rad": nf.angle_guard_rad,
        **sincos_context(nf),
        "input_fields": records[0].bind(nf).members,
        "output_fields": records[1].bind(nf).members,
        **values,
    }


def table_fields(tables: object) -> dict[str, object]:
    """The derived tables' dataclass fields by name, to spread into a step context."""
    return {f.name: getattr(tables, f.name) for f in dataclasses.fields(tables)}  # type: ignore[arg-type]


def render_step(model: Model, topology_dir: str, ctx: dict[str, Any]) -> dict[str, str]:
    """File name -> text of a step: ``<topology_dir>/mpc.h.j2``, ``mpc.c.j2`` and the shared binding."""
    p = model.prefix
    return render_files({f"{p}_mpc.h": f"{topology_dir}/mpc.h.j2", f"{p}_mpc.c": f"{topology_dir}/mpc.c.j2",
                         "mpc_binding.h": "common/binding.h.j2"}, ctx)


def render_step_cdef(ctx: dict[str, Any]) -> str:
    """cffi declarations (no preprocessor lines) of a step's host build."""
    return render_files({"cdef": "common/cdef.h.j2"}, ctx)["cdef"]


#: the speed PI's number format beside a float step; a fixed-point step gets the integer PI in its
#: own Q formats (``codegen.numfmt.speedpi``)
SPEED_PI_FORMAT = FLOAT32


def speed_pi_constants(model: Model) -> list[Const]:
    """Constants of the generated speed PI (``speed_loop``, ``controller.dt_s``), rounded once."""
    nf = SPEED_PI_FORMAT
    sl = model.speed_loop
    return [
        Const("SPI_KP", nf.const(sl.kp), "N*m*s/rad", "speed PI proportional gain kp"),
        Const("SPI_KI_DT", nf.const(sl.ki * model.controller.dt_s), "N*m/rad", "ki dt: integral += ki dt e"),
        Const("SPI_LIMIT_NM", nf.const(sl.limit_nm), "N*m", "torque reference and integral clamp"),
    ]


def render_speed_pi(model: Model, target: str, scaling: Any = None) -> dict[str, str]:
    """File name -> text of the portable speed PI, ``<prefix>_speed_pi.h`` and ``.c``: float32
    (``SPEED_PI_FORMAT``) beside a float step; with the fixed-point step's ``scaling``, integer in its Q
    formats (``codegen.numfmt.speedpi``; RepresentationError if a gain or the clamp does not fit)."""
    nf = SPEED_PI_FORMAT
    sl = model.speed_loop
    ctx = {**base_context(model, target), "number_format": nf.name, "numfmt": nf.macros,
           "consts": speed_pi_constants(model), "real": nf.c_type,
           "kp": sl.kp, "ki": sl.ki, "limit_nm": sl.limit_nm, "dt_s": model.controller.dt_s}
    if scaling is not None:
        from codegen.numfmt.speedpi import FixedSpeedPI

        ctx.update(FixedSpeedPI.of(sl.kp, sl.ki * model.controller.dt_s, sl.limit_nm, scaling).template_values())
    p = model.prefix
    return render_files({f"{p}_speed_pi.h": "common/speed_pi.h.j2", f"{p}_speed_pi.c": "common/speed_pi.c.j2"}, ctx)


def write_files(files: dict[str, str], outdir: Path) -> list[Path]:
    """Write relative paths -> text under ``outdir`` (folders created as needed), touching only the
    files whose bytes change so that builds stay incremental; the paths, in name order.  Each file is
    written through a temporary and renamed (:func:`codegen.outputs.write_atomic`): a full disk or a name
    the file system refuses stops with one line and leaves no half-written file."""
    written = []
    for name, text in sorted(files.items()):
        path = outdir / name
        data = text.encode()
        try:
            unchanged = path.is_file() and path.read_bytes() == data
        except OSError as exc:
            raise output_error(exc, path) from None
        if not unchanged:
            write_atomic(path, data)
        written.append(path)
    return written
