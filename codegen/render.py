"""Rendering derived tables into C through jinja2 (templates only format).

The environment, the target profiles and the context every generated file
shares (banner, prefix, config hash); each topology builds the rest of its
context from its own derived tables.  Target profiles differ only in
placement attributes and comments; the arithmetic is identical for every
target.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import jinja2

from codegen import __version__
from codegen.model import Model
from codegen.numfmt.float32 import c_float_literal
from codegen.resources import templates_dir


@dataclass(frozen=True)
class Profile:
    """What a target changes in the emitted C."""

    name: str
    code_attr: str  # attribute placing the step (e.g. in ITCM)
    data_attr: str  # attribute placing the tables (e.g. in DTCM)
    description: str


PROFILES: dict[str, Profile] = {
    "host": Profile("host", "", "", "x86-64 host (cffi build, verification)"),
    "stm32h743": Profile(
        "stm32h743",
        '__attribute__((section(".itcm_text")))',
        '__attribute__((section(".dtcm_rodata")))',
        "STM32H743 Cortex-M7: step in ITCM, tables in DTCM (RM0433 memory map)",
    ),
    "tms320f28377": Profile(
        "tms320f28377",
        "",
        "",
        "TMS320F28377 C28x+FPU32: 16-bit char/int, no double; step in .TI.ramfunc",
    ),
}


def environment() -> jinja2.Environment:
    """The jinja2 environment: strict undefined, C-float filter, no autoescape."""
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(templates_dir())),
        undefined=jinja2.StrictUndefined,
        keep_trailing_newline=True,
        autoescape=False,
    )
    env.filters["c_float"] = c_float_literal
    return env


def base_context(model: Model, target: str) -> dict:
    """Context every generated file of ``model`` shares."""
    if target not in PROFILES:
        raise ValueError(f"unknown target {target!r}; allowed: {', '.join(PROFILES)}")
    return {
        "model_name": model.name,
        "config_hash": model.config_hash(),
        "version": __version__,
        "prefix": model.prefix,
        "PREFIX": model.prefix.upper(),
        "profile": PROFILES[target],
    }


def render_files(templates: dict[str, str], ctx: dict) -> dict[str, str]:
    """File name -> rendered text, for file name -> template path."""
    env = environment()
    return {name: env.get_template(tpl).render(ctx) for name, tpl in templates.items()}


def write_files(files: dict[str, str], outdir: Path) -> list[Path]:
    """Write files (only when their bytes change, so builds stay incremental)."""
    outdir.mkdir(parents=True, exist_ok=True)
    written = []
    for name, text in sorted(files.items()):
        path = outdir / name
        data = text.encode()
        if not path.exists() or path.read_bytes() != data:
            path.write_bytes(data)
        written.append(path)
    return written
