"""The sections of the evidence page, one function each: HTML from the inputs.

Each section starts with its heading and a provenance line naming the file(s) it came from with their
sha256; a section whose input was not given says so and names the option.
"""
from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import PurePosixPath
from typing import Any

from codegen.evidence.inputs import CONFIG_HASH_KEY, Identity, Inputs, Source, config_hashes, named_hashes
from codegen.evidence.markup import BAD, cell, esc, figure, flatten, markdown_html, png_data_uri, table

__all__ = ["ConfigFacts", "Section", "config_section", "hashes_section", "verify_section", "hil_section",
           "quantisation_section", "bench_section", "simulate_section", "plots_section", "manifest_section"]


@dataclass(frozen=True)
class ConfigFacts:
    """The config the page is about, as the command line loaded it."""

    path: str
    sha256: str
    name: str
    config_hash: str
    topology: str
    strategy: str
    number_format: str
    target: str
    version: str
    #: the overrides given on the command line (``section.field=value``), in order
    overrides: tuple[str, ...]


@dataclass(frozen=True)
class Section:
    """One section: its anchor id, heading and body HTML; ``bad``: it holds a red flag."""

    id: str
    title: str
    body: str
    bad: bool = False

    def html(self) -> str:
        """The section element."""
        return f'<section id="{esc(self.id)}">\n<h2>{esc(self.title)}</h2>\n{self.body}\n</section>'


def _provenance(sources: Sequence[Source]) -> str:
    items = "".join(f"<li><code>{esc(s.path)}</code> sha256 <code>{s.sha256}</code></li>" for s in sources)
    return f'<ul class="source">{items}</ul>'


def _from(source: Source) -> str:
    return f'<p class="source">from <code>{esc(source.path)}</code> sha256 <code>{source.sha256}</code></p>'


def _absent(option: str, what: str) -> str:
    return f'<p class="absent">not given: pass <code>{esc(option)}</code> {esc(what)}</p>'


def _key_values(items: Sequence[tuple[str, object]], bad_keys: Callable[[str, object], bool]) -> tuple[str, bool]:
    rows = [[cell(k), cell(v, bad_keys(k, v))] for k, v in items]
    return table(("key", "value"), rows), any(bad_keys(k, v) for k, v in items)


