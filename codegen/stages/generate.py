"""``mpcgen generate``: config -> derived tables -> C for one target + reports + a manifest.

Besides the step (``<prefix>_mpc.c/.h``, ``mpc_binding.h``) it writes the
portable speed PI (``<prefix>_speed_pi.c/.h``) every target can use and, for
a target that drives a power stage, the topology's modulator
(``<prefix>_modulator.c/.h``: decision -> timer compares) and an example
interrupt routine (``<prefix>_isr_example.c``), docs/modulator.md.

The report (``<prefix>_report.md``) lists what the C contains (the
topology's :meth:`~codegen.topology.Topology.report`) and ends with the C
hash and the SHA-256 of every C file.  A fixed-point config also gets
``<prefix>_quantisation.md``: the quantisation report of the generated
strategy (``codegen.stages.quantreport``; ``mpcgen report`` gives every
strategy, plots and JSON), naming the same C hash.  ``<prefix>_manifest.json``
(``codegen.manifest``) gives the SHA-256 of every file written, the C hash,
the config hash, target, strategy and number format.  Deterministic: the
same config gives the same bytes.
"""
from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from codegen.manifest import C_HASH_DEFINITION, c_hash_of, manifest, manifest_name, manifest_text, sources
from codegen.model import Model
from codegen.numfmt import number_format
from codegen.render import write_files
from codegen.topology import topology_of

Log = Callable[[str], None]


def generate(model: Model, outdir: Path, log: Log = print, analysis: dict[str, Any] | None = None) -> list[Path]:
    """Write the C files, the reports and the manifest for ``model.target`` into ``outdir``.

    ``analysis``: :func:`quantisation_analysis` of ``model`` (the same for every target, so a caller
    generating several targets computes it once); computed here when None."""
    topo = topology_of(model)
    c = model.controller
    log(f"deriving the {topo.name} tables for {model.name} (controller.strategy {c.strategy})")
    tables = topo.derive(model)
    files = sources(model, model.target, tables)
    hashes = manifest(files)
    c_hash = c_hash_of(files)
    files[f"{model.prefix}_report.md"] = topo.report(model, tables, model.target) + _hash_section(
        model, hashes, c_hash)
    data = quantisation_analysis(model, log) if analysis is None else analysis
    if data is not None:
        from codegen.stages.quantreport import markdown, report_name

        files[report_name(model)] = markdown(model, data, {c.strategy: c_hash})
    files[manifest_name(model)] = manifest_text(model, files)
    return write_files(files, outdir)


def _hash_section(model: Model, hashes: dict[str, str], c_hash: str) -> str:
    """The report's last section: the C hash and the SHA-256 of every C file (markdown)."""
    lines = ["", "## Generated files", "",
             f"- C hash: `{c_hash}` ({C_HASH_DEFINITION}; also in `{manifest_name(model)}`)"]
    lines += [f"- `{name}`: sha256 `{h}`" for name, h in hashes.items()]
    return "\n".join(lines) + "\n"


#: states of the generated report (``mpcgen report`` takes more random states and every closed-loop state)
GENERATE_RANDOM_STATES = 5_000
GENERATE_CLOSED_LOOP_STATES = 20_000


def quantisation_analysis(model: Model, log: Log = print) -> dict[str, Any] | None:
    """For a quantised number format, the quantisation analysis of ``model``'s strategy
    (``codegen.stages.quantisation.analyse``) for ``<prefix>_quantisation.md``; else None.
    Target-independent: it runs on the host twin of ``model`` (the Python reference and host builds of
    the same arithmetic), so ``generate --target all`` computes it once."""
    if not number_format(model.controller.number_format).quantised:
        return None
    from codegen.stages.quantisation import analyse

    log(f"quantisation report of {model.name} ({model.controller.strategy}): against the float64 ideal "
        "and the float controller")
    return analyse(model.replace(target="host"), [model.controller.strategy], random_states=GENERATE_RANDOM_STATES,
                   max_closed_loop=GENERATE_CLOSED_LOOP_STATES)
