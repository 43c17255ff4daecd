"""The topology interface: what every inverter topology provides, and the registry.

A topology (two-level, T-type) is a plugin package under
``codegen/topologies/`` whose ``plugin`` module implements :class:`Topology`:
the module itself is the plugin (module-level constants and functions, checked
against the protocol by mypy).  The stages (generate, verify, simulate,
bench, tables, firmware, hil) call only this interface and contain no
topology branch: they take the plugin of the config's
``inverter.topology`` from :func:`topology_of`.  A command a topology cannot
serve raises :class:`codegen.errors.Unsupported` (exit code 2), never a
fallback to another topology's code.

Plugins are imported by name (``importlib``), so this module and the stages
depend on no topology package.
"""
from __future__ import annotations

import importlib
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from codegen.hostbuild import HostLib
from codegen.model import Model
from codegen.records import Record

__all__ = ["Topology", "Trajectory", "record_trajectory", "topology_of", "topology", "TOPOLOGIES"]

Log = Callable[[str], None]
Progress = Callable[[float], None]


@dataclass(frozen=True)
class Trajectory:
    """Controller inputs recorded from a closed-loop run, with its wall time and length."""

    states: np.ndarray
    wall_s: float
    periods: int


class Topology(Protocol):
    """One inverter topology: its strategies, tables, records, reference, plant, scenarios."""

    #: ``inverter.topology`` value
    name: str
    #: what the generated step is, for reports ("two-level MPTC")
    title: str
    #: every strategy, in report order; the first is the baseline others are compared to
    strategies: tuple[str, ...]
    #: the step's input record (every layout derives from it)
    input_record: Record
    #: dotted name of the Python reference step (generated comments)
    reference: str
    #: what the recorded bench trajectory is
    trajectory_doc: str

    def output_record(self, model: Model) -> Record:
        """The step's output record for ``model``'s strategy (every layout derives from it)."""
        ...

    def derive(self, model: Model, progress: Progress | None = None) -> Any:
        """The step's derived tables for ``model.controller.strategy`` (derived once)."""
        ...

    def render(self, model: Model, tables: Any, target: str) -> dict[str, str]:
        """File name -> text of the generated C for ``target``."""
        ...

    def report(self, model: Model, tables: Any, target: str) -> str:
        """Markdown report of the generated controller (constants, tables, guard, assumptions)."""
        ...

    def step_batch(self, tables: Any, states: np.ndarray) -> np.ndarray:
        """The Python reference over a batch of input records."""
        ...

    def host_library(self, model: Model, tables: Any, with_sim: bool = False) -> HostLib:
        """The generated C built for the host (+ the closed-loop simulator)."""
        ...

    def closed_loop_states(self, model: Model, lib: HostLib) -> np.ndarray:
        """Controller inputs recorded from the variant's own closed-loop scenario run(s)."""
        ...

    def adversarial_states(self, model: Model, tables: Any, n: int) -> np.ndarray:
        """About ``n`` adversarial states (borders, ties, guard limits, non-finite values)."""
        ...

    def random_states(self, model: Model, tables: Any, n: int, seed: int) -> np.ndarray:
        """``n`` random states over (and a little beyond) the operating range, in the step's format
        (``tables.nf``)."""
        ...

    def selftest_states(self, model: Model, tables: Any, n: int, seed: int) -> np.ndarray:
        """``n`` deterministic firmware self-test states, guard cases first."""
        ...

    def trajectory(self, model: Model, progress: Progress | None = None) -> Trajectory:
        """The baseline's recorded closed-loop run every strategy is benchmarked on."""
        ...

    def simulate(self, model: Model, strategies: list[str], plots: Path | None, log: Log,
                 traces: Path | None = None) -> dict:
        """The config's scenario for each strategy: JSON-ready metrics plus a printable ``_table`` and
        ``_warnings`` (stderr lines); ``traces``: write the time series there (npz, or CSV)."""
        ...

    def sweep_eps(self, model: Model, eps_list: list[float], log: Log) -> dict:
        """Torque-threshold sweep (``simulate --sweep-eps``), or Unsupported."""
        ...

    def paper_table(self, model: Model, data: dict) -> dict:
        """The seed's published figures next to ours for ``data`` (a :meth:`simulate` or
        :meth:`sweep_eps` result), with the ratios the seed draws (``simulate --paper``): JSON-ready,
        ``available`` and a printable ``_table``; when the topology has no published figures for this
        config or scenario, ``available`` is false and ``_table`` one line saying so."""
        ...

    def tables_text(self, model: Model, source: str | None, log: Log) -> str:
        """The derived switch tables and vector sets as text (``mpcgen tables``); ``source`` is the
        ``--utilisation`` option (None: the topology's default)."""
        ...

    def tables_rows(self, model: Model, source: str | None, log: Log) -> list[dict[str, object]]:
        """The same tables as flat rows, each with a ``table`` column (``tables --json/--csv``)."""
        ...

    def essential_ops(self, model: Model, tables: Any) -> dict[str, dict[str, int]]:
        """The operations the step's algorithm cannot do without, for ``mpcgen bench``'s cycle bounds:
        ``per_step``, ``per_candidate`` and any further units (``op_multiplicities`` says how often
        each runs), optionally ``first_candidate`` (the first evaluated candidate's, in place of
        ``per_candidate``), each ``{"fp", "cmp", "sqrt", "div", "load", "store"}`` counts (``fp``: FP
        operations that write a register; ``cmp``: compares and branches)."""
        ...

    def op_multiplicities(self, model: Model, tables: Any, states: np.ndarray,
                          expected: np.ndarray) -> dict[str, np.ndarray]:
        """Per state of ``states`` (input records in the step's format; ``expected`` their output
        records), how many times each unit of ``essential_ops`` other than ``per_step`` and
        ``first_candidate`` runs; ``per_candidate`` is the evaluated candidates."""
        ...

    def export_tables(self, model: Model, path: Path, log: Log) -> str:
        """Run the training and write the trained tables with their provenance (``tables --derive``),
        or Unsupported; returns a one-paragraph summary."""
        ...


def record_trajectory(base: Model, lib: HostLib, run: Callable[..., Any],
                      inputs: Callable[[Any, Model, Any], np.ndarray], progress: Progress | None = None) -> Trajectory:
    """Run ``base``'s scenario through ``lib`` (``run(ffi, lib, model, progress=...)``) and keep the
    controller inputs it fed the step (``inputs(trace, model, number_format)``), with the run's wall time."""
    t0 = time.perf_counter()
    trace = run(lib.ffi, lib.lib, base, progress=progress)
    wall = time.perf_counter() - t0
    return Trajectory(inputs(trace, base, lib.records.input.nf), wall, trace.n)


#: ``inverter.topology`` value -> the plugin module
TOPOLOGIES: dict[str, str] = {
    "two-level": "codegen.topologies.twolevel.plugin",
    "t-type": "codegen.topologies.ttype.plugin",
}


def topology(name: str) -> Topology:
    """The plugin of topology ``name``."""
    try:
        module = TOPOLOGIES[name]
    except KeyError:
        raise ValueError(f"unknown topology {name!r}; allowed: {', '.join(TOPOLOGIES)}") from None
    plugin: Topology = importlib.import_module(module)  # type: ignore[assignment]
    return plugin


def topology_of(model: Model) -> Topology:
    """The plugin of ``model.inverter.topology``."""
    return topology(model.inverter.topology)
