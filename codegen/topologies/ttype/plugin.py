"""The T-type three-level topology behind :class:`codegen.topology.Topology` (MPDTC, seed 000).

Strategies mpdtc27 and mpdtc63; the baseline is 27-MPDTC.  Everything here
delegates to this package's modules.
"""
from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import Any

import numpy as np

from codegen.errors import Unsupported
from codegen.hostbuild import HostLib
from codegen.model import STRATEGIES_BY_TOPOLOGY, Model
from codegen.topologies.ttype import fwstates, reference, report, scenarios, sim, states, tables_text
from codegen.topologies.ttype.derive import derive_three_level
from codegen.topologies.ttype.hostbuild import build_three_level_library
from codegen.topologies.ttype.records import INPUT, OUTPUT
from codegen.topologies.ttype.render import render_three_level
from codegen.topology import Log, Progress, Trajectory

#: steady speeds whose closed-loop states join verification (seed 000 Table 5: 300, 1800, 3000 r/min)
VERIFY_SPEEDS_RPM = (300.0, 1800.0, 3000.0)


class TType:
    """T-type three-level inverter, 27- and 63-MPDTC with virtual vectors."""

    name = "t-type"
    title = "T-type three-level MPDTC"
    strategies = STRATEGIES_BY_TOPOLOGY["t-type"]
    input_record = INPUT
    output_record = OUTPUT
    reference = "codegen.topologies.ttype.reference.step_batch"
    trajectory_doc = "states evenly spaced over the 27-MPDTC run at rated speed and torque"

    def derive(self, model: Model, progress: Progress | None = None) -> Any:
        return derive_three_level(model)

    def render(self, model: Model, tables: Any, target: str) -> dict[str, str]:
        return render_three_level(model, tables, target)

    def report(self, model: Model, tables: Any, target: str) -> str:
        return report.report_text(model, tables, target)

    def step_batch(self, tables: Any, states: np.ndarray) -> np.ndarray:
        return reference.step_batch(tables, states)

    def host_library(self, model: Model, tables: Any, with_sim: bool = False) -> HostLib:
        return build_three_level_library(model, tables, with_sim=with_sim)

    def closed_loop_states(self, model: Model, lib: HostLib) -> np.ndarray:
        runs = []
        for speed in VERIFY_SPEEDS_RPM:
            m = model.replace(scenario=dataclasses.replace(model.scenario, speed_ref_rpm=((0.0, speed),)))
            runs.append(sim.controller_inputs3(sim.run_closed_loop3(lib.ffi, lib.lib, m), m))
        return np.concatenate(runs)

    def adversarial_states(self, model: Model, tables: Any, n: int) -> np.ndarray:
        return states.adversarial_states(model, tables, n_target=n)

    def random_states(self, model: Model, n: int, seed: int) -> np.ndarray:
        return states.random_states(model, n, seed=seed)

    def selftest_states(self, model: Model, tables: Any, n: int, seed: int) -> np.ndarray:
        return fwstates.selftest_states(model, tables, n, seed)

    def trajectory(self, model: Model, progress: Progress | None = None) -> Trajectory:
        base = scenarios.steady_model(model.with_controller(strategy=self.strategies[0]),
                                      model.motor.rated_speed_rpm)
        lib = build_three_level_library(base, derive_three_level(base), with_sim=True)
        t0 = time.perf_counter()
        trace = sim.run_closed_loop3(lib.ffi, lib.lib, base, progress=progress)
        wall = time.perf_counter() - t0
        return Trajectory(sim.controller_inputs3(trace, base), wall, trace.n)

    def simulate(self, model: Model, strategies: list[str], plots: Path | None, log: Log) -> dict:
        return scenarios.run_three_level(model, strategies, plots=plots, log=log)

    def sweep_eps(self, model: Model, eps_list: list[float], log: Log) -> dict:
        raise Unsupported("--sweep-eps: the torque-threshold sweep belongs to the two-level strategies s1-s3; "
                          f"{model.source} is a t-type config (strategies {', '.join(self.strategies)}), "
                          "whose MPDTC has no torque threshold")

    def tables_text(self, model: Model, source: str | None, log: Log) -> str:
        if source is not None:
            raise Unsupported(f"--utilisation {source}: utilisation-derived switch tables belong to the two-level "
                              f"strategies s2/s3; {model.source} is a t-type config")
        return tables_text.tables_report()

    def export_tables(self, model: Model, path: Path, log: Log) -> str:
        raise Unsupported("--derive: t-type candidate tables are derived by search when generating and need "
                          f"no training run; {model.source} has nothing to export (see `mpcgen tables` for them)")


PLUGIN = TType()
