"""The T-type three-level topology behind :class:`codegen.topology.Topology` (MPDTC with virtual vectors).

This module is the plugin: its constants and functions are the protocol's
members.  Strategies mpdtc27 and mpdtc63; the baseline is 27-MPDTC.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

import numpy as np

from codegen.errors import Unsupported
from codegen.hostbuild import HostLib
from codegen.model import Model
from codegen.mpcc.states import adversarial
from codegen.mpcc.tables import MpccTables
from codegen.records import Record
from codegen.teststates import in_format
from codegen.topologies.ttype import fwstates, paper, scenarios, section, sim
from codegen.topologies.ttype import mpcc as mpcc_step
from codegen.topologies.ttype import reference as ref
from codegen.topologies.ttype import report as report_md
from codegen.topologies.ttype import states as test_states
from codegen.topologies.ttype import tables_text as text
from codegen.topologies.ttype.derive import ThreeLevelTables, derive_three_level, max_groups_of
from codegen.topologies.ttype.hostbuild import build_three_level_library
from codegen.topologies.ttype.modulator import render_modulator
from codegen.topologies.ttype.records import INPUT
from codegen.topologies.ttype.records import output_record as _output_record
from codegen.topologies.ttype.render import render_three_level
from codegen.topologies.ttype.vectors import N_STATES
from codegen.topology import Log, Progress, Trajectory, record_trajectory

name = "t-type"
title = "T-type three-level MPDTC"
strategies = section.strategies
input_record = INPUT
reference = "codegen.topologies.ttype.reference.step_batch"
trajectory_doc = "states evenly spaced over the 27-MPDTC run at rated speed and torque"
#: steady speeds whose closed-loop states join verification (the paper's Table 5: 300, 1800, 3000 r/min)
VERIFY_SPEEDS_RPM = (300.0, 1800.0, 3000.0)

#: the tables of either family: the MPDTC's, or the long-horizon family's (``codegen.mpcc``)
Tables = ThreeLevelTables | MpccTables


def _long(model: Model) -> bool:
    """The config's strategy is of the long-horizon family (``mpcc``)."""
    return section.family(model.controller.strategy) == section.MPCC


def report(model: Model, tables: Tables, target: str) -> str:
    if isinstance(tables, MpccTables):
        from codegen.mpcc.report import report_text

        return report_text(model, tables, target, "T-type three-level")
    return report_md.report_text(model, tables, target)


def step_batch(tables: Tables, states: np.ndarray) -> np.ndarray:
    if isinstance(tables, MpccTables):
        return mpcc_step.step_batch(tables, states)
    return ref.step_batch(tables, states)


def selftest_states(model: Model, tables: Tables, n: int, seed: int) -> np.ndarray:
    if isinstance(tables, MpccTables):
        return random_states(model, tables, n, seed)
    return fwstates.selftest_states(model, tables, n, seed)


def _modulator_tables(model: Model) -> ThreeLevelTables:
    """The MPDTC tables whose 7-segment sequences the modulator assumes (a long-horizon decision is one
    basic state, the sequence of its own: the modulator serves it unchanged)."""
    return derive_three_level(model.with_controller(strategy=section.families[section.MPDTC][0]))


def render(model: Model, tables: Tables, target: str) -> dict[str, str]:
    """The step (``render``) and, for a target that drives a power stage, its modulator and example
    interrupt routine (``modulator``: 7-segment sequence -> 12 gates on TIM1/TIM8 or ePWM1..6,
    docs/modulator.md)."""
    if isinstance(tables, MpccTables):
        return {**mpcc_step.render(model, tables, target), **render_modulator(model, _modulator_tables(model), target)}
    return {**render_three_level(model, tables, target), **render_modulator(model, tables, target)}


def output_record(model: Model) -> Record:
    """The strategy's output record: ``costs`` and ``cand`` as long as its longest candidate row (the
    long-horizon family: its own, for the config's horizon)."""
    if _long(model):
        return mpcc_step.output_record(model.controller.horizon)
    return _output_record(max_groups_of(model.controller.strategy))


def derive(model: Model) -> Tables:
    return mpcc_step.derive(model) if _long(model) else derive_three_level(model)


def needs_training(model: Model) -> bool:
    """No T-type table is trained: every table is derived by search."""
    return False


def train(model: Model, log: Log) -> Model:
    """The model itself (nothing to train)."""
    return model


def host_library(model: Model, tables: Tables, with_sim: bool = False) -> HostLib:
    if isinstance(tables, MpccTables):
        return mpcc_step.host_library(model, tables, with_sim=with_sim)
    return build_three_level_library(model, tables, with_sim=with_sim)


def closed_loop_states(model: Model, lib: HostLib) -> np.ndarray:
    runs = []
    for speed in VERIFY_SPEEDS_RPM:
        m = model.replace(scenario=dataclasses.replace(model.scenario, speed_ref_rpm=((0.0, speed),)))
        runs.append(sim.controller_inputs(sim.run_closed_loop(lib.ffi, lib.lib, m), m, lib.records.input.nf))
    return np.concatenate(runs)


