"""controller.psi_ref = "mtpa" and controller.cost = "reference" of the two-level step.

docs/algorithms.md (two-level MPTC) "Flux reference" eq. (M1)-(M3) and "Cost" eq. (C1)-(C2):
the generated C equals the reference bit for bit in float32 and fixed point, the MTPA table
agrees with an independent brute-force minimum-current search, the reference cost is defined
at T* = 0 and across sign changes, and the closed loop settles on the MTPA flux.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from codegen.cli import main
from codegen.config import load_config
from codegen.kernels.consts import Constants
from codegen.model import Model, Motor
from codegen.stages.verify import verify_strategy
from codegen.topologies.twolevel import mtpa
from codegen.topologies.twolevel.derive import T_FLOOR_OF_RATED, cost_bounds, derive_two_level, guard_limits
from codegen.topologies.twolevel.reference import flux_reference, flux_weight, step_batch
from codegen.topology import topology_of

from conftest import check_target_c

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"
VARIANTS = [("mtpa", "rated"), ("constant", "reference"), ("mtpa", "reference")]


def _model(name: str, **fields: object) -> Model:
    over = {f"controller.{k}": v for k, v in fields.items()}
    # s2/s3: the published tables (no training run; the step's arithmetic is what is tested here)
    if fields.get("strategy") in ("s2", "s3"):
        over["controller.tables"] = "published"
    return load_config(EXAMPLES / f"{name}.toml", over)


# ---- bit for bit -------------------------------------------------------------------------------

@pytest.mark.parametrize("number_format", ["float32", "fixed"])
@pytest.mark.parametrize("name", ["seed001_spmsm", "seed001_ipmsm"])
@pytest.mark.parametrize("strategy", ["conventional", "s1", "s2", "s3"])
@pytest.mark.parametrize("psi_ref,cost", VARIANTS)
def test_c_equals_reference_bit_for_bit(name: str, strategy: str, number_format: str, psi_ref: str,
                                        cost: str) -> None:
    m = _model(name, strategy=strategy, number_format=number_format, psi_ref=psi_ref, cost=cost)
    r = verify_strategy(m, 20_000, log=lambda _m: None, closed_loop=(psi_ref, cost) == ("mtpa", "reference"))
    assert r.states == 20_000
    assert r.mismatches == 0, r.as_dict()


@pytest.mark.parametrize("number_format", ["float32", "fixed"])
def test_generated_c_is_strict_clean_on_every_target(tmp_path: Path, number_format: str) -> None:
    """mtpa + reference, s3 (every new statement): gcc strict, Cortex-M7, the C28x text rules and
    (fixed point) the 16-bit-int type model."""
    cfg = str(EXAMPLES / "seed001_ipmsm.toml")
    for target in ("host", "stm32h743", "tms320f28377"):
        out = tmp_path / target
        assert main(["generate", cfg, "--number-format", number_format, "--strategy", "s3", "--tables", "published",
                     "--target", target, "--set", "controller.psi_ref=mtpa", "--set", "controller.cost=reference",
                     "-o", str(out), "-q"]) == 0
        text = next(out.glob("*_mpc.c")).read_text()
        assert "ipmsm_psi_tab[128]" in text and "ipmsm_psi_slope[128]" in text
        check_target_c(out, tmp_path, target, int16_model=number_format == "fixed")


# ---- MTPA flux reference against an independent float64 computation ---------------------------

def _brute_force_flux(m: Motor, torque: float) -> float:
    """psi of the least current giving ``torque``: minimise |i| over the current angle beta
    (i_d = -|i| sin beta, i_q = |i| cos beta), |i| the positive root of
    1.5 p |i| cos b (psi_f + (Lq - Ld) |i| sin b) = torque."""
    if torque == 0.0:
        return m.psi_f_wb
    k, d_l = 1.5 * m.pole_pairs, m.lq_h - m.ld_h

    def current(beta: float) -> float:
        a, b, c = k * d_l * math.sin(beta) * math.cos(beta), k * m.psi_f_wb * math.cos(beta), -torque
        if abs(a) < 1e-15:
            return -c / b
        return (-b + math.sqrt(b * b - 4 * a * c)) / (2 * a)

    lim = 1.2 if d_l >= 0 else -1.2
    grid = np.linspace(0.0, lim, 2001)
    best = grid[int(np.argmin([current(b) for b in grid]))]
    step = abs(grid[1] - grid[0])
    res = minimize_scalar(current, bounds=(best - step, best + step), method="bounded",
                          options={"xatol": 1e-12})
    i = current(res.x)
    i_d, i_q = -i * math.sin(res.x), i * math.cos(res.x)
    return math.hypot(m.psi_f_wb + m.ld_h * i_d, m.lq_h * i_q)


@pytest.mark.parametrize("name", ["seed001_spmsm", "seed001_ipmsm"])
def test_mtpa_flux_matches_brute_force_minimum_current(name: str) -> None:
    m = _model(name).motor
    for torque in (0.0, 0.3, 1.0, 5.0, 12.0, 15.0, 30.0, 60.0, 119.0):
        assert float(mtpa.mtpa_flux(m, torque)) == pytest.approx(_brute_force_flux(m, torque), rel=1e-7, abs=1e-9)
        assert float(mtpa.mtpa_flux(m, -torque)) == float(mtpa.mtpa_flux(m, torque))


def test_mtpa_closed_forms() -> None:
    spm = _model("seed001_spmsm").motor
    ipm = _model("seed001_ipmsm").motor
    t = np.linspace(0.0, 120.0, 97)
    i_d, i_q = mtpa.mtpa_current(spm, t)
    assert np.all(i_d == 0.0)
    np.testing.assert_allclose(i_q, t / (1.5 * spm.pole_pairs * spm.psi_f_wb), rtol=1e-12)
    np.testing.assert_allclose(mtpa.mtpa_flux(spm, t), np.hypot(spm.psi_f_wb, spm.lq_h * i_q), rtol=1e-12)
    i_d, i_q = mtpa.mtpa_current(ipm, 15.0)
    assert float(i_d) == pytest.approx(-3.2408, abs=1e-3) and float(i_q) == pytest.approx(13.926, abs=1e-3)
    assert float(mtpa.mtpa_flux(ipm, 15.0)) == pytest.approx(0.2385, abs=1e-4)  # the spec's value


@pytest.mark.parametrize("number_format", ["float32", "fixed"])
@pytest.mark.parametrize("name", ["seed001_spmsm", "seed001_ipmsm"])
def test_step_psi_ref_follows_mtpa(name: str, number_format: str) -> None:
    """The step's psi* (eq. (M3), through the format's ops) is the float64 MTPA flux up to the
    interpolation error and the format's rounding, over the whole guarded T* range, both signs."""
    m = _model(name, psi_ref="mtpa", number_format=number_format)
    t = derive_two_level(m)
    nf, o, k = t.nf, t.nf.ops, Constants(t.consts)
    t_max = guard_limits(m)["TORQUE_REF_GUARD_NM"]
    tref = np.concatenate([np.linspace(-t_max, t_max, 4001), [0.0, t_max, -t_max]])
    psir, inv = flux_reference(t, o, k, nf.encode("N*m", tref))
    got, got_inv = nf.decode("Wb", psir), nf.decode("1/Wb", inv)
    want = mtpa.mtpa_flux(m.motor, tref)
    err = mtpa.interpolation_error(m.motor, t_max)
    tol = err + (1e-6 if number_format == "float32" else 4 * nf.scaling.resolution("Wb"))
    assert np.max(np.abs(got - want)) <= tol
    inv_tol = 1e-6 if number_format == "float32" else float(np.max(got)) * nf.scaling.resolution("1/Wb")
    assert np.max(np.abs(got_inv * got - 1.0)) <= inv_tol
    assert err < 5e-5