def _positive(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and value > 0


def config_section(facts: ConfigFacts, identities: Mapping[str, Identity]) -> Section:
    """Name, hashes, topology, strategy, number format, target and overrides of the config."""
    rows: list[tuple[str, object]] = [
        ("name", facts.name), ("config hash", facts.config_hash), ("topology", facts.topology),
        ("strategy", facts.strategy), ("number format", facts.number_format), ("target", facts.target),
        ("overrides", ", ".join(facts.overrides) or "none"), ("mpcgen", facts.version)]
    rows += [(f"config hash: {i.label}", h) for h, i in identities.items() if h != facts.config_hash]
    body = (f'<p class="source">from <code>{esc(facts.path)}</code> sha256 <code>{facts.sha256}</code></p>\n'
            + table(("field", "value"), [[cell(k), cell(v)] for k, v in rows]))
    return Section("config", "Config", body)


def hashes_section(inputs: Inputs, identities: Mapping[str, Identity]) -> Section:
    """Every hash each input names; a config hash none of ``identities`` names is red."""
    sources = inputs.all()
    named = [(s, named_hashes(s)) for s in sources]
    seen: dict[str, list[str]] = {}
    for s, pairs in named:
        for key, value in pairs:
            seen.setdefault(value, []).append(f"{s.name}: {key}")
    rows, bad = [], False
    for s, pairs in named:
        if not pairs:
            rows.append([cell(s.option), cell(s.name), cell("(names no hash)"), cell("-"), cell("-")])
        for key, value in pairs:
            is_config = key.rsplit(".", 1)[-1] == CONFIG_HASH_KEY
            ident = identities.get(value) if is_config else None
            foreign = is_config and ident is None
            bad |= foreign
            others = [w for w in seen[value] if w != f"{s.name}: {key}"]
            verdict = ((ident.label if ident else "NOT THIS CONFIG") if is_config else
                       "same as " + "; ".join(others) if others else "")
            rows.append([cell(s.option), cell(s.name), cell(key), cell(value, foreign), cell(verdict, foreign)])
    config_named = sorted({h for s in sources for h in config_hashes(s)})
    if not sources:
        summary = '<p class="absent">no input names a hash</p>'
    elif bad:
        summary = (f'<p class="{BAD}">the inputs name config hashes that are not this config\'s: '
                   + esc(", ".join(h for h in config_named if h not in identities)) + " (included with --allow-mixed)</p>")
    else:
        summary = ('<p class="ok">every config hash the inputs name is this config\'s: '
                   + esc(", ".join(f"{h} ({identities[h].label})" for h in config_named)) + "</p>")
    body = (summary + "\n" + _provenance(sources) + "\n"
            + table(("input", "file", "key", "hash", "belongs to / named also by"), rows))
    return Section("hashes", "Hashes", body, bad)


def _format_of(source: Source, entry: Mapping[str, Any], identities: Mapping[str, Identity]) -> str:
    for data in (entry, source.json or {}):
        if isinstance(data.get("number_format"), str):
            return str(data["number_format"])
    ident = identities.get(str((source.json or {}).get(CONFIG_HASH_KEY)))
    return ident.number_format if ident else "?"


def verify_section(inputs: Inputs, identities: Mapping[str, Identity]) -> Section:
    """States and mismatches per strategy and number format, one table row per strategy and file."""
    if not inputs.verify:
        return Section("verify", "Verification", _absent("--verify FILE", "(mpcgen verify --json FILE)"))
    header = ("file", "strategy", "number format", "states", "mismatches", "guard trips", "states by source",
              "mismatches per field", "states/s", "first mismatch")
    rows, bad = [], False
    total_states = total_mismatches = 0
    for s in inputs.verify:
        strategies = (s.json or {}).get("strategies", {})
        for name in sorted(strategies):
            e = strategies[name]
            if not isinstance(e, Mapping):
                continue
            miss = e.get("mismatches")
            bad |= _positive(miss)
            total_states += int(e.get("states", 0) or 0)
            total_mismatches += int(miss or 0)
            rows.append([cell(s.name), cell(name), cell(_format_of(s, e, identities)), cell(e.get("states")),
                         cell(miss, _positive(miss)), cell(e.get("faulted_states")), cell(e.get("sources")),
                         cell(e.get("mismatches_per_field") or "none"), cell(e.get("states_per_s")),
                         cell(e.get("first_mismatch") or "-", bool(e.get("first_mismatch")))])
    verdict = (f'<p class="{BAD if bad or not rows else "ok"}">{total_states} states compared, '
               f"{total_mismatches} mismatches</p>")
    return Section("verify", "Verification", verdict + "\n" + _provenance(inputs.verify) + "\n" + table(header, rows),
                   bad or not rows)


#: HIL counters that must be zero
_HIL_ZERO = ("mismatches", "lost", "resets", "unexpected", "duplicates", "resent_states")


def hil_section(inputs: Inputs) -> Section:
    """Every counter of each HIL summary (nested ones dotted); a non-zero error counter is red."""
    if not inputs.hil:
        return Section("hil", "HIL", _absent("--hil FILE", "(mpcgen hil --json FILE)"))
    parts, bad = [], False
    for s in inputs.hil:
        text, flagged = _key_values(flatten(s.json or {}),
                                    lambda k, v: k.rsplit(".", 1)[-1] in _HIL_ZERO and _positive(v))
        bad |= flagged
        data = s.json or {}
        counts = ", ".join(f"{esc(data[k])} {k}" for k in ("states", "answered", "mismatches", "lost") if k in data)
        verdict = f'<p class="{BAD if flagged else "ok"}">{counts}</p>\n' if counts else ""
        parts.append(f"<h3>{esc(s.name)}</h3>\n{_from(s)}\n{verdict}{text}")
    return Section("hil", "HIL", "\n".join(parts), bad)


def _image_resolver(inputs: Inputs) -> Callable[[str, str], str]:
    def image(src: str, alt: str) -> str:
        found = inputs.report_images.get(src)
        uri = png_data_uri(found.data) if found is not None else None
        if found is None or uri is None:
            return f'<p class="absent">image not found beside the markdown: <code>{esc(src)}</code></p>'
        return figure(uri, alt, f"{found.name} sha256 {found.sha256}")

    return image


def quantisation_section(inputs: Inputs) -> Section:
    """The quantisation markdown rendered: its tables as HTML tables, its plots inline."""
    s = inputs.report
    if s is None:
        return Section("quantisation", "Quantisation", _absent("--report DIR_OR_MD", "(mpcgen report -o DIR)"))
    body = _from(s) + "\n" + markdown_html(s.text, _image_resolver(inputs))
    return Section("quantisation", "Quantisation", body)


def _by_strategy(strategies: Mapping[str, Any], skip: Sequence[str] = ()) -> str:
    """Metrics (rows, nested ones dotted) by strategy (columns)."""
    names = sorted(n for n in strategies if isinstance(strategies[n], Mapping))
    values = {n: dict(flatten(strategies[n], skip)) for n in names}
    keys = sorted({k for v in values.values() for k in v if not isinstance(v[k], list)})
    rows = [[cell(k), *(cell(values[n].get(k)) for n in names)] for k in keys]
    return table(("metric", *names), rows)


def _run_facts(data: Mapping[str, Any], skip: Sequence[str]) -> str:
    items = [(k, data[k]) for k in sorted(data) if k not in skip]
    return table(("key", "value"), [[cell(k), cell(v)] for k, v in items])


def bench_section(inputs: Inputs) -> Section:
    """Host ns per step and, from ``bench --emulated``, the Cortex-M7 instruction and cycle estimates."""
    s = inputs.bench
    if s is None:
        return Section("bench", "Cycle estimates", _absent("--bench FILE", "(mpcgen bench --json FILE)"))
    data = s.json or {}
    strategies = data.get("strategies")
    body = _from(s) + "\n" + _run_facts(data, ("strategies",))
    if isinstance(strategies, Mapping):
        body += "\n" + _by_strategy(strategies)
    return Section("bench", "Cycle estimates", body)


def simulate_section(inputs: Inputs) -> Section:
    """The run (scenario, plant, versions) and every metric by strategy; a fault count above zero is red."""
    s = inputs.simulate
    if s is None:
        return Section("simulate", "Simulation", _absent("--simulate FILE", "(mpcgen simulate --json FILE)"))
    data = s.json or {}
    strategies = data.get("strategies")
    body = _from(s) + "\n" + _run_facts(data, ("strategies",))
    bad = False
    if isinstance(strategies, Mapping):
        body += "\n" + _by_strategy(strategies, skip=("window", "plots"))
        bad = any(_positive(e.get("faults")) for e in strategies.values() if isinstance(e, Mapping))
    return Section("simulate", "Simulation", body, bad)


def plots_section(inputs: Inputs) -> Section:
    """Every PNG of the plots folder inline, each captioned with its name and sha256."""
    if not inputs.plots:
        return Section("plots", "Plots", _absent("--plots DIR", "(mpcgen simulate --plots DIR)"))
    figures = []
    for p in inputs.plots:
        uri = png_data_uri(p.data)
        if uri is None:
            figures.append(f'<p class="{BAD}">{esc(p.name)}: not a PNG</p>')
        else:
            figures.append(figure(uri, PurePosixPath(p.name).stem, f"{p.name} sha256 {p.sha256}"))
    body = (f'<p class="source">from the folder <code>{esc(inputs.plots_dir or "")}</code>, '
            f"{len(inputs.plots)} PNG files (each captioned with its sha256)</p>\n"
            + '<div class="figures">\n' + "\n".join(figures) + "\n</div>")
    return Section("plots", "Plots", body)


def manifest_section(inputs: Inputs) -> Section:
    """Every entry of each generate manifest (nested ones dotted)."""
    parts = []
    for s in inputs.manifest:
        text, _ = _key_values(flatten(s.json or {}), lambda k, v: False)
        parts.append(f"<h3>{esc(s.name)}</h3>\n{_from(s)}\n{text}")
    return Section("manifest", "Generated C", "\n".join(parts) or
                   _absent("--manifest FILE", "(the <prefix>_manifest.json mpcgen generate writes)"))