def adversarial_states(model: Model, tables: Tables, n: int) -> np.ndarray:
    if isinstance(tables, MpccTables):
        base = _basic_previous(test_states.random_states(model, n, seed=5), 5)
        x = adversarial(base, test_states.limits(model)[:-2], "prev_vector", N_STATES, tables.nf.angle_guard_rad,
                        tables.nf.sincos_form.table_n)
        return in_format(x, input_record.bind(tables.nf))
    return test_states.adversarial_states(model, tables, n_target=n)


def _basic_previous(x: np.ndarray, seed: int) -> np.ndarray:
    """``x`` with ``prev_vector`` a switching state 0..26 but in one state of 500 (the long-horizon
    family applies no virtual vector; an id above 26 trips its guard)."""
    rng = np.random.default_rng(seed)
    x["prev_vector"] = np.where(rng.random(len(x)) < 0.002, x["prev_vector"], x["prev_vector"] % N_STATES)
    return x


def random_states(model: Model, tables: Tables, n: int, seed: int) -> np.ndarray:
    x = test_states.random_states(model, n, seed=seed)
    if isinstance(tables, MpccTables):
        x = _basic_previous(x, seed)
    return in_format(x, input_record.bind(tables.nf))


def trajectory(model: Model, progress: Progress | None = None) -> Trajectory:
    """The 27-MPDTC run at rated speed and rated torque (a long-horizon config: its own run)."""
    if _long(model):
        m = scenarios.steady_model(model, model.motor.rated_speed_rpm)
        lib = mpcc_step.host_library(m, mpcc_step.derive(m), with_sim=True)
        return record_trajectory(m, lib, sim.run_closed_loop, sim.controller_inputs, progress)
    base = scenarios.steady_model(model.with_controller(strategy=strategies[0]), model.motor.rated_speed_rpm)
    lib = build_three_level_library(base, derive_three_level(base), with_sim=True)
    return record_trajectory(base, lib, sim.run_closed_loop, sim.controller_inputs, progress)


def simulate(model: Model, chosen: list[str], plots: Path | None, log: Log, traces: Path | None = None) -> dict[str, Any]:
    return scenarios.run_three_level(model, chosen, plots=plots, log=log, traces=traces)


def sweep_eps(model: Model, eps_list: list[float], log: Log) -> NoReturn:
    raise Unsupported("--sweep-eps: the torque-threshold sweep belongs to the two-level strategies s1-s3; "
                      f"{model.source} is a t-type config (strategies {', '.join(strategies)}), "
                      "whose MPDTC has no torque threshold")


def paper_table(model: Model, data: dict[str, Any]) -> dict[str, Any]:
    return paper.paper_table(model, data)


def tables_text(model: Model, source: str | None, log: Log) -> str:
    if source is not None:
        raise Unsupported(f"--utilisation {source}: utilisation-derived switch tables belong to the two-level "
                          f"strategies s2/s3; {model.source} is a t-type config")
    return text.tables_report()


def tables_rows(model: Model, source: str | None, log: Log) -> list[dict[str, object]]:
    tables_text(model, source, log)  # the same refusals
    return text.tables_rows()


def export_tables(model: Model, path: Path, log: Log) -> NoReturn:
    raise Unsupported("--derive: t-type candidate tables are derived by search when generating and need "
                      f"no training run; {model.source} has nothing to export (see `mpcgen tables` for them)")


# -- simulation facet: this topology's simulator (sim.py) --
decision_field, trace_from, trace_metrics = sim.DECISION_FIELD, sim.trace_from, sim.trace_metrics
closed_loop_trace, period_stepper, firmware_plant = (sim.SIMULATOR.closed_loop_trace, sim.SIMULATOR.period_stepper,
                                                     sim.SIMULATOR.firmware_plant)


def essential_ops(model: Model, tables: Tables) -> dict[str, dict[str, int]]:
    """Essential operations per step, per candidate, per member, per virtual member and per
    unclamped T_N (``opcount``): the cycle bound (the long-horizon family: ``codegen.mpcc.opcount``)."""
    from codegen.topologies.ttype import opcount

    if isinstance(tables, MpccTables):
        from codegen.mpcc import opcount as mpcc_opcount

        return mpcc_opcount.essential_ops(tables)

    return opcount.essential_ops(tables)


def op_multiplicities(model: Model, tables: Tables, states: np.ndarray, expected: np.ndarray) -> dict[str, np.ndarray]:
    """Per state, how often each unit of ``essential_ops`` runs: the output's ``n_eval`` and
    ``n_members``, and the reference's count of virtual members and of unclamped T_N (the long-horizon
    family: ``codegen.mpcc.opcount.multiplicities``)."""
    if isinstance(tables, MpccTables):
        from codegen.mpcc import opcount as mpcc_opcount

        return mpcc_opcount.multiplicities(tables, states, expected)
    deadbeat = ref.deadbeat_counts(tables, states)
    return {"per_candidate": expected["n_eval"], "per_member": expected["n_members"],
            "per_virtual_member": deadbeat["virtual"], "per_unclamped": deadbeat["unclamped"]}


if TYPE_CHECKING:  # mypy checks this module against the protocol it implements
    from codegen.topologies.ttype import plugin as _this
    from codegen.topology import Topology

    _implements: Topology[Tables] = _this
