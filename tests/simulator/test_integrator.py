"""The plant's integrators (``plant.integrator``, docs/simulation.md "Integration") against a tight reference.

The reference (codegen/simulator/tightref.py) writes the plant's equations again in Python and
integrates them with scipy's ``solve_ivp(method="DOP853", rtol=1e-10, atol=1e-12)``, independently
of the C.  Checked here, on every example (the seed scenarios and servo400w):

- open loop: a closed-loop run's inverter (its trace, period by period) replayed through DOP853 from
  the run's first sample; the largest phase-current error of each integrator over the first
  ``WINDOW`` periods is bounded (asserted: exact <= ``EXACT_BOUND_A`` = 1e-10 A, rk4 <= ``RK4_BOUND_A``
  = 1e-9 A; measured: exact 1e-13 .. 2e-11 A, rk4 1e-12 .. 8e-11 A, the T-type the larger, its
  neutral point integrating the reference's own error), and so is the T-type's neutral point;
- closed loop: the loop with the DOP853 plant (a period stepper whose plant state is DOP853's every
  period) decides exactly as the "exact" run (T-type: vector and T_N) over the first ``PREFIX`` periods
  of every example's scenario (and of the T-type's Table 5 runs); every period of every run ``mpcgen
  simulate`` makes, every strategy, in the slow test;
- the exact integrator keeps the simulator's other properties: a chunked run equals one long run and
  the period stepper equals the run bit for bit; dead time and the measurement delay against the
  reference; device drops (held over a piece, RK4 where a current changes sign) against RK4; the
  exact single-interval plant against DOP853 at its edges (long pieces cut in parts, tiny pieces,
  Rs = 0, the speed imposed or free, Ld != Lq).
"""
from __future__ import annotations

import dataclasses
import functools
import importlib
import math
from typing import Any

import numpy as np
import pytest

from codegen.config import load_config
from codegen.errors import ConfigError
from codegen.model import Model
from codegen.registry import TOPOLOGY_PACKAGES
from codegen.simulator import tightref
from codegen.simulator.driver import InverterPeriod, run_chunked
from codegen.simulator.integrators import with_integrator
from codegen.topology import topology_of

from conftest import EXAMPLES, TTYPE_STRATEGIES, TWO_LEVEL

#: the examples (every seed scenario, and servo400w)
EXAMPLE_NAMES = ("seed001_spmsm", "seed001_ipmsm", "seed000_tlevel", "servo400w")
#: periods of the open-loop replay window
WINDOW = 1000
#: asserted bounds on the largest phase-current error against DOP853 over WINDOW periods, A
EXACT_BOUND_A = 1e-10
RK4_BOUND_A = 1e-9
#: periods of the closed-loop decision check (the whole scenarios: test_closed_loop_whole_scenarios)
PREFIX = 1500


@functools.cache
def _setup(name: str, **overrides: object) -> tuple[Model, Any, Any]:
    """(baseline model, its plugin, its host library with the simulator) of an example."""
    m = load_config(EXAMPLES / f"{name}.toml", dict(overrides))
    topo = topology_of(m)
    base = m.with_controller(strategy=topo.strategies[0])
    return base, topo, topo.host_library(base, topo.derive(base), with_sim=True)


@functools.cache
def _trace(name: str, integrator: str) -> Any:
    base, topo, lib = _setup(name)
    return topo.closed_loop_trace(with_integrator(base, integrator), lib)


def test_config_field():
    m = load_config(EXAMPLES / "seed001_spmsm.toml", {"plant.integrator": "exact"})
    assert m.plant.integrator == "exact"
    assert load_config(EXAMPLES / "seed001_spmsm.toml").plant.integrator == "exact"  # the default
    with pytest.raises(ConfigError) as e:
        load_config(EXAMPLES / "seed001_spmsm.toml", {"plant.integrator": "euler"})
    assert "\n" not in str(e.value) and "rk4, exact" in str(e.value)


