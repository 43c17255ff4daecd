"""Shared fixtures: example configs, tables per strategy, host builds."""
from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from codegen.config import load_config
from codegen.model import Model

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
SPMSM = EXAMPLES / "seed001_spmsm.toml"
IPMSM = EXAMPLES / "seed001_ipmsm.toml"
TWO_LEVEL = ("conventional", "s1", "s2", "s3")


def model_for(path: Path, **overrides: object) -> Model:
    """Load an example with ``controller.<key>`` overrides."""
    return load_config(path, {f"controller.{k}": v for k, v in overrides.items()})


def require_tool(name: str, package: str) -> str:
    """Path of a required tool; fail (not skip) when it is missing: CI installs it."""
    path = shutil.which(name)
    if path is None:
        pytest.fail(f"{name} not found: install the Debian package {package} (scripts/bootstrap.sh does)")
    return path
