"""``mpcgen generate``: config -> derived tables -> C for one target + a report.

Besides the step (``<prefix>_mpc.c/.h``, ``mpc_binding.h``) it writes the
portable speed PI (``<prefix>_speed_pi.c/.h``) every target can use.

The report (``<prefix>_report.md``) lists what the C contains (the
topology's :meth:`~codegen.topology.Topology.report`).  A fixed-point config
also gets ``<prefix>_quantisation.md``: the quantisation report of the
generated strategy (``codegen.stages.quantreport``; ``mpcgen report`` gives
every strategy, plots and JSON).  Deterministic: the same config gives the
same bytes.
"""
from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from codegen.model import Model
from codegen.numfmt import number_format
from codegen.render import render_speed_pi, write_files
from codegen.topology import topology_of


def generate(model: Model, outdir: Path, log: Callable[[str], None] = print,
             extra: dict[str, str] | None = None) -> list[Path]:
    """Write the C files and the report for ``model.target`` into ``outdir``, and the target-independent
    files ``extra`` (:func:`target_independent_files`; computed here when not given)."""
    topo = topology_of(model)
    c = model.controller
    log(f"deriving the {topo.title} tables for {model.name} ({c.strategy}, tables {c.tables})")
    tables = topo.derive(model)
    files = topo.render(model, tables, model.target)
    files.update(render_speed_pi(model, model.target))
    files[f"{model.prefix}_report.md"] = topo.report(model, tables, model.target)
    files.update(target_independent_files(model, log) if extra is None else extra)
    return write_files(files, outdir)


def target_independent_files(model: Model, log: Callable[[str], None] = print) -> dict[str, str]:
    """Files that are the same for every target: for a quantised number format, the quantisation
    report of the generated strategy (``<prefix>_quantisation.md``); else none."""
    if not number_format(model.controller.number_format).quantised:
        return {}
    from codegen.stages.quantreport import report_name

    log(f"quantisation report of {model.name} ({model.controller.strategy}): against the float64 ideal "
        "and the float controller")
    return {report_name(model): _quantisation(model.replace(target="host"))}


#: states of the generated report (``mpcgen report`` takes more random states and every closed-loop state)
GENERATE_RANDOM_STATES = 5_000
GENERATE_CLOSED_LOOP_STATES = 20_000


def _quantisation(model: Model) -> str:
    """The quantisation report of ``model``'s strategy."""
    from codegen.stages.quantisation import analyse
    from codegen.stages.quantreport import markdown

    data = analyse(model, [model.controller.strategy], random_states=GENERATE_RANDOM_STATES,
                   max_closed_loop=GENERATE_CLOSED_LOOP_STATES)
    return markdown(model, data)