@pytest.mark.parametrize("name", EXAMPLE_NAMES)
def test_open_loop_current_error_against_dop853(name):
    base, _topo, _lib = _setup(name)
    errors = {}
    for integrator in ("rk4", "exact"):
        trace = _trace(name, integrator)
        errors[integrator] = tightref.current_error(with_integrator(base, integrator), trace, WINDOW)
    assert errors["exact"] <= EXACT_BOUND_A, errors
    assert errors["rk4"] <= RK4_BOUND_A, errors
    # not vacuous: the currents of the window reach amperes
    assert np.max(np.abs(_trace(name, "exact").ia_a[:WINDOW])) > 1.0


def test_neutral_point_against_dop853():
    base, _topo, _lib = _setup("seed000_tlevel")
    trace = _trace("seed000_tlevel", "exact")
    ref = tightref.replay(with_integrator(base, "exact"), trace, 400)
    assert np.max(np.abs(trace.vo_v[1:401] - ref[:, 4])) < 1e-9
    assert np.ptp(trace.vo_v[:400]) > 1e-3  # V_o moves


def _decisions(trace: Any, topo: Any) -> np.ndarray:
    """The decision field, with the T-type's T_N beside its vector (bits)."""
    d = np.asarray(getattr(trace, topo.decision_field)).astype(np.float64)
    if hasattr(trace, "t_n_s"):
        d = np.stack([d, np.asarray(trace.t_n_s)])
    return d


def _reference_loop(model: Model, topo: Any, lib: Any, n: int, initial_speed_rpm: float = 0.0) -> Any:
    stepper = topo.period_stepper(lib, model, initial_speed_rpm=initial_speed_rpm)
    return tightref.closed_loop(stepper, lib.step_batch, topo.trace_from, n)


@pytest.mark.parametrize("name", EXAMPLE_NAMES)
def test_closed_loop_decisions_equal_the_dop853_loop(name):
    """Over the first PREFIX periods: the exact run's decisions are the DOP853 plant's, and its
    currents stay within a few 1e-12 A of it."""
    base, topo, lib = _setup(name)
    exact = _trace(name, "exact")
    ref = _reference_loop(with_integrator(base, "exact"), topo, lib, PREFIX)
    assert np.array_equal(_decisions(ref, topo), _decisions(exact, topo)[..., :PREFIX])
    assert np.max(np.abs(ref.ia_a - exact.ia_a[:PREFIX])) < 1e-10


def _ttype_table5_runs() -> list[tuple[str, Model, float]]:
    from codegen.topologies.ttype import scenarios

    base, _topo, _lib = _setup("seed000_tlevel")
    return [(key, m, speed) for key, m, speed in scenarios.runs_of(base)]


@pytest.mark.parametrize("run", [0, 1, 2, 3])
def test_ttype_table5_runs_decide_as_the_dop853_loop(run):
    """The T-type seed's simulate set (Table 5: 300/1800/3000 r/min steady, the rated load step), first
    PREFIX/3 periods each; the exact run against the DOP853 loop, and against RK4."""
    from codegen.topologies.ttype.sim import run_closed_loop

    _base, topo, lib = _setup("seed000_tlevel")
    key, m, speed = _ttype_table5_runs()[run]
    n = PREFIX // 3
    exact = run_closed_loop(lib.ffi, lib.lib, with_integrator(m, "exact"), initial_speed_rpm=speed)
    rk4 = run_closed_loop(lib.ffi, lib.lib, with_integrator(m, "rk4"), initial_speed_rpm=speed)
    ref = _reference_loop(with_integrator(m, "exact"), topo, lib, n, initial_speed_rpm=speed)
    assert np.array_equal(_decisions(ref, topo), _decisions(exact, topo)[..., :n]), key
    # RK4: the same vectors (its T_N may differ in the last bits where a float32 input rounds the other way)
    assert np.array_equal(rk4.vector, exact.vector), key


@pytest.mark.slow
@pytest.mark.parametrize("name,strategy", [(n, s) for n in ("seed001_spmsm", "seed001_ipmsm", "servo400w")
                                           for s in TWO_LEVEL] + [("seed000_tlevel", s) for s in TTYPE_STRATEGIES])
