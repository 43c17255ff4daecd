"""Shared helpers of the HIL tests: the example models with their tables (from tests/conftest.py)."""
from __future__ import annotations

from conftest import CASE_IDS, CASES, ROOT, SPMSM, example
from conftest import TTYPE as TLEVEL

__all__ = ["CASES", "CASE_IDS", "ROOT", "SPMSM", "TLEVEL", "example"]
