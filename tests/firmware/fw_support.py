"""Shared helpers of the firmware tests: example models and tables per strategy, tool checks.

Not a conftest.py: tests/conftest.py is imported as ``conftest`` by other
test modules, and a second conftest.py here would shadow it.

Tests that need the Arm cross toolchain or QEMU fail, naming the Debian
package, when a tool is missing (never skip): the bootstrap installs
gcc-arm-none-eabi, libnewlib-arm-none-eabi and qemu-system-arm.
"""
from __future__ import annotations

import functools
from collections.abc import Callable
from pathlib import Path
from typing import Any

from conftest import CASE_IDS, CASES, example, require_tool  # noqa: F401  (re-exported for the firmware tests)

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = {"spmsm": ROOT / "examples" / "seed001_spmsm.toml", "tlevel": ROOT / "examples" / "seed000_tlevel.toml"}
SPMSM = EXAMPLES["spmsm"]
TTYPE = EXAMPLES["tlevel"]  # the example keeps its file name and C prefix "tlevel"


def _needs(*tools: tuple[str, str]) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Decorator: the test fails (conftest.require_tool) when one of ``tools`` (executable, Debian
    package) is missing."""
    def wrap(test: Callable[..., Any]) -> Callable[..., Any]:
        @functools.wraps(test)
        def run(*args: Any, **kwargs: Any) -> Any:
            for exe, package in tools:
                require_tool(exe, package)
            return test(*args, **kwargs)
        return run
    return wrap


_ARM = ("arm-none-eabi-gcc", "gcc-arm-none-eabi libnewlib-arm-none-eabi")
needs_arm = _needs(_ARM)
needs_qemu = _needs(_ARM, ("qemu-system-arm", "qemu-system-arm"))