def test_closed_loop_whole_scenarios(name, strategy):
    """Every period of every run ``mpcgen simulate`` makes of the example (the T-type's: the Table 5 set),
    every strategy: the DOP853 loop decides as the exact run, and the RK4 run chooses the same vectors
    (its T-type T_N differs in the last bits in 4 of the 56 000 periods, where a float32 input rounds
    the other way)."""
    from codegen.stages.training import with_trained_tables
    from codegen.topologies.ttype import scenarios

    model = with_trained_tables(load_config(EXAMPLES / f"{name}.toml", {"controller.strategy": strategy}), [strategy])
    topo = topology_of(model)
    lib = topo.host_library(model, topo.derive(model), with_sim=True)
    sim = importlib.import_module(f"{TOPOLOGY_PACKAGES[model.inverter.topology]}.sim")
    runs = scenarios.runs_of(model) if model.inverter.topology == "t-type" else [("scenario", model, 0.0)]
    for key, m, speed in runs:
        traces = {integrator: sim.run_closed_loop(lib.ffi, lib.lib, with_integrator(m, integrator),
                                                  initial_speed_rpm=speed) for integrator in ("rk4", "exact")}
        exact = traces["exact"]
        ref = _reference_loop(with_integrator(m, "exact"), topo, lib, int(exact.n), initial_speed_rpm=speed)
        assert np.array_equal(_decisions(ref, topo), _decisions(exact, topo)), key
        assert np.array_equal(getattr(traces["rk4"], topo.decision_field), getattr(exact, topo.decision_field)), key


def test_exact_chunked_and_stepped_equal_one_run():
    """Bit for bit: chunks of 777 periods, and the period stepper fed the step's decisions."""
    from codegen.topologies.ttype import sim

    base, topo, lib = _setup("seed000_tlevel")
    model = with_integrator(base, "exact")
    model = model.replace(scenario=dataclasses.replace(model.scenario, duration_s=0.05))

    whole = sim.run_closed_loop(lib.ffi, lib.lib, model)
    params = sim.params_from_model(lib.ffi, model, None)
    chunked = run_chunked(lib.ffi, lib.lib, sim.SIM, model, params, None, 777)
    stepper = topo.period_stepper(lib, model)
    for _ in range(whole.n):
        stepper.finish(lib.step_batch(stepper.input()))
    stepped = topo.trace_from(stepper.result(), model)
    for name in ("ia_a", "ib_a", "vo_v", "theta_e_rad", "vector"):
        assert np.array_equal(getattr(whole, name), chunked[name]), name
        assert np.array_equal(getattr(whole, name), getattr(stepped, name)), name


@pytest.mark.parametrize("name,overrides", [
    ("seed001_ipmsm", {"plant.dead_time_s": 2e-6}),
    ("seed000_tlevel", {"plant.dead_time_s": 1e-6}),
    ("seed001_spmsm", {"plant.measurement_delay_s": 20e-6}),
], ids=["dead-time-two-level", "dead-time-ttype", "measurement-delay"])
def test_exact_with_dead_time_and_delay_against_dop853(name, overrides):
    base, topo, lib = _setup(name, **overrides)
    model = with_integrator(base, "exact")
    trace = topo.closed_loop_trace(model, lib)
    assert tightref.current_error(model, trace, 600) <= EXACT_BOUND_A


def test_exact_with_device_drops_against_rk4():
    """Drops held over a piece, RK4 for a piece whose current changes sign: the currents stay with
    RK4's over the window (both are first-order where a drop flips)."""
    base, topo, lib = _setup("seed001_spmsm", **{"plant.device_drop_v": 1.5})
    rk4 = topo.closed_loop_trace(with_integrator(base, "rk4"), lib)
    exact = topo.closed_loop_trace(with_integrator(base, "exact"), lib)
    n = 4000
    assert np.max(np.abs(rk4.ia_a[:n] - exact.ia_a[:n])) < 1e-6
    assert np.array_equal(rk4.sw[:n], exact.sw[:n])


# ------------------------------------------------------------------ the plant alone, one interval

@pytest.fixture(scope="module")
def stub(tmp_path_factory):
    """(ffi, lib): the two-level simulator with the stub controller (tests/fixtures/stub_twolevel)."""
    from codegen.topologies.twolevel.sim import SIM
    from tests.fixtures.simbuild import build_stub_library

    return build_stub_library(SIM, "", tmp_path_factory.mktemp("integrator_stub"))


