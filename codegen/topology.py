"""The topology interface: what every inverter topology provides, as facets.

A topology (two-level, T-type) is a plugin package under
``codegen/topologies/`` whose ``plugin`` module implements :class:`Topology`,
the union of five small facets (:class:`Codegen`, :class:`Reference`,
:class:`Training`, :class:`Simulation`, :class:`Reporting`), each generic over
the topology's derived-tables type: the module itself is the plugin
(module-level constants and functions, checked against the protocol by
mypy).  Its ``section`` module is the sixth facet, its part of the
configuration (:class:`codegen.config.TopologySection`).  The stages (generate, verify, simulate,
bench, tables, firmware, hil) call only this interface and contain no
topology branch: they take the plugin of the config's
``inverter.topology`` from :func:`topology_of`.  A command a topology cannot
serve raises :class:`codegen.errors.Unsupported` (exit code 2), never a
fallback to another topology's code.

Plugins are imported by name through :mod:`codegen.registry`, so this module
and the stages depend on no topology package.
"""
from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol, TypeVar

import numpy as np

from codegen.hostbuild import HostLib
from codegen.model import Model
from codegen.records import Record
from codegen.registry import topology_module

__all__ = ["Topology", "Codegen", "Reference", "Training", "Simulation", "Reporting", "Trajectory",
           "record_trajectory", "topology_of", "topology"]

Log = Callable[[str], None]
Progress = Callable[[float], None]


@dataclass(frozen=True)
class Trajectory:
    """Controller inputs recorded from a closed-loop run, with its wall time and length."""

    states: np.ndarray
    wall_s: float
    periods: int


#: a topology's derived tables (each topology its own frozen type: ``TwoLevelTables``, ...)
T = TypeVar("T")
#: the same, in facets that only take the tables
T_in = TypeVar("T_in", contravariant=True)


class Codegen(Protocol[T]):
    """Facet 1, code generation: strategies, records, the derived tables and the C rendered from them
    (``generate``, ``firmware``, the host build of ``verify``/``bench``)."""

    #: ``inverter.topology`` value
    name: str
    #: what the generated step is, for reports ("two-level MPTC")
    title: str
    #: every strategy, in report order; the first is the baseline others are compared to
    strategies: tuple[str, ...]
    #: the step's input record (every layout derives from it)
    input_record: Record

    def output_record(self, model: Model) -> Record:
        """The step's output record for ``model``'s strategy (every layout derives from it)."""
        ...

    def derive(self, model: Model) -> T:
        """The step's derived tables for ``model.controller.strategy`` (derived once): a pure function of
        the model (no compiler, no file, no run); a strategy that needs trained tables the model does not
        carry raises :class:`codegen.errors.ConfigError` naming the command that makes them."""
        ...

    def render(self, model: Model, tables: T, target: str) -> dict[str, str]:
        """File name -> text of the generated C for ``target``: the step (``<prefix>_mpc.c/.h``,
        ``mpc_binding.h``) and, for a target that drives a power stage (:func:`codegen.pwm.modulated_targets`),
        the modulator that turns the step's decision into timer compares (``<prefix>_modulator.c/.h``) and
        an example interrupt routine (``<prefix>_isr_example.c``), docs/modulator.md.  Every file is in the
        C hash (``codegen.manifest``) and in a firmware project's ``gen/``."""
        ...

    def report(self, model: Model, tables: T, target: str) -> str:
        """Markdown report of the generated controller (constants, tables, guard, assumptions)."""
        ...

    def host_library(self, model: Model, tables: T, with_sim: bool = False) -> HostLib:
        """The generated C built for the host (+ the closed-loop simulator)."""
        ...


