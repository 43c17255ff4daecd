"""The two-level topology behind :class:`codegen.topology.Topology` (MPTC, seed 001).

Strategies conventional, s1, s2, s3; the baseline is the conventional
controller.  Everything here delegates to this package's modules: tables
(``switch_tables``, ``derive``), C (``render``), reference (``reference``),
test states (``states``, ``fwstates``), plant (``sim``), scenarios and
metrics (``scenarios``, ``metrics``, ``plots``) and table printing
(``tables_text``).
"""
from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from codegen.hostbuild import HostLib
from codegen.model import STRATEGIES_BY_TOPOLOGY, Model
from codegen.topologies.twolevel import (
    fwstates,
    reference,
    report,
    scenarios,
    sim,
    states,
    switch_tables,
    tables_text,
)
from codegen.topologies.twolevel.hostbuild import build_host_library
from codegen.topologies.twolevel.records import INPUT, OUTPUT
from codegen.topologies.twolevel.render import render_two_level
from codegen.topologies.twolevel.switch_tables import tables_for
from codegen.topology import Log, Progress, Trajectory


class TwoLevel:
    """Two-level voltage-source inverter, MPTC with simplified strategies 1-3."""

    name = "two-level"
    title = "two-level MPTC"
    strategies = STRATEGIES_BY_TOPOLOGY["two-level"]
    input_record = INPUT
    output_record = OUTPUT
    reference = "codegen.topologies.twolevel.reference.step_batch"
    trajectory_doc = "states evenly spaced over the conventional controller's closed-loop run of the scenario"

    def derive(self, model: Model, progress: Progress | None = None) -> Any:
        return tables_for(model, progress)

    def render(self, model: Model, tables: Any, target: str) -> dict[str, str]:
        return render_two_level(model, tables, target)

    def report(self, model: Model, tables: Any, target: str) -> str:
        return report.report_text(model, tables, target)

    def step_batch(self, tables: Any, states: np.ndarray) -> np.ndarray:
        return reference.step_batch(tables, states)

    def host_library(self, model: Model, tables: Any, with_sim: bool = False) -> HostLib:
        return build_host_library(model, tables, with_sim=with_sim)

    def closed_loop_states(self, model: Model, lib: HostLib) -> np.ndarray:
        return sim.controller_inputs(sim.run_closed_loop(lib.ffi, lib.lib, model), model)

    def adversarial_states(self, model: Model, tables: Any, n: int) -> np.ndarray:
        return states.adversarial_states(model, tables, reference.step_batch, n_target=n)

    def random_states(self, model: Model, n: int, seed: int) -> np.ndarray:
        return states.random_states(model, n, seed=seed)

    def selftest_states(self, model: Model, tables: Any, n: int, seed: int) -> np.ndarray:
        return fwstates.selftest_states(model, tables, n, seed)

    def trajectory(self, model: Model, progress: Progress | None = None) -> Trajectory:
        base = model.with_controller(strategy=self.strategies[0])
        lib = build_host_library(base, tables_for(base), with_sim=True)
        t0 = time.perf_counter()
        trace = sim.run_closed_loop(lib.ffi, lib.lib, base, progress=progress)
        wall = time.perf_counter() - t0
        return Trajectory(sim.controller_inputs(trace, base), wall, trace.n)

    def simulate(self, model: Model, strategies: list[str], plots: Path | None, log: Log) -> dict:
        return scenarios.run_scenarios(model, strategies, plots=plots, log=log)

    def sweep_eps(self, model: Model, eps_list: list[float], log: Log) -> dict:
        return scenarios.run_threshold_sweep(model, eps_list, log=log)

    def tables_text(self, model: Model, source: str | None, log: Log) -> str:
        return tables_text.two_level_tables_text(model, source or "training", log)

    def export_tables(self, model: Model, path: Path, log: Log) -> str:
        log(f"training run: conventional controller over the {model.scenario.duration_s:g} s scenario of {model.name}")
        data = switch_tables.export_tables(model, path, progress=lambda f: log(f"  training {f:5.0%}"))
        thin = {k: len(v) for k, v in data["thin_cells"].items()}
        return (f"wrote {path}: s2 and s3 switch tables from {data['training']['samples_outside_eps']} training "
                f"samples outside eps_T (training config {data['training']['training_config_hash']}; cells with "
                f"< {data['derivation']['min_cell_samples']} samples taking the published-derived set: "
                f"s2 {thin['s2']}, s3 {thin['s3']}); name it in the config as controller.tables_file")


PLUGIN = TwoLevel()