DT = 50e-6
IPMSM = dict(rs_ohm=0.25, ld_h=3.3e-3, lq_h=7.3e-3, psi_f_wb=0.2264, pole_pairs=3, j_kgm2=0.01, b_nms=0.002,
             udc_v=312.0)
SERVO = dict(rs_ohm=0.9, ld_h=3.2e-3, lq_h=3.2e-3, psi_f_wb=0.036, pole_pairs=4, j_kgm2=5e-5, b_nms=0.0,
             udc_v=310.0)


def _ref_interval(d: dict[str, float], sw: int, x0: list[float], load: float, imposed: int, dt: float) -> np.ndarray:
    plant = tightref.ReferencePlant(d["rs_ohm"], d["ld_h"], d["lq_h"], d["psi_f_wb"], int(d["pole_pairs"]),
                                    d["j_kgm2"], d["b_nms"], d["udc_v"], 1e-3, 0.0, bool(imposed))
    lv = tuple(2 * ((sw >> b) & 1) - 1 for b in (2, 1, 0))
    return plant.piece(np.array([*x0, 0.0]), lv, load, dt)[:4]  # type: ignore[arg-type]


@pytest.mark.parametrize("motor", [IPMSM, SERVO, {**SERVO, "rs_ohm": 0.0}], ids=["ipmsm", "spmsm", "rs0"])
@pytest.mark.parametrize("imposed", [0, 1], ids=["free", "imposed"])
@pytest.mark.parametrize("dt", [DT, 1e-9, 1e-3], ids=["50us", "1ns", "1ms"])
def test_exact_interval_against_dop853(stub, motor, imposed, dt):
    """One interval of the exact two-level plant (twolevel_plant_advance, integrator 1) from a state with
    current and speed, every switching state: the end state within rounding of DOP853's."""
    from tests.fixtures.plantref import plant_params

    ffi, lib = stub
    x0 = [-3.0, 7.0, 150.0, 2.0]
    for sw in range(8):
        p = plant_params(ffi, "sim_params_t", motor, imposed)
        p.integrator = 1
        s = ffi.new("pmsm_state_t *", dict(zip(("i_d_a", "i_q_a", "omega_m_rad_s", "theta_e_rad"), x0)))
        assert lib.twolevel_plant_advance(s, p, sw, 2.0, dt, 1) == 0
        got = np.array([s.i_d_a, s.i_q_a, s.omega_m_rad_s, s.theta_e_rad])
        ref = _ref_interval(motor, sw, x0, 2.0, imposed, dt)
        scale = 1.0 + np.max(np.abs(ref[:2]))
        assert np.max(np.abs(got[:2] - ref[:2])) < 1e-9 * scale, (sw, got, ref)
        assert abs(got[2] - ref[2]) < 1e-9 * (1.0 + abs(ref[2]))
        assert abs(math.remainder(got[3] - ref[3], 2.0 * math.pi)) < 1e-9


def test_exact_interval_invalid_integrator_refused(stub):
    from tests.fixtures.plantref import plant_params

    ffi, lib = stub
    p = plant_params(ffi, "twolevel_sim_params_t", IPMSM)
    p.common.dt_s, p.common.integrator, p.substeps = DT, 2, 50
    state = ffi.new("twolevel_sim_state_t *")
    assert lib.twolevel_sim_init(p, state) == -1
    p.common.integrator = 1
    assert lib.twolevel_sim_init(p, state) == 0


@pytest.fixture(scope="module")
def stub_ttype(tmp_path_factory):
    """(ffi, lib): the T-type simulator with the stub controller (tests/fixtures/stub_ttype)."""
    from codegen.topologies.ttype.sim import SIM
    from tests.fixtures.simbuild import build_stub_library

    return build_stub_library(SIM, "", tmp_path_factory.mktemp("integrator_stub_ttype"))