class Reference(Protocol[T_in]):
    """Facet 2, the independent reference and the states it is checked on (``verify``, ``bench``, the
    firmware self-test, the serial HIL)."""

    #: dotted name of the Python reference step (generated comments)
    reference: str

    def step_batch(self, tables: T_in, states: np.ndarray) -> np.ndarray:
        """The Python reference over a batch of input records."""
        ...

    def closed_loop_states(self, model: Model, lib: HostLib) -> np.ndarray:
        """Controller inputs recorded from the variant's own closed-loop scenario run(s)."""
        ...

    def adversarial_states(self, model: Model, tables: T_in, n: int) -> np.ndarray:
        """About ``n`` adversarial states (borders, ties, guard limits, non-finite values)."""
        ...

    def random_states(self, model: Model, tables: T_in, n: int, seed: int) -> np.ndarray:
        """``n`` random states over (and a little beyond) the operating range, in the step's format
        (``tables.nf``)."""
        ...

    def selftest_states(self, model: Model, tables: T_in, n: int, seed: int) -> np.ndarray:
        """``n`` deterministic firmware self-test states, guard cases first."""
        ...


class Training(Protocol):
    """Facet 3, tables trained on the config's own scenario (``tables --derive`` and the training stage
    of the commands that run the controller on the host)."""

    def needs_training(self, model: Model) -> bool:
        """True when ``model``'s strategy needs trained tables the model does not carry."""
        ...

    def train(self, model: Model, log: Log) -> Model:
        """``model`` with the tables trained on its scenario read in (cached training run), exactly as
        loading a config that names the artefact reads it."""
        ...

    def export_tables(self, model: Model, path: Path, log: Log) -> str:
        """Run the training and write the trained tables with their provenance (``tables --derive``),
        or Unsupported; returns a one-paragraph summary."""
        ...


class Simulation(Protocol):
    """Facet 4, the plant and the closed loop (``simulate``, ``sweep``, ``bench``'s trajectory, the
    serial HIL's closed-loop and on-board modes)."""

    #: what the recorded bench trajectory is
    trajectory_doc: str
    #: the trace field (and output record field) holding the controller's decision, one name in
    #: Python, C, JSON and on the serial wire
    decision_field: str

    def trajectory(self, model: Model, progress: Progress | None = None) -> Trajectory:
        """The baseline's recorded closed-loop run every strategy is benchmarked on."""
        ...

    def simulate(self, model: Model, strategies: list[str], plots: Path | None, log: Log,
                 traces: Path | None = None) -> dict[str, Any]:
        """The config's scenario for each strategy: JSON-ready metrics plus a printable ``_table`` and
        ``_warnings`` (stderr lines); ``traces``: write the time series there (npz, or CSV)."""
        ...

    def sweep_eps(self, model: Model, eps_list: list[float], log: Log) -> dict[str, Any]:
        """Torque-threshold sweep (``simulate --sweep-eps``), or Unsupported."""
        ...

    def closed_loop_trace(self, model: Model, lib: HostLib) -> Any:
        """The trace of ``model``'s scenario through ``lib`` (built with the simulator): ``mpcgen
        simulate``'s closed-loop run."""
        ...

    def period_stepper(self, lib: HostLib, model: Model, *, substep_max_s: float | None = None,
                       initial_speed_rpm: float = 0.0) -> Any:
        """The same closed loop one period at a time, each decision given from outside (a
        :class:`codegen.simulator.driver.PeriodStepper`): RK4 sub-steps of at most ``substep_max_s``
        (None: the simulator's 1 us), the plant starting at ``initial_speed_rpm``."""
        ...

    def trace_from(self, arrays: dict[str, np.ndarray], model: Model) -> Any:
        """The trace of the arrays a period stepper's ``result()`` gives."""
        ...

    def trace_metrics(self, trace: Any, model: Model) -> dict[str, Any]:
        """The metrics ``mpcgen simulate`` reports for a trace of this topology."""
        ...

    def firmware_plant(self, model: Model) -> dict[str, str]:
        """File name -> text of the C of the on-board plant (the serial HIL's mode onboard): the plant
        core compiled in float32 and the topology's part of firmware/runtime/onboard.h's loop (its
        ``onb_topo_*`` functions); the firmware build compiles the .c files and finds the headers on
        its include path."""
        ...