# ---- the reference cost at T* = 0 and across sign changes ---------------------------------------

def _states(m: Model, n: int, seed: int) -> np.ndarray:
    return topology_of(m).random_states(m, derive_two_level(m), n, seed)


@pytest.mark.parametrize("number_format", ["float32", "fixed"])
@pytest.mark.parametrize("psi_ref", ["constant", "mtpa"])
def test_reference_cost_defined_through_zero_torque(psi_ref: str, number_format: str) -> None:
    m = _model("seed001_ipmsm", psi_ref=psi_ref, cost="reference", number_format=number_format)
    t = derive_two_level(m)
    nf, o, k = t.nf, t.nf.ops, Constants(t.consts)
    t_n = m.motor.rated_torque_nm
    tref = np.array([0.0, -0.0, 1e-6, -1e-6, 0.5 * T_FLOOR_OF_RATED * t_n, -T_FLOOR_OF_RATED * t_n, 3.0, -3.0,
                     15.0, -15.0])
    w = nf.decode("", flux_weight(t, o, k, nf.encode("N*m", tref)))
    want = np.maximum(np.abs(tref), T_FLOOR_OF_RATED * t_n) / t_n
    np.testing.assert_allclose(w, want, rtol=1e-5, atol=2 * nf.scaling.resolution("") if nf.scaling else 0.0)
    assert np.all(w[:6] >= T_FLOOR_OF_RATED * (1 - 1e-4))
    assert w[6] == w[7] and w[8] == w[9]  # symmetric in the sign of T*

    # whole steps with T* at zero and either side of it: finite, non-negative costs, every candidate
    x = _states(m, 3000, 7)
    x["torque_ref_nm"] = nf.encode("N*m", np.tile([0.0, -0.0, 0.2, -0.2, 1.0, -1.0], 500))
    out = step_batch(t, x)
    ok = out["fault"] == 0
    assert ok.sum() > 2000
    costs = nf.decode("", out["costs"][ok])
    assert np.all(np.isfinite(costs)) and np.all(costs >= 0)
    assert np.all(out["n_eval"][ok] == 7)


