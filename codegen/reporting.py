"""Markdown building blocks of the ``generate`` report, shared by every topology.

Each topology's report composes these sections with its own candidate
tables and assumptions.  Deterministic: no dates, no paths.
"""
from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

from codegen import __version__
from codegen.model import Model
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
        f"- number format: {model.controller.number_format}; build with `-ffp-contract=off -fno-math-errno`",
    ]


def constants_section(consts: Iterable[Any]) -> list[str]:
    """Every constant with its value, bits, unit and meaning."""
    lines = ["", "## Constants (float64 -> float32 once)", "",
             "| name | value | float32 bits | unit | meaning |", "|---|---|---|---|---|"]
    for k in consts:
        bits = int(k.value.view("uint32"))
        lines.append(f"| {k.name} | {float(k.value)!r} | 0x{bits:08x} | {k.unit} | {k.doc} |")
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
    lines = header(model, target, title, settings) + constants_section(consts) + tables
    lines += memory_section(table_bytes) + guard_section(fault_bits, safe) + bullets("Assumptions", assumptions)
    return "\n".join(lines) + "\n"
