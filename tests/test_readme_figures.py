"""The README's measured figures are the ones scripts/readme_figures.py last measured, on this code.

The table between the README's markers must be exactly what the script renders from
``docs/figures.json``; that file must hold every figure the script defines, each measured (none
failed), on a commit of this history whose code (codegen, templates, firmware, hil, examples) is the
code checked out now: a change to the code without re-running the script fails here.
"""
from __future__ import annotations

import importlib.util
import json
import subprocess
import sys

import pytest

from conftest import ROOT

CODE = ("codegen", "templates", "firmware", "hil", "examples", "scripts/readme_figures.py")


def _script():
    spec = importlib.util.spec_from_file_location("readme_figures", ROOT / "scripts" / "readme_figures.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # its dataclasses look their module up there
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def store() -> dict:
    return json.loads((ROOT / "docs" / "figures.json").read_text())


def test_readme_block_is_rendered_from_the_store(store):
    fig = _script()
    text = (ROOT / "README.md").read_text()
    start, end = text.index(fig.BEGIN), text.index(fig.END) + len(fig.END)
    assert text[start:end] == fig.render_block(store)
    assert text.count(fig.BEGIN) == 1 and text.count(fig.END) == 1


def test_every_figure_measured(store):
    fig = _script()
    got = {f["key"]: f for f in store["figures"]}
    assert sorted(got) == sorted(f.key for f in fig.FIGURES)
    failed = {k: f["error"] for k, f in got.items() if not f["ok"]}
    assert not failed, failed
    for f in fig.FIGURES:  # the command shown is the one the script runs
        assert got[f.key]["command"] == f.command
    assert store["machine"]["cpu"] and store["machine"]["cores"]


def test_measured_on_this_code(store):
    head = store["commit"]["head"]
    assert not store["commit"]["changed_files"], store["commit"]["changed_files"]
    anc = subprocess.run(["git", "merge-base", "--is-ancestor", head, "HEAD"], cwd=ROOT)
    if anc.returncode == 128:  # not a git checkout (an installed copy): nothing to compare against
        pytest.fail("not a git checkout: the figures cannot be tied to the code")
    assert anc.returncode == 0, f"figures measured on {head}, not an ancestor of HEAD"
    changed = subprocess.run(["git", "diff", "--name-only", head, "--", *CODE], cwd=ROOT, capture_output=True,
                             text=True, check=True).stdout.split()
    assert not changed, (f"code changed since the figures were measured on {head[:12]}: {changed[:8]}; "
                         "run .venv/bin/python scripts/readme_figures.py")