def test_reference_cost_ranks_as_eq5() -> None:
    """(C2) is w^2 times seed eq. (5) squared with T* -> T_n = max(|T*|, T_floor), w = T_n/T_N: the
    candidates' predicted Te and flux error are recovered in float64 from rated costs (C1) at two
    torque references (the predictions do not depend on T*), eq. (5) is evaluated from them, and its
    ranking and values are compared with the step's reference costs (float32, constant psi*)."""
    m = _model("seed001_ipmsm", cost="reference", psi_ref="constant")  # the example itself uses MTPA
    t, rated = derive_two_level(m), derive_two_level(m.with_controller(cost="rated"))
    x = _states(m, 4000, 11)
    t_n, t_a = m.motor.rated_torque_nm, 8.0
    x0, xa = x.copy(), x.copy()
    x0["torque_ref_nm"], xa["torque_ref_nm"] = 0.0, t_a
    c0 = step_batch(rated, x0)["costs"].astype(np.float64)
    ca = step_batch(rated, xa)["costs"].astype(np.float64)
    te = ((c0 - ca) * t_n * t_n + t_a * t_a) / (2 * t_a)  # c0 - ca = (2 Te T_a - T_a^2)/T_N^2
    e_p2 = c0 - (te / t_n) ** 2
    rng = np.random.default_rng(5)
    x["torque_ref_nm"] = np.float32(rng.choice([0.0, 0.1, -0.4, 2.0, -6.0, 15.0], len(x)))
    out = step_batch(t, x)
    ok = out["fault"] == 0
    tref = x["torque_ref_nm"].astype(np.float64)[:, None]
    t_nn = np.maximum(np.abs(tref), T_FLOOR_OF_RATED * t_n)
    eq5 = ((te - tref) / t_nn) ** 2 + e_p2
    g = out["costs"].astype(np.float64)
    w2 = (t_nn / t_n) ** 2
    np.testing.assert_allclose((g / w2)[ok], eq5[ok], rtol=1e-3, atol=2e-3)
    best5 = np.argmin(eq5, axis=1)
    gap = np.sort(eq5, axis=1)[:, 1] - np.sort(eq5, axis=1)[:, 0]
    clear = ok & (gap > 1e-2 * np.sort(eq5, axis=1)[:, 0] + 1e-3)
    assert clear.sum() > 2500
    assert np.array_equal(out["cand"][clear, best5[clear]], out["vector"][clear])


