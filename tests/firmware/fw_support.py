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
from pathlib import Path

import pytest

from conftest import CASE_IDS, CASES, example  # noqa: F401  (re-exported for the firmware tests)

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = {"spmsm": ROOT / "examples" / "seed001_spmsm.toml", "tlevel": ROOT / "examples" / "seed000_tlevel.toml"}
SPMSM = EXAMPLES["spmsm"]
TTYPE = EXAMPLES["tlevel"]  # the example keeps its file name and C prefix "tlevel"


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
