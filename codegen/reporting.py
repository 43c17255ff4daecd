"""Markdown building blocks of the ``generate`` report, shared by every topology.

Each topology's report composes these sections with its own candidate
tables and assumptions.  Deterministic: no dates, no paths.
"""
from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

from codegen import __version__
from codegen.model import Model
from codegen.numfmt import number_format
from codegen.render import PROFILES

__all__ = ["header", "constants_section", "memory_section", "guard_section", "bullets", "document"]


def header(model: Model, target: str, title: str, settings: str) -> list[str]:
    """Title, config, target profile, strategy settings and number format."""
    return [
        f"# {model.prefix}: generated {title} controller",
        "",
        f"- config: `{model.name}` (hash {model.config_hash()}), mpcgen {__version__}",
        f"- target profile: {target} -- {PROFILES[target].description}",
        f"- {settings}",
        f"- number format: {model.controller.number_format}; "
        + ("int32 counts, int64 intermediates, no floating point in the step"
           if number_format(model.controller.number_format).quantised
           else "build with `-ffp-contract=off -fno-math-errno`"),
    ]


def constants_section(consts: Iterable[Any], format_name: str = "float32", prefix: str = "") -> list[str]:
    """Every constant with its value, bits, unit and meaning, labelled in its number format
    ``format_name``: float32 gives the value and its float32 bits; a quantised format (fixed point)
    the stored int32 count and its bits (the Q format of each unit: ``<prefix>_quantisation.md``)."""
    if not number_format(format_name).quantised:
        lines = ["", "## Constants (float64 -> float32 once)", "",
                 "| name | value | float32 bits | unit | meaning |", "|---|---|---|---|---|"]
        for k in consts:
            bits = int(k.value.view("uint32"))
            lines.append(f"| {k.name} | {float(k.value)!r} | 0x{bits:08x} | {k.unit} | {k.doc} |")
        return lines
    lines = ["", f"## Constants (float64 -> {format_name} once: int32 counts)", "",
             f"Each constant is an int32 count of its unit's Q format: value = count x 2^-q SI units, q from the "
             f"unit (the Q formats, the stored values and their rounding errors: `{prefix}_quantisation.md`; "
             f"the field formats: `{prefix}_mpc.h`).", "",
             "| name | count (int32) | int32 bits | unit | meaning |", "|---|---|---|---|---|"]
    for k in consts:
        count = int(k.value)
        lines.append(f"| {k.name} | {count} | 0x{count & 0xFFFFFFFF:08x} | {k.unit} | {k.doc} |")
    return lines


def memory_section(table_bytes: Mapping[str, int]) -> list[str]:
    """Read-only data the step's tables take."""
    lines = ["", "## Read-only data", ""]
    lines += [f"- {k}: {v} bytes" for k, v in table_bytes.items()]
    lines.append(f"- total: {sum(table_bytes.values())} bytes")
    return lines


def guard_section(fault_bits: Iterable[tuple[str, int, str]], safe: str) -> list[str]:
    """The input guard's fault bits and the safe decision."""
    lines = ["", f"## Input guard (safe decision: {safe}, fault bits set)", ""]
    lines += [f"- FAULT_{name} = {bit}: {doc}" for name, bit, doc in fault_bits]
    return lines


def bullets(title: str, items: Iterable[str]) -> list[str]:
    """A titled bullet list."""
    return ["", f"## {title}", "", *[f"- {i}" for i in items]]


def document(model: Model, target: str, title: str, settings: str, consts: Iterable[Any],
             tables: list[str], table_bytes: Mapping[str, int], fault_bits: Iterable[tuple[str, int, str]],
             safe: str, assumptions: Iterable[str]) -> str:
    """The whole report: header, constants, the topology's ``tables`` section lines, memory, guard,
    assumptions."""
    lines = header(model, target, title, settings) + constants_section(consts, model.controller.number_format,
                                                                       model.prefix) + tables
    lines += memory_section(table_bytes) + guard_section(fault_bits, safe) + bullets("Assumptions", assumptions)
    return "\n".join(lines) + "\n"
