"""Architecture rules, checked on the syntax tree (comments and docstrings do not count).

1. No module of codegen/ outside the plugins (codegen/topologies/) and no module
   of hil/ names a topology, a strategy or a plugin package: no string naming a
   topology ("two-level", "t-type"), a topology package or a strategy
   ("conventional", "mpdtc63", ...), no ``isinstance`` test on a tables class,
   no import of ``codegen.topologies``, no identifier naming a topology
   (TwoLevelTables, ThreeLevelTables, twolevel, ttype, ...).  The one exception
   is the registry ``TOPOLOGY_PACKAGES`` in codegen/registry.py, which maps each
   ``inverter.topology`` value to its plugin package.  The stages
   (codegen/stages/*.py, codegen/cli.py, codegen/topology.py) name no number
   format either.
2. No topology package imports another (nor names another's modules in a string).

The checker is tested on small snippets too, so that a rule that silently
matches nothing fails.
"""
from __future__ import annotations

import ast
import re
from dataclasses import dataclass
from pathlib import Path

import pytest

from codegen.config import strategies_of
from codegen.numfmt import FORMATS
from codegen.registry import topology_names

from conftest import ROOT

CODEGEN = ROOT / "codegen"
STAGE_FILES = sorted((CODEGEN / "stages").glob("*.py")) + [CODEGEN / "cli.py", CODEGEN / "topology.py"]
#: every module that must not name a topology or a strategy: codegen/ outside the plugins, and hil/
NAMING_FILES = sorted(p for p in CODEGEN.rglob("*.py") if "topologies" not in p.relative_to(CODEGEN).parts) + \
    sorted((ROOT / "hil").rglob("*.py"))
TOPOLOGY_PACKAGES = sorted(p.parent.name for p in (CODEGEN / "topologies").glob("*/__init__.py"))

#: string fragments that name a topology or a topology package
TOPOLOGY_STRINGS = ("two-level", "t-type", "codegen.topologies")
#: identifier word sequences that name a topology (after splitting at "_" and camelCase)
TOPOLOGY_WORDS = (("two", "level"), ("twolevel",), ("three", "level"), ("threelevel",), ("t", "type"),
                  ("ttype",), ("tlevel",), ("3l",), ("2l",))
#: strategies by name (every topology's)
STRATEGY_NAMES = tuple(s for t in topology_names() for s in strategies_of(t))
#: number formats by name: a stage asks the format (``quantised``, the report's roles), never its name
FORMAT_NAMES = tuple(FORMATS)
#: the registry: the one assignment allowed to name topologies
REGISTRY = (CODEGEN / "registry.py", "TOPOLOGY_PACKAGES")


@dataclass(frozen=True)
class Finding:
    """One rule violation: where, which rule, what."""

    path: str
    line: int
    rule: str
    text: str

    def __str__(self) -> str:
        return f"{self.path}:{self.line}: {self.rule}: {self.text}"


def _words(identifier: str) -> list[str]:
    """``TwoLevelTables`` -> [two, level, tables]; ``t_type`` -> [t, type]; ``sim3l`` -> [sim, 3l]."""
    spaced = re.sub(r"([a-z0-9])([A-Z])", r"\1_\2", identifier)
    spaced = re.sub(r"([A-Z])([A-Z][a-z])", r"\1_\2", spaced)
    spaced = re.sub(r"([a-z])([0-9])", r"\1_\2", spaced)
    return [w for w in spaced.lower().split("_") if w]


def names_topology(identifier: str) -> bool:
    """Whether ``identifier`` contains a word sequence naming a topology."""
    words = _words(identifier)
    return any(tuple(words[i:i + len(seq)]) == seq for seq in TOPOLOGY_WORDS for i in range(len(words)))


def _docstrings(tree: ast.AST) -> set[int]:
    """ids of the docstring constants of the module, classes and functions."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) and isinstance(first.value.value, str):
                out.add(id(first.value))
    return out


def _registry_nodes(tree: ast.AST, name: str) -> set[int]:
    """ids of every node inside the assignment of module-level ``name``."""
    out: set[int] = set()
    for node in getattr(tree, "body", []):
        targets = node.targets if isinstance(node, ast.Assign) else [node.target] if isinstance(node, ast.AnnAssign) else []
        if any(isinstance(t, ast.Name) and t.id == name for t in targets):
            out |= {id(n) for n in ast.walk(node)}
    return out


def _identifiers(node: ast.AST) -> list[str]:
    """The identifiers a node introduces or uses."""
    if isinstance(node, ast.Name):
        return [node.id]
    if isinstance(node, ast.Attribute):
        return [node.attr]
    if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
        return [node.name]
    if isinstance(node, ast.arg):
        return [node.arg]
    if isinstance(node, ast.keyword) and node.arg:
        return [node.arg]
    if isinstance(node, ast.alias):
        return [node.name, *([node.asname] if node.asname else [])]
    if isinstance(node, ast.ImportFrom) and node.module:
        return [node.module]
    return []


def _imported_modules(node: ast.AST, module: str) -> list[str]:
    """Absolute names of the modules an import statement in ``module`` imports."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    if isinstance(node, ast.ImportFrom):
        base = node.module or ""
        if node.level:
            parent = module.split(".")[: -node.level]
            base = ".".join([*parent, base] if base else parent)
        return [base, *(f"{base}.{a.name}" for a in node.names)]
    return []