# ---- fixed-point ranges stay honest -------------------------------------------------------------

@pytest.mark.parametrize("name", ["seed001_spmsm", "seed001_ipmsm"])
def test_cost_bound_covers_the_reference_cost(name: str) -> None:
    rated = {s.name: s.max_abs for s in cost_bounds(_model(name))}
    ref = {s.name: s.max_abs for s in cost_bounds(_model(name, cost="reference", psi_ref="mtpa"))}
    assert ref["e_T (cost torque term)"] == rated["e_T (cost torque term)"]
    assert ref["e_psi (cost flux term)"] > rated["e_psi (cost flux term)"]
    m = _model(name, cost="reference", psi_ref="mtpa", number_format="fixed")
    t = derive_two_level(m)
    assert t.scaling.frac_bits >= 18  # the product form (C2) costs at most one fractional bit
    # T* at the guard and at zero, random currents: no cost saturates
    x = _states(m, 4000, 5)
    g = guard_limits(m)["TORQUE_REF_GUARD_NM"]
    x["torque_ref_nm"] = t.nf.encode("N*m", np.tile([g, -g, 0.0, 1e-3], 1000))
    out = step_batch(t, x)
    assert np.all(out["costs"] < np.iinfo(np.int32).max)


# ---- closed loop ------------------------------------------------------------------------------------

def test_closed_loop_ipmsm_settles_on_the_mtpa_flux() -> None:
    """IPMSM example, conventional, 15 N*m load at 1000 r/min: with psi* = 0.3 Wb the drive magnetises
    (i_d about +12 A); with MTPA the plant flux settles near psi*(T*) and i_d is negative (about -3 A)."""
    from codegen.topologies.twolevel.hostbuild import build_host_library
    from codegen.topologies.twolevel.sim import run_closed_loop

    def steady(psi_ref: str) -> tuple[float, float, float]:
        m = load_config(EXAMPLES / "seed001_ipmsm.toml", {
            "controller.psi_ref": psi_ref, "scenario.duration_s": 0.5,
            "scenario.speed_ref_rpm": [[0.0, 1000.0]], "scenario.load_nm": [[0.0, 15.0]]})
        t = derive_two_level(m)
        lib = build_host_library(m, t, with_sim=True)
        tr = run_closed_loop(lib.ffi, lib.lib, m)
        sl = slice(int(0.3 / m.controller.dt_s), int(0.5 / m.controller.dt_s))
        th = np.asarray(tr.theta_e_rad[sl])
        i_alpha = np.asarray(tr.ia_a[sl])
        i_beta = (np.asarray(tr.ia_a[sl]) + 2 * np.asarray(tr.ib_a[sl])) / math.sqrt(3)
        i_d = i_alpha * np.cos(th) + i_beta * np.sin(th)
        psi_star = mtpa.mtpa_flux(m.motor, np.asarray(tr.torque_ref_nm[sl]))
        return float(np.mean(i_d)), float(np.mean(tr.psi_wb[sl])), float(np.mean(psi_star))

    i_d_c, psi_c, _ = steady("constant")
    i_d_m, psi_m, psi_star = steady("mtpa")
    assert i_d_c > 8.0 and psi_c == pytest.approx(0.3, abs=0.01)
    assert -6.0 < i_d_m < -1.0
    assert psi_star == pytest.approx(0.2385, abs=0.005)
    assert psi_m == pytest.approx(psi_star, rel=0.02)
