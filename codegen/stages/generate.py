"""``mpcgen generate``: config -> derived tables -> C for one target + a report.

Besides the step (``<prefix>_mpc.c/.h``, ``mpc_binding.h``) it writes the
portable speed PI (``<prefix>_speed_pi.c/.h``) every target can use.

The report (``<prefix>_report.md``) lists what the C contains (the
topology's :meth:`~codegen.topology.Topology.report`).  Deterministic: the
same config gives the same bytes.
"""
from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from codegen.model import Model
from codegen.render import render_speed_pi, write_files
from codegen.topology import topology_of


def generate(model: Model, outdir: Path, log: Callable[[str], None] = print) -> list[Path]:
    """Write the C files and the report for ``model.target`` into ``outdir``."""
    topo = topology_of(model)
    c = model.controller
    log(f"deriving the {topo.title} tables for {model.name} ({c.strategy}, tables {c.tables})")
    tables = topo.derive(model, progress=lambda f: log(f"  training run {f:5.0%}"))
    files = topo.render(model, tables, model.target)
    files.update(render_speed_pi(model, model.target))
    files[f"{model.prefix}_report.md"] = topo.report(model, tables, model.target)
    return write_files(files, outdir)
