"""Render the derived tables into C through jinja2 (templates only format).

Target profiles differ only in placement attributes and comments; the
arithmetic is identical for every target.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import jinja2

from . import __version__
from .f32 import c_float_literal
from .model import Model
from .resources import templates_dir
from .twolevel.derive import TwoLevelTables
from .twolevel.interface import FAULT_BITS, INPUT_FIELDS, N_VECTORS, OUTPUT_FIELDS


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


@dataclass(frozen=True)
class _Row:
    cells: tuple[int, ...]
    label: str


def _row_labels(t: TwoLevelTables) -> list[str]:
    if t.n_sectors == 1:
        return ["all candidates V0..V6"]
    names = {
        2: ["dT>0", "dT<0"],
        4: ["dT>0 dpsi>0", "dT>0 dpsi<=0", "dT<0 dpsi>0", "dT<0 dpsi<=0"],
    }[t.n_conditions]
    return [f"{names[c]}, sector {s + 1}" for c in range(t.n_conditions) for s in range(t.n_sectors)]


def two_level_context(model: Model, t: TwoLevelTables, target: str) -> dict:
    """Template context: values to print, already derived."""
    labels = _row_labels(t)
    rows = [
        _Row(tuple(r) + (0,) * (N_VECTORS - len(r)), f"{lab}: " + " ".join(f"V{v}" for v in r))
        for r, lab in zip(t.rows, labels)
    ]
    return {
        "model_name": model.name,
        "config_hash": model.config_hash(),
        "version": __version__,
        "prefix": model.prefix,
        "PREFIX": model.prefix.upper(),
        "strategy": t.strategy,
        "predictor": t.predictor,
        "delay_compensation": t.delay_compensation,
        "profile": PROFILES[target],
        "consts": t.consts,
        "ux": t.ux,
        "uy": t.uy,
        "vec_to_sw": t.vec_to_sw,
        "sw_to_vec": t.sw_to_vec,
        "zero_sw": t.zero_sw,
        "n_sectors": t.n_sectors,
        "uses_threshold": t.uses_threshold,
        "rows": t.rows,
        "rows_padded": rows,
        "row_len": t.row_len,
        "n_vectors": N_VECTORS,
        "faults": FAULT_BITS,
        "input_fields": INPUT_FIELDS,
        "output_fields": OUTPUT_FIELDS,
    }


def render_two_level(model: Model, t: TwoLevelTables, target: str) -> dict[str, str]:
    """File name -> text of the generated controller for ``target``."""
    if target not in PROFILES:
        raise ValueError(f"unknown target {target!r}; allowed: {', '.join(PROFILES)}")
    env = environment()
    ctx = two_level_context(model, t, target)
    p = model.prefix
    return {
        f"{p}_mpc.h": env.get_template("twolevel/mpc.h.j2").render(ctx),
        f"{p}_mpc.c": env.get_template("twolevel/mpc.c.j2").render(ctx),
        "mpc_binding.h": env.get_template("twolevel/binding.h.j2").render(ctx),
    }


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