class Reporting(Protocol[T_in]):
    """Facet 5, what the topology prints and counts: paper tables, switch tables, cycle-bound
    operations (``tables``, ``simulate --paper``, ``bench``)."""

    def paper_table(self, model: Model, data: dict[str, Any]) -> dict[str, Any]:
        """The seed's published figures next to ours for ``data`` (a :meth:`Simulation.simulate` or
        :meth:`Simulation.sweep_eps` result), with the ratios the seed draws (``simulate --paper``):
        JSON-ready, ``available`` and a printable ``_table``; when the topology has no published
        figures for this config or scenario, ``available`` is false and ``_table`` one line saying so."""
        ...

    def tables_text(self, model: Model, source: str | None, log: Log) -> str:
        """The derived switch tables and vector sets as text (``mpcgen tables``); ``source`` is the
        ``--utilisation`` option (None: the topology's default)."""
        ...

    def tables_rows(self, model: Model, source: str | None, log: Log) -> list[dict[str, object]]:
        """The same tables as flat rows, each with a ``table`` column (``tables --json/--csv``)."""
        ...

    def essential_ops(self, model: Model, tables: T_in) -> dict[str, dict[str, int]]:
        """The operations the step's algorithm cannot do without, for ``mpcgen bench``'s cycle bounds:
        ``per_step``, ``per_candidate`` and any further units (``op_multiplicities`` says how often
        each runs), optionally ``first_candidate`` (the first evaluated candidate's, in place of
        ``per_candidate``), each ``{"add", "mul", "cmp", "sqrt", "div", "load", "store"}`` counts
        (``mul``: products; ``add``: the other operations that write a value; ``cmp``: compares and
        branches): operations of the algorithm, which the step's number format turns into instructions
        (``NumberFormat.op_costs``)."""
        ...

    def op_multiplicities(self, model: Model, tables: T_in, states: np.ndarray,
                          expected: np.ndarray) -> dict[str, np.ndarray]:
        """Per state of ``states`` (input records in the step's format; ``expected`` their output
        records), how many times each unit of ``essential_ops`` other than ``per_step`` and
        ``first_candidate`` runs; ``per_candidate`` is the evaluated candidates."""
        ...


class Topology(Codegen[T], Reference[T], Training, Simulation, Reporting[T], Protocol[T]):
    """One inverter topology: every facet.  A plugin module implements all of them (mypy checks it in
    the module's ``TYPE_CHECKING`` block); a stage depends on the facets it uses.  The sixth facet, the
    topology's part of the configuration, is read while a config is loaded: ``<package>.section``
    (:class:`codegen.config.TopologySection`)."""


def record_trajectory(base: Model, lib: HostLib, run: Callable[..., Any],
                      inputs: Callable[[Any, Model, Any], np.ndarray], progress: Progress | None = None) -> Trajectory:
    """Run ``base``'s scenario through ``lib`` (``run(ffi, lib, model, progress=...)``) and keep the
    controller inputs it fed the step (``inputs(trace, model, number_format)``), with the run's wall time."""
    t0 = time.perf_counter()
    trace = run(lib.ffi, lib.lib, base, progress=progress)
    wall = time.perf_counter() - t0
    return Trajectory(inputs(trace, base, lib.records.input.nf), wall, trace.n)


def topology(name: str) -> Topology[Any]:
    """The plugin of topology ``name`` (a value of :data:`codegen.registry.TOPOLOGY_PACKAGES`).  A stage
    holds the topology's tables opaquely (it passes what ``derive`` returned back to the same plugin),
    hence ``Topology[Any]`` here and only here."""
    plugin: Topology[Any] = topology_module(name, "plugin")  # type: ignore[assignment]
    return plugin


def topology_of(model: Model) -> Topology[Any]:
    """The plugin of ``model.inverter.topology``."""
    return topology(model.inverter.topology)
