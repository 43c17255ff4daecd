"""``mpcgen generate``: config -> derived tables -> C for one target + a report.

The report (``<prefix>_report.md``) lists what the C contains: constants with
their float32 bits, the candidate rows, the memory the tables take, the
input guard and the assumptions the step makes.  Deterministic: no dates,
no paths, sorted output.
"""
from __future__ import annotations

from pathlib import Path
from typing import Callable

from . import __version__
from .model import Model
from .render import PROFILES, render_two_level, write_files
from .twolevel.derive import TwoLevelTables
from .twolevel.interface import FAULT_BITS, N_VECTORS
from .twolevel.switch_tables import tables_for


def table_bytes(t: TwoLevelTables) -> dict[str, int]:
    """Bytes of read-only data the step's tables take (uint16 = 2, float = 4)."""
    return {
        "ux, uy (float)": 2 * N_VECTORS * 4,
        "vec_to_sw, zero_sw (uint16)": (N_VECTORS + 8) * 2,
        "sw_to_vec (uint16)": 8 * 2 if t.delay_compensation else 0,
        "candidate rows (uint16)": len(t.rows) * (N_VECTORS + 1) * 2,
    }


def report_text(model: Model, t: TwoLevelTables, target: str) -> str:
    """Markdown report of the generated controller."""
    c = model.controller
    lines = [
        f"# {model.prefix}: generated two-level MPTC controller",
        "",
        f"- config: `{model.name}` (hash {model.config_hash()}), mpcgen {__version__}",
        f"- target profile: {target} -- {PROFILES[target].description}",
        f"- strategy `{c.strategy}`, predictor `{c.predictor}`, delay compensation {c.delay_compensation}, tables `{c.tables}`",
        f"- number format: {c.number_format}; build with `-ffp-contract=off -fno-math-errno` (numerics.md)",
        "",
        "## Constants (float64 -> float32 once)",
        "",
        "| name | value | float32 bits | unit | meaning |",
        "|---|---|---|---|---|",
    ]
    for k in t.consts:
        bits = int(k.value.view("uint32"))
        lines.append(f"| {k.name} | {float(k.value)!r} | 0x{bits:08x} | {k.unit} | {k.doc} |")
    lines += ["", "## Candidate rows", ""]
    for i, r in enumerate(t.rows):
        lines.append(f"- row {i}: " + " ".join(f"V{v}" for v in r))
    lines += ["", "## Read-only data", ""]
    tb = table_bytes(t)
    for k, v in tb.items():
        lines.append(f"- {k}: {v} bytes")
    lines.append(f"- total: {sum(tb.values())} bytes")
    lines += ["", "## Input guard (safe decision: zero vector 000, fault bits set)", ""]
    for name, bit, doc in FAULT_BITS:
        lines.append(f"- FAULT_{name} = {bit}: {doc}")
    lines += [
        "",
        "## Assumptions",
        "",
        "- flux-geometry: Rs neglected and rotor frozen over dt (seed eq. (1)-(3)); dq-euler: forward Euler,",
        "  candidate voltages rotated with theta_e(k).",
        "- delay compensation (when on): k+1 predicted under the vector applied now, candidates for k+2.",
        "- sin/cos: generated polynomial, |error| < 2e-7 for |theta_e| <= 256 rad (tests/test_trig.py).",
        "",
    ]
    return "\n".join(lines)


def generate(model: Model, outdir: Path, log: Callable[[str], None] = print) -> list[Path]:
    """Write the C files and the report for ``model.target`` into ``outdir``."""
    if model.inverter.topology == "t-type":
        from .threelevel.derive import derive_three_level
        from .threelevel.render import render_three_level

        log(f"deriving the three-level tables for {model.name} ({model.controller.strategy})")
        t3 = derive_three_level(model)
        files = render_three_level(model, t3, model.target)
        return write_files(files, outdir)
    log(f"deriving tables for {model.name} ({model.controller.strategy}, tables {model.controller.tables})")
    t = tables_for(model, progress=lambda f: log(f"  training run {f:5.0%}"))
    files = render_two_level(model, t, model.target)
    files[f"{model.prefix}_report.md"] = report_text(model, t, model.target)
    return write_files(files, outdir)
