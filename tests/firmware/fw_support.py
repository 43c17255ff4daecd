"""Shared helpers of the firmware tests: SPMSM models and tables per strategy, tool skips.

Not a conftest.py: tests/conftest.py is imported as ``conftest`` by other
test modules, and a second conftest.py here would shadow it.

Tests that need the Arm cross toolchain or QEMU are skipped, with the reason,
only when those are not installed on a developer machine.  Under CI (CI set
in the environment; .ci/run installs the Debian packages gcc-arm-none-eabi,
libnewlib-arm-none-eabi, qemu-system-arm) they are never skipped: a missing
tool fails them.
"""
from __future__ import annotations

import os
import shutil
from functools import lru_cache
from pathlib import Path

import pytest

from codegen.config import load_config
from codegen.model import Model
from codegen.twolevel.derive import TwoLevelTables, derive_two_level
from codegen.twolevel.utilisation import published_tables

ROOT = Path(__file__).resolve().parents[2]
SPMSM = ROOT / "examples" / "seed001_spmsm.toml"
STRATEGIES = ("conventional", "s1", "s2", "s3")


@lru_cache(maxsize=None)
def spmsm(strategy: str) -> tuple[Model, TwoLevelTables]:
    """The SPMSM example with ``strategy``; s2/s3 use the published switch tables."""
    m = load_config(SPMSM, {"controller.strategy": strategy})
    s2, s3 = published_tables()
    return m, derive_two_level(m, {"s2": s2, "s3": s3}.get(strategy))


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


TLEVEL = ROOT / "examples" / "seed000_tlevel.toml"
THREE_LEVEL_STRATEGIES = ("mpdtc27", "mpdtc63")


@lru_cache(maxsize=None)
def tlevel(strategy: str):
    """The T-type three-level example with ``strategy`` and its ThreeLevelTables."""
    from codegen.threelevel.derive import derive_three_level

    m = load_config(TLEVEL, {"controller.strategy": strategy})
    return m, derive_three_level(m)