def _is_tables_class(node: ast.AST) -> bool:
    """Whether an isinstance type argument names a tables class (``...Tables``)."""
    return any(re.search(r"Tables$", name) for n in ast.walk(node) for name in _identifiers(n))


def stage_findings(source: str, path: str, module: str, registry: str | None = None,
                   formats: bool = True) -> list[Finding]:
    """Topology branches in the stage module ``module`` with text ``source`` (``formats``: number-format
    names count too)."""
    tree = ast.parse(source)
    skip = _docstrings(tree) | (_registry_nodes(tree, registry) if registry else set())
    found: list[Finding] = []
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        line = getattr(node, "lineno", 0)
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            low = node.value.lower()
            for frag in TOPOLOGY_STRINGS:
                if frag in low:
                    found.append(Finding(path, line, "topology string", repr(node.value)))
            if formats and node.value in FORMAT_NAMES:
                found.append(Finding(path, line, "number-format name", repr(node.value)))
            if node.value in STRATEGY_NAMES:
                found.append(Finding(path, line, "strategy name", repr(node.value)))
        for mod in _imported_modules(node, module):
            if mod == "codegen.topologies" or mod.startswith("codegen.topologies."):
                found.append(Finding(path, line, "topology import", mod))
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "isinstance"
                and len(node.args) == 2 and _is_tables_class(node.args[1])):
            found.append(Finding(path, line, "isinstance on a tables class", ast.unparse(node)))
        for name in _identifiers(node):
            if names_topology(name):
                found.append(Finding(path, line, "topology name", name))
    return found


def cross_topology_findings(source: str, path: str, module: str, package: str, others: list[str]) -> list[Finding]:
    """Imports of (or module strings naming) another topology package in ``module`` of ``package``."""
    tree = ast.parse(source)
    found: list[Finding] = []
    other_mods = [f"codegen.topologies.{o}" for o in others]
    for node in ast.walk(tree):
        line = getattr(node, "lineno", 0)
        names = _imported_modules(node, module)
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            names.append(node.value)
        for name in names:
            if any(name == o or name.startswith(o + ".") for o in other_mods):
                found.append(Finding(path, line, f"{package} imports another topology", name))
    return found


def _module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


# --- the rules on the code -------------------------------------------------

def test_the_stage_list_is_not_empty():
    assert len(STAGE_FILES) >= 8 and all(p.is_file() for p in STAGE_FILES)
    assert {"twolevel", "ttype"} <= set(TOPOLOGY_PACKAGES)


@pytest.mark.parametrize("path", STAGE_FILES, ids=lambda p: str(p.relative_to(CODEGEN)))
def test_stage_has_no_topology_branch(path: Path):
    found = stage_findings(path.read_text(), str(path.relative_to(ROOT)), _module_name(path))
    assert not found, "\n".join(map(str, found))


def test_the_naming_list_covers_codegen_and_hil():
    names = {str(p.relative_to(ROOT)) for p in NAMING_FILES}
    assert {"codegen/config.py", "codegen/model.py", "codegen/operating.py", "codegen/registry.py",
            "hil/closedloop.py", "hil/onboard.py", "hil/codecgen.py", "hil/cli.py"} <= names
    assert not any(n.startswith("codegen/topologies/") for n in names)


