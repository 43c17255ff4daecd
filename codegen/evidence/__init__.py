"""One self-contained HTML page of a run's evidence (``mpcgen evidence``).

The page gathers what the other commands wrote for one config -- ``verify --json``, ``simulate --json
--plots``, ``report -o``, ``bench --json``, ``hil --json``, the generate manifest -- into sections, each
naming the file it came from with its sha256.  It needs nothing outside itself: no external CSS,
script or font, and every image is inline as a ``data:`` URI.  The same inputs give the same bytes
(no timestamp).

:mod:`~codegen.evidence.inputs` reads the files and checks their config hashes,
:mod:`~codegen.evidence.sections` renders each section, :mod:`~codegen.evidence.markup` holds the
HTML building blocks.
"""
from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from pathlib import Path

from codegen.errors import UsageError
from codegen.evidence import sections as sec
from codegen.evidence.inputs import (
    Identity,
    Inputs,
    Source,
    check_belongs,
    config_hashes,
    quant_markdown,
    read_file,
    read_json,
    read_pngs,
)
from codegen.evidence.markup import BAD, esc
from codegen.evidence.sections import ConfigFacts

__all__ = ["ConfigFacts", "Identity", "Inputs", "collect", "named_config_hashes", "check_belongs", "page"]

#: the page's style sheet (inline: the page loads nothing)
_CSS = """
body { font-family: sans-serif; margin: 1.5em auto; max-width: 1200px; color: #111; line-height: 1.35; }
h1 { font-size: 1.6em; } h2 { border-bottom: 2px solid #445; padding-bottom: .2em; margin-top: 1.6em; }
table { border-collapse: collapse; margin: .6em 0; font-size: .85em; }
th, td { border: 1px solid #bbb; padding: .2em .5em; text-align: left; vertical-align: top;
         overflow-wrap: anywhere; }
th:first-child, td:first-child { white-space: nowrap; }
th { background: #e8e8f0; }
code { font-family: monospace; font-size: .95em; }
.source { color: #444; font-size: .85em; margin: .2em 0; }
ul.source { padding-left: 1.2em; }
.absent { color: #777; font-style: italic; }
.bad { color: #b00000; font-weight: bold; background: #fde8e8; }
.ok { color: #145214; }
nav li.bad { background: none; }
.figures { display: flex; flex-wrap: wrap; gap: 1em 2%; }
.figures figure { width: 49%; }
figure { margin: .5em 0; }
figure img { max-width: 100%; border: 1px solid #ccc; }
figcaption { font-size: .75em; color: #444; overflow-wrap: anywhere; }
pre { background: #f4f4f4; padding: .5em; overflow-x: auto; }
"""
_MD_IMAGE = re.compile(r"^!\[[^\]]*\]\(([^)\s]+)\)\s*$", re.M)


def _report_images(option: str, md: Source) -> dict[str, Source]:
    """The PNGs the markdown shows that exist beside it (names inside its folder only)."""
    folder = Path(md.path).parent
    out: dict[str, Source] = {}
    for src in sorted(set(_MD_IMAGE.findall(md.text))):
        if src.startswith("/") or ".." in Path(src).parts:
            continue
        candidate = folder / src
        if candidate.is_file():
            out[src] = read_file(option, candidate)
    return out


def collect(*, verify: Sequence[str] = (), simulate: str | None = None, plots: str | None = None,
            report: str | None = None, bench: str | None = None, hil: Sequence[str] = (),
            manifest: Sequence[str] = ()) -> Inputs:
    """Read every input named (paths as given); a missing or unreadable one is a :class:`UsageError`."""
    md = read_file("--report", quant_markdown("--report", report)) if report is not None else None
    return Inputs(
        verify=tuple(read_json("--verify", p) for p in verify),
        simulate=read_json("--simulate", simulate) if simulate is not None else None,
        plots=read_pngs("--plots", plots) if plots is not None else (),
        plots_dir=plots,
        report=md,
        report_images=_report_images("--report", md) if md is not None else {},
        bench=read_json("--bench", bench) if bench is not None else None,
        hil=tuple(read_json("--hil", p) for p in hil),
        manifest=tuple(read_json("--manifest", p) for p in manifest),
    )


def named_config_hashes(inputs: Inputs) -> set[str]:
    """Every config hash the inputs name."""
    return {h for s in inputs.all() for h in config_hashes(s)}


def page(facts: ConfigFacts, inputs: Inputs, identities: Mapping[str, Identity]) -> str:
    """The HTML page (one string); ``identities``: the config hashes that are this config's."""
    if facts.config_hash not in identities:
        raise UsageError(f"{facts.path}: the config's own hash {facts.config_hash} is not among its identities")
    parts = [sec.config_section(facts, identities), sec.hashes_section(inputs, identities),
             sec.verify_section(inputs, identities), sec.hil_section(inputs), sec.quantisation_section(inputs),
             sec.bench_section(inputs), sec.simulate_section(inputs), sec.plots_section(inputs)]
    if inputs.manifest:
        parts.insert(2, sec.manifest_section(inputs))
    nav = "\n".join(f'<li class="{BAD}"><a href="#{p.id}">{esc(p.title)}</a> (flagged)</li>' if p.bad else
                    f'<li><a href="#{p.id}">{esc(p.title)}</a></li>' for p in parts)
    title = f"mpcgen evidence: {facts.name}"
    return ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            f"<title>{esc(title)}</title>\n<style>{_CSS}</style>\n</head>\n<body>\n"
            f"<h1>{esc(title)}</h1>\n"
            f'<p class="source">config <code>{esc(facts.name)}</code> hash <code>{esc(facts.config_hash)}</code>, '
            f"mpcgen {esc(facts.version)}; every section names the file it came from and its sha256</p>\n"
            f"<nav><ul>\n{nav}\n</ul></nav>\n"
            + "\n".join(p.html() for p in parts) + "\n</body>\n</html>\n")
