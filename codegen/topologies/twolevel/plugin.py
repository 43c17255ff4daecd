"""The two-level topology behind :class:`codegen.topology.Topology` (MPTC with simplified strategies).

This module is the plugin: its constants and functions are the protocol's
members.  Strategies conventional, s1, s2, s3; the baseline is the
conventional controller.  Everything delegates to this package: tables
(``switch_tables``, ``derive``), C (``render``; the modulator and the
example interrupt routine: ``modulator``), reference (``reference``),
test states (``states``, ``fwstates``), plant (``sim``), scenarios and
metrics (``scenarios``, ``metrics``, ``plots``), table printing
(``tables_text``) and the trained-tables artefact (``tables_file``).
"""
from __future__ import annotations

import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from codegen.hostbuild import HostLib
from codegen.model import Model
from codegen.mpcc.states import adversarial
from codegen.mpcc.tables import MpccTables
from codegen.records import Record
from codegen.teststates import in_format
from codegen.topologies.twolevel import fwstates, paper, scenarios, section, sim, switch_tables, tables_file
from codegen.topologies.twolevel import mpcc as mpcc_step
from codegen.topologies.twolevel import reference as ref
from codegen.topologies.twolevel import report as report_md
from codegen.topologies.twolevel import states as test_states
from codegen.topologies.twolevel import tables_text as text
from codegen.topologies.twolevel.derive import TwoLevelTables
from codegen.topologies.twolevel.hostbuild import build_host_library
from codegen.topologies.twolevel.modulator import render_modulator
from codegen.topologies.twolevel.records import INPUT, OUTPUT
from codegen.topologies.twolevel.render import render_two_level
from codegen.topology import Log, Progress, Trajectory, record_trajectory

name = "two-level"
title = "two-level MPTC"
strategies = section.strategies
input_record = INPUT
reference = "codegen.topologies.twolevel.reference.step_batch"
trajectory_doc = "states evenly spaced over the conventional controller's closed-loop run of the scenario"

#: the tables of either family: the MPTC's, or the long-horizon family's (``codegen.mpcc``)
Tables = TwoLevelTables | MpccTables


def _long(model: Model) -> bool:
    """The config's strategy is of the long-horizon family (``mpcc``)."""
    return section.family(model.controller.strategy) == section.MPCC


def needs_training(model: Model) -> bool:
    return not _long(model) and switch_tables.needs_training(model)


def derive(model: Model) -> Tables:
    return mpcc_step.derive(model) if _long(model) else switch_tables.tables_for(model)


def report(model: Model, tables: Tables, target: str) -> str:
    if isinstance(tables, MpccTables):
        from codegen.mpcc.report import report_text

        return report_text(model, tables, target, title)
    return report_md.report_text(model, tables, target)


def step_batch(tables: Tables, states: np.ndarray) -> np.ndarray:
    if isinstance(tables, MpccTables):
        return mpcc_step.step_batch(tables, states)
    return ref.step_batch(tables, states)


def selftest_states(model: Model, tables: Tables, n: int, seed: int) -> np.ndarray:
    if isinstance(tables, MpccTables):
        return random_states(model, tables, n, seed)
    return fwstates.selftest_states(model, tables, n, seed)


def output_record(model: Model) -> Record:
    """The output record: the MPTC's (the same for every MPTC strategy: 7 candidate slots), or the
    long-horizon family's for the config's horizon."""
    return mpcc_step.output_record(model.controller.horizon) if _long(model) else OUTPUT


def render(model: Model, tables: Tables, target: str) -> dict[str, str]:
    """The step (``render``) and, for a target that drives a power stage, its modulator and example
    interrupt routine (``modulator``: switching state -> TIM1 / ePWM1..3 compares, docs/modulator.md;
    the long-horizon step's decision is the same ``sw``)."""
    step = mpcc_step.render(model, tables, target) if isinstance(tables, MpccTables) \
        else render_two_level(model, tables, target)
    return {**step, **render_modulator(model, tables, target)}  # type: ignore[arg-type]


def host_library(model: Model, tables: Tables, with_sim: bool = False) -> HostLib:
    if isinstance(tables, MpccTables):
        return mpcc_step.host_library(model, tables, with_sim=with_sim)
    return build_host_library(model, tables, with_sim=with_sim)


def closed_loop_states(model: Model, lib: HostLib) -> np.ndarray:
    return sim.controller_inputs(sim.run_closed_loop(lib.ffi, lib.lib, model), model, lib.records.input.nf)


def adversarial_states(model: Model, tables: Tables, n: int) -> np.ndarray:
    if isinstance(tables, MpccTables):
        base = test_states.random_states(model, n, seed=5)
        x = adversarial(base, test_states.limits(model), "prev_sw", 8, tables.nf.angle_guard_rad,
                        tables.nf.sincos_form.table_n)
        return in_format(x, input_record.bind(tables.nf))
    return test_states.adversarial_states(model, tables, ref.step_batch, n_target=n)