TLEVEL = dict(rs_ohm=1.75, ld_h=1.6e-3, lq_h=1.6e-3, psi_f_wb=0.045, pole_pairs=5, j_kgm2=5e-4, b_nms=1e-4,
              udc_v=220.0, c_f=1e-4)


@pytest.mark.parametrize("motor", [TLEVEL, {**TLEVEL, "lq_h": 3.1e-3}], ids=["spmsm", "salient"])
@pytest.mark.parametrize("imposed", [0, 1], ids=["free", "imposed"])
def test_exact_ttype_periods_against_dop853(stub_ttype, motor, imposed):
    """Seven-segment periods of the exact T-type plant (the neutral point a state; the rotor frame with
    its V_o products for Ld != Lq, the stationary frame for Ld = Lq) against DOP853, 40 periods of random
    states and segment times, with dead time."""
    from tests.fixtures.plantref import plant_params

    ffi, lib = stub_ttype
    rng = np.random.default_rng(5)
    p = plant_params(ffi, "ttype_sim_params_t", motor, imposed)
    p.substep_max_s, p.common.dt_s, p.common.integrator, p.common.dead_time_s = 1e-6, DT, 1, 0.5e-6
    plant = tightref.ReferencePlant(motor["rs_ohm"], motor["ld_h"], motor["lq_h"], motor["psi_f_wb"],
                                    int(motor["pole_pairs"]), motor["j_kgm2"], motor["b_nms"], motor["udc_v"],
                                    motor["c_f"], 0.5e-6, bool(imposed))
    s = ffi.new("ttype_plant_state_t *", {"motor": {"i_d_a": 2.0, "i_q_a": 6.0, "omega_m_rad_s": 200.0,
                                                    "theta_e_rad": 0.5}, "vo_v": 3.0})
    x = np.array([2.0, 6.0, 200.0, 0.5, 3.0])
    last = 13
    worst_i = worst_v = 0.0
    for _ in range(40):
        states = rng.integers(0, 27, 7).astype(np.uint16)
        cuts = np.sort(rng.uniform(0.0, DT, 6))
        seg = np.diff(np.concatenate(([0.0], cuts, [DT])))
        seg[rng.random(7) < 0.2] = 0.0
        seg[-1] = DT - seg[:-1].sum()
        assert lib.ttype_plant_advance_period(s, p, last, ffi.new("uint16_t[7]", list(map(int, states))),
                                              ffi.new("double[7]", list(seg)), 0.5, ffi.NULL, -1.0, ffi.NULL) == 0
        lv = [(int(st) // 9 - 1, (int(st) // 3) % 3 - 1, int(st) % 3 - 1) for st in states]
        before = (last // 9 - 1, (last // 3) % 3 - 1, last % 3 - 1)
        x = plant.period(x, InverterPeriod(before, tuple(zip(map(float, seg), lv))), 0.5)
        last = int(states[np.nonzero(seg > 0.0)[0][-1]])
        got_i = tightref.phase_currents(s.motor.i_d_a, s.motor.i_q_a, s.motor.theta_e_rad)
        ref_i = tightref.phase_currents(x[0], x[1], x[3])
        worst_i = max(worst_i, *(abs(a - b) for a, b in zip(got_i, ref_i)))
        worst_v = max(worst_v, abs(s.vo_v - x[4]))
    assert worst_i < 1e-10 and worst_v < 1e-9, (worst_i, worst_v)
    assert abs(s.vo_v - 3.0) > 0.1  # the neutral point moved


def test_exact_diverged_state_reported(stub):
    """A state the series cannot sum (non-finite) ends the interval as NaN, which the simulator reports
    as a diverged drive (never a frozen state)."""
    from tests.fixtures.plantref import plant_params

    ffi, lib = stub
    p = plant_params(ffi, "sim_params_t", IPMSM)
    p.integrator = 1
    for bad in (math.inf, math.nan, 1e300):
        s = ffi.new("pmsm_state_t *", {"i_d_a": bad, "i_q_a": 1.0, "omega_m_rad_s": 100.0, "theta_e_rad": 0.0})
        assert lib.twolevel_plant_advance(s, p, 4, 0.0, DT, 1) == 0
        assert not math.isfinite(s.i_q_a + s.i_d_a)
