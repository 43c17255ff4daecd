"""Shared helpers of the HIL tests: example models with their tables (cached per process)."""
from __future__ import annotations

from functools import cache
from pathlib import Path
from typing import Any

from codegen.config import load_config
from codegen.model import Model
from codegen.topology import topology_of

ROOT = Path(__file__).resolve().parents[2]
SPMSM = ROOT / "examples" / "seed001_spmsm.toml"
TLEVEL = ROOT / "examples" / "seed000_tlevel.toml"
#: (example, strategy) of every strategy of both topologies
CASES = [("spmsm", s) for s in ("conventional", "s1", "s2", "s3")] + [("tlevel", s) for s in ("mpdtc27", "mpdtc63")]
CASE_IDS = [f"{c}-{s}" for c, s in CASES]


@cache
def example(config: str, strategy: str) -> tuple[Model, Any]:
    """An example with ``strategy`` and its tables (two-level: the published switch tables)."""
    overrides: dict[str, object] = {"controller.strategy": strategy}
    if config == "spmsm":
        overrides["controller.tables"] = "published"
    m = load_config(SPMSM if config == "spmsm" else TLEVEL, overrides)
    return m, topology_of(m).derive(m)