@pytest.mark.parametrize("path", NAMING_FILES, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_module_outside_the_plugins_names_a_topology(path: Path):
    registry = REGISTRY[1] if path == REGISTRY[0] else None
    found = stage_findings(path.read_text(), str(path.relative_to(ROOT)), _module_name(path), registry,
                           formats=False)
    assert not found, "\n".join(map(str, found))


def test_the_registry_names_every_topology_package():
    """The exemption is for the registry only: it must exist and map to plugin packages."""
    tree = ast.parse(REGISTRY[0].read_text())
    nodes = _registry_nodes(tree, REGISTRY[1])
    values = [n.value for n in ast.walk(tree) if id(n) in nodes and isinstance(n, ast.Constant)]
    for package in TOPOLOGY_PACKAGES:
        assert f"codegen.topologies.{package}" in values


@pytest.mark.parametrize("package", TOPOLOGY_PACKAGES)
def test_no_topology_package_imports_another(package: str):
    others = [p for p in TOPOLOGY_PACKAGES if p != package]
    found: list[Finding] = []
    for path in sorted((CODEGEN / "topologies" / package).rglob("*.py")):
        found += cross_topology_findings(path.read_text(), str(path.relative_to(ROOT)), _module_name(path),
                                         package, others)
    assert not found, "\n".join(map(str, found))


# --- the checker itself ----------------------------------------------------

STAGE = "codegen.stages.example"


@pytest.mark.parametrize("snippet, rule", [
    ('def run(model):\n    if model.inverter.topology == "t-type":\n        return 1\n', "topology string"),
    ('def run(model):\n    return {"two-level": 1}[model.inverter.topology]\n', "topology string"),
    ('def run(model):\n    return model.controller.number_format == "fixed"\n', "number-format name"),
    ('import importlib\nm = importlib.import_module("codegen.topologies.ttype.plugin")\n', "topology string"),
    ("from codegen.topologies.twolevel import reference\n", "topology import"),
    ("import codegen.topologies.ttype.derive as d\n", "topology import"),
    ("from ..topologies import ttype\n", "topology import"),
    ("def run(t, Tables):\n    return isinstance(t, Tables)\n", "isinstance on a tables class"),
    ("def run(t, m):\n    return isinstance(t, (m.FooTables, int))\n", "isinstance on a tables class"),
    ("def run(t):\n    return TwoLevelTables(t)\n", "topology name"),
    ("def run(t):\n    return t.ThreeLevelTables\n", "topology name"),
    ("def derive_three_level(m):\n    return m\n", "topology name"),
    ("def run(m, ttype=None):\n    return ttype\n", "topology name"),
    ("def run(m):\n    return m.sim3l\n", "topology name"),
    ("def run(twolevel):\n    return twolevel\n", "topology name"),
    ('def run(model):\n    return model.controller.strategy == "mpdtc63"\n', "strategy name"),
    ('def run(model):\n    return model.controller.strategy in ("s2", "s3")\n', "strategy name"),
])
def test_checker_finds_a_branch(snippet: str, rule: str):
    found = stage_findings(snippet, "example.py", STAGE)
    assert rule in {f.rule for f in found}, found


def test_checker_ignores_comments_docstrings_and_lookalikes():
    snippet = ('"""Runs the two-level and the t-type step alike."""\n'
               "# if model.inverter.topology == 't-type': a comment is not a branch\n"
               "def run(model, output_type, three, level, tables):\n"
               '    """Never asks whether the topology is two-level."""\n'
               "    return isinstance(tables, dict) and output_type and three and level\n")
    assert stage_findings(snippet, "example.py", STAGE) == []


def test_checker_exempts_only_the_registry():
    snippet = ('TOPOLOGIES = {"two-level": "codegen.topologies.twolevel.plugin"}\n'
               'OTHER = {"t-type": "codegen.topologies.ttype.plugin"}\n')
    found = stage_findings(snippet, "topology.py", "codegen.topology", registry="TOPOLOGIES")
    assert found and all(f.line == 2 for f in found)


@pytest.mark.parametrize("snippet, hit", [
    ("from codegen.topologies.ttype.derive import guard_limits\n", True),
    ("from codegen.topologies import ttype\n", True),
    ("from ..ttype import vectors\n", True),
    ('import importlib\nimportlib.import_module("codegen.topologies.ttype.sim")\n', True),
    ("from codegen.topologies.twolevel.derive import guard_limits\nfrom codegen.teststates import Limit\n", False),
    ("from . import derive\n", False),
])
def test_cross_topology_checker(snippet: str, hit: bool):
    found = cross_topology_findings(snippet, "x.py", "codegen.topologies.twolevel.x", "twolevel", ["ttype"])
    assert bool(found) == hit, found


def test_targets_profiles_and_boards_are_one_enumeration():
    """Every config target has exactly one render profile, every firmware board renders one of them, and
    the emulated board is one of the boards (each name written once, in its own record)."""
    from codegen.model import TARGETS
    from codegen.render import PROFILES
    from codegen.stages.firmware import BOARDS, EMULATED_BOARD
    from hil.boards import QEMU_BOARD

    assert set(PROFILES) == set(TARGETS)
    assert all(b.profile in PROFILES and b.name == name for name, b in BOARDS.items())
    assert EMULATED_BOARD in BOARDS and QEMU_BOARD == EMULATED_BOARD
