"""Shared helpers of the firmware tests: example models and tables per strategy, tool skips.

Not a conftest.py: tests/conftest.py is imported as ``conftest`` by other
test modules, and a second conftest.py here would shadow it.

Tests that need the Arm cross toolchain or QEMU are skipped, with the reason,
only when those are not installed on a developer machine.  Under CI (CI set
in the environment; the bootstrap installs the Debian packages
gcc-arm-none-eabi, libnewlib-arm-none-eabi, qemu-system-arm) they are never
skipped: a missing tool fails them.
"""
from __future__ import annotations

import os
import shutil
from functools import cache
from pathlib import Path
from typing import Any

import pytest

from codegen.config import load_config
from codegen.model import Model
from codegen.topology import topology_of

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = {"spmsm": ROOT / "examples" / "seed001_spmsm.toml", "tlevel": ROOT / "examples" / "seed000_tlevel.toml"}
SPMSM = EXAMPLES["spmsm"]
TTYPE = EXAMPLES["tlevel"]  # the example keeps its file name and C prefix "tlevel"
#: (example, strategy) of every strategy of both topologies
CASES = [("spmsm", s) for s in ("conventional", "s1", "s2", "s3")] + [("tlevel", s) for s in ("mpdtc27", "mpdtc63")]
CASE_IDS = [f"{c}-{s}" for c, s in CASES]


@cache
def example(config: str, strategy: str) -> tuple[Model, Any]:
    """An example config with ``strategy`` and its derived tables (two-level: published switch tables)."""
    overrides: dict[str, object] = {"controller.strategy": strategy}
    if config == "spmsm":
        overrides["controller.tables"] = "published"  # no training run in the firmware tests
    m = load_config(EXAMPLES[config], overrides)
    return m, topology_of(m).derive(m)


def _missing(*exes: str) -> list[str]:
    if os.environ.get("CI"):
        return []  # CI must have them: run, and fail loudly if they are absent
    return [e for e in exes if shutil.which(e) is None]


needs_arm = pytest.mark.skipif(bool(_missing("arm-none-eabi-gcc")),
                               reason="arm-none-eabi-gcc not installed (apt-get install gcc-arm-none-eabi "
                                      "libnewlib-arm-none-eabi)")
needs_qemu = pytest.mark.skipif(bool(_missing("arm-none-eabi-gcc", "qemu-system-arm")),
                                reason="arm-none-eabi-gcc or qemu-system-arm not installed "
                                       "(apt-get install gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm)")