def random_states(model: Model, tables: Tables, n: int, seed: int) -> np.ndarray:
    return in_format(test_states.random_states(model, n, seed=seed), input_record.bind(tables.nf))


def trajectory(model: Model, progress: Progress | None = None) -> Trajectory:
    """The conventional controller's closed-loop run of the config's scenario (a long-horizon config:
    its own run)."""
    if _long(model):
        lib = mpcc_step.host_library(model, mpcc_step.derive(model), with_sim=True)
        return record_trajectory(model, lib, sim.run_closed_loop, sim.controller_inputs, progress)
    base = model.with_controller(strategy=strategies[0])
    lib = build_host_library(base, switch_tables.tables_for(base), with_sim=True)
    return record_trajectory(base, lib, sim.run_closed_loop, sim.controller_inputs, progress)


def simulate(model: Model, chosen: list[str], plots: Path | None, log: Log, traces: Path | None = None) -> dict[str, Any]:
    return scenarios.run_scenarios(model, chosen, plots=plots, log=log, traces=traces)


def sweep_eps(model: Model, eps_list: list[float], log: Log) -> dict[str, Any]:
    return scenarios.run_threshold_sweep(model, eps_list, log=log)


def paper_table(model: Model, data: dict[str, Any]) -> dict[str, Any]:
    return paper.paper_table(model, data)


def tables_text(model: Model, source: str | None, log: Log) -> str:
    return text.two_level_tables_text(model, source or "training", log)


def tables_rows(model: Model, source: str | None, log: Log) -> list[dict[str, object]]:
    return text.two_level_tables_rows(model, source or "training", log)


def train(model: Model, log: Log) -> Model:
    """``model`` with the s2/s3 tables trained on its scenario read in: the artefact of
    :func:`export_tables` written to a temporary file and read back as a config's ``tables_file`` is
    (:func:`tables_file.load_into`); the model names no file afterwards (its config hash carries the
    tables' digest)."""
    with tempfile.TemporaryDirectory(prefix="mpcgen-tables-") as tmp:
        path = Path(tmp) / "trained_tables.json"
        export_tables(model, path, log)
        trained = tables_file.load_into(model.with_controller(tables_file=str(path)))
    log(f"training stage: tables trained on the scenario of {model.name} (write them once with "
        f"`mpcgen tables {model.source} --derive -o FILE` and set controller.tables_file to skip this stage)")
    return trained.with_controller(tables_file=None)


def export_tables(model: Model, path: Path, log: Log) -> str:
    log(f"training run: conventional controller over the {model.scenario.duration_s:g} s scenario of {model.name}")
    data = switch_tables.export_tables(model, path, progress=lambda f: log(f"  training {f:5.0%}"))
    thin = {k: len(v) for k, v in data["thin_cells"].items()}
    return (f"wrote {path}: s2 and s3 switch tables from {data['training']['samples_outside_eps']} training "
            f"samples outside eps_T (training config {data['training']['training_config_hash']}; cells with "
            f"< {data['derivation']['min_cell_samples']} samples taking the published-derived set: "
            f"s2 {thin['s2']}, s3 {thin['s3']}); name it in the config as controller.tables_file")


# -- simulation facet: this topology's simulator (sim.py) --
decision_field, trace_from, trace_metrics = sim.DECISION_FIELD, sim.trace_from, sim.trace_metrics
closed_loop_trace, period_stepper, firmware_plant = (sim.SIMULATOR.closed_loop_trace, sim.SIMULATOR.period_stepper,
                                                     sim.SIMULATOR.firmware_plant)


def essential_ops(model: Model, tables: Tables) -> dict[str, dict[str, int]]:
    """Essential operations per step and per candidate (``opcount``): the cycle bound (the long-horizon
    family: ``codegen.mpcc.opcount``)."""
    from codegen.topologies.twolevel import opcount

    if isinstance(tables, MpccTables):
        from codegen.mpcc import opcount as mpcc_opcount

        return mpcc_opcount.essential_ops(tables)

    return opcount.essential_ops(tables)


def op_multiplicities(model: Model, tables: Tables, states: np.ndarray, expected: np.ndarray) -> dict[str, np.ndarray]:
    """Per state, how often each unit of ``essential_ops`` runs: the output's ``n_eval`` candidates (the
    long-horizon family: ``codegen.mpcc.opcount.multiplicities``)."""
    if isinstance(tables, MpccTables):
        from codegen.mpcc import opcount as mpcc_opcount

        return mpcc_opcount.multiplicities(tables, states, expected)
    return {"per_candidate": expected["n_eval"]}


if TYPE_CHECKING:  # mypy checks this module against the protocol it implements
    from codegen.topologies.twolevel import plugin as _this
    from codegen.topology import Topology

    _implements: Topology[Tables] = _this
