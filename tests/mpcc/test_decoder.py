"""The generated sphere decoder against the exhaustive search of the same float32 objective
(docs/mpcc.md eq. (10)-(12), with the T-type's neutral-point penalty eq. (14)), the one-step
enumeration (N = 1), the jump rule and the node budget."""
from __future__ import annotations

import itertools
import math
from dataclasses import replace

import numpy as np
import pytest

from codegen.mpcc.decoder import distance, exhaustive
from codegen.mpcc.lattice import CLARKE, discretise
from codegen.mpcc.reference import prev_digits, problem

from .helpers import built, mpcc_model, penalties, sequence_digits, sequence_index, states

#: states per exhaustive comparison (those failing the guard are left out: about 6 %)
N_EXHAUSTIVE = 110_000
#: the largest budget: more than the whole search tree of every case below (two-level N = 4: 8190
#: nodes; T-type N = 3: fewer than 3^1 + ... + 3^9 = 29523), so it never binds
UNLIMITED = 65535


@pytest.mark.parametrize("config, horizon, lambda_vo", [
    ("spmsm", 1, None), ("spmsm", 2, None), ("spmsm", 3, None), ("spmsm", 4, None),
    ("tlevel", 1, None), ("tlevel", 2, None), ("tlevel", 3, None), ("tlevel", 2, 1000.0)])
def test_decoder_equals_the_exhaustive_optimum(config: str, horizon: int, lambda_vo: float | None):
    """The C's sequence and distance are the exhaustive search's (lowest distance, then lowest index),
    bit for bit, on >= 10^5 states passing the guard; the budget never binds here.  T-type: the
    distance includes the neutral-point penalty of the first period (eq. (14), the example's weight
    and a weight where it dominates), and the penalty changes the optimum on some states."""
    extra = {} if lambda_vo is None else {"lambda_vo_a2_per_v2": lambda_vo}
    m = mpcc_model(config, horizon=horizon, node_budget=UNLIMITED, **extra)
    _, t, lib = built(m)
    x = states(m, t, N_EXHAUSTIVE)
    out = lib.step_batch(x)
    ok = out["fault"] == 0
    assert ok.sum() >= 100_000
    assert not out["budget_hit"][ok].any()
    y = out[ok]
    pen = penalties(t, x)
    assert (pen is not None) == (config == "tlevel")
    prev = prev_digits(t, x[t.adapter.prev_field][ok])
    best, cost = exhaustive(problem(t), y["ubar"], prev, pen)
    assert np.array_equal(sequence_index(y["seq"], t.n_levels), best)
    assert np.array_equal(y["cost_best"].view(np.uint32), cost.view(np.uint32))
    if pen is not None:
        assert np.all(pen >= 0) and np.any(pen > 0)
        plain, _ = exhaustive(replace(problem(t), mid=None), y["ubar"], prev)
        moved = np.mean(plain != best)
        assert 1e-3 < moved < (0.9 if lambda_vo else 0.5)


def _one_step_costs(m, x, levels: tuple[int, ...], jump: int | None) -> tuple[np.ndarray, np.ndarray]:
    """Float64 one-step enumeration straight from the model (docs/mpcc.md eq. (1)), horizon 1 with the
    delay compensated: (candidate states (S, 3) positions, costs (n, S)) of J(u) = ||i*(k+2) - i(k+2)||^2
    + lambda_u (Udc/udc_v)^2 ||u - u_prev||^2 (the weight is defined at the nominal DC link, eq. (3)),
    T-type + lambda_vo V_o(k+2)^2 (eq. (14): V_o(k+1) = (uc1 - uc2)/2 + Ts/(2C) i_o(u_prev; i(k)),
    V_o(k+2) = V_o(k+1) + Ts/(2C) i_o(u; i(k+1)), i_o the sum of the currents of the phases at 0),
    infeasible candidates (jump rule) at +inf."""
    mo, c = m.motor, m.controller
    a, b = discretise(mo.rs_ohm, mo.ld_h, c.dt_s)
    th = x["theta_e_rad"].astype(np.float64)
    om = x["omega_e_rad_s"].astype(np.float64)
    ia = x["ia_a"].astype(np.float64)
    ib = x["ib_a"].astype(np.float64)
    i0 = np.stack([ia, (ia + 2.0 * ib) / math.sqrt(3.0)], axis=1)
    udc = sum(x[f].astype(np.float64) for f in (("udc_v",) if "udc_v" in x.dtype.names else ("uc1_v", "uc2_v")))
    g = 0.5 * udc
    prev_name = "prev_sw" if "prev_sw" in x.dtype.names else "prev_vector"
    base = len(levels)
    pv = np.array(levels)[np.stack([(x[prev_name] // (base * base)) % base, (x[prev_name] // base) % base,
                                    x[prev_name] % base], axis=1)].astype(np.float64)

    def emf(k: int) -> np.ndarray:
        t = th + k * om * c.dt_s
        return (om * mo.psi_f_wb)[:, None] * np.stack([-np.sin(t), np.cos(t)], axis=1)

    x1 = a * i0 + (b * g)[:, None] * (pv @ CLARKE.T) - b * emf(0)
    free = a * x1 - b * emf(1)
    t2 = th + 2 * om * c.dt_s
    iq = x["torque_ref_nm"].astype(np.float64) / (1.5 * mo.pole_pairs * mo.psi_f_wb)
    iref = iq[:, None] * np.stack([-np.sin(t2), np.cos(t2)], axis=1)
    cands = np.array(list(itertools.product(levels, repeat=3)), np.float64)
    i2 = free[:, None, :] + (b * g)[:, None, None] * (cands @ CLARKE.T)[None, :, :]
    du = cands[None, :, :] - pv[:, None, :]
    lam = c.lambda_u * (udc / m.inverter.udc_v) ** 2
    cost = ((iref[:, None, :] - i2) ** 2).sum(axis=2) + lam[:, None] * (du ** 2).sum(axis=2)
    if "uc1_v" in x.dtype.names:  # the neutral-point term, eq. (14)
        k_vo = c.dt_s / (2.0 * m.inverter.c_f)
        ph0 = np.stack([ia, ib, -(ia + ib)], axis=1)
        vo1 = 0.5 * (x["uc1_v"].astype(np.float64) - x["uc2_v"].astype(np.float64)) \
            + k_vo * np.where(pv == 0.0, ph0, 0.0).sum(axis=1)
        b1 = 0.5 * math.sqrt(3.0) * x1[:, 1] - 0.5 * x1[:, 0]
        ph1 = np.stack([x1[:, 0], b1, -(x1[:, 0] + b1)], axis=1)
        io = ph1 @ (cands == 0.0).T.astype(np.float64)
        cost = cost + c.lambda_vo_a2_per_v2 * (vo1[:, None] + k_vo * io) ** 2
    if jump is not None:
        cost = np.where((np.abs(du) <= jump).all(axis=2), cost, np.inf)
    return cands, cost


@pytest.mark.parametrize("config, extra", [("spmsm", {}), ("tlevel", {}), ("tlevel", {"lambda_vo_a2_per_v2": 1000.0})])
def test_horizon_one_is_the_one_step_enumeration(config: str, extra: dict[str, float]):
    """N = 1, unlimited budget: the decision is the float64 one-step enumeration's optimum on every
    state whose two best candidates are more than 1e-6 (relative) apart, and on every state the chosen
    candidate's float64 cost is within that of the optimum (float32 rounding of a near tie); the
    T-type's cost with its neutral-point term at the example's weight and at one where it dominates."""
    m = mpcc_model(config, horizon=1, node_budget=UNLIMITED, **extra)
    _, t, lib = built(m)
    x = states(m, t, 50_000)
    out = lib.step_batch(x)
    ok = out["fault"] == 0
    x, y = x[ok], out[ok]
    _, cost = _one_step_costs(m, x, t.adapter.levels, t.max_step)
    ordered = np.sort(cost, axis=1)
    best = np.argmin(cost, axis=1)
    chosen = y["seq"].astype(np.int64)  # N = 1: one state
    scale = 1.0 + ordered[:, 0]
    clear = (ordered[:, 1] - ordered[:, 0]) > 1e-6 * scale
    assert clear.sum() > 0.99 * len(x)
    assert np.array_equal(chosen[clear], best[clear])
    picked = cost[np.arange(len(x)), chosen]
    assert np.all(picked - ordered[:, 0] <= 1e-6 * scale)


def test_ttype_never_jumps_between_n_and_p():
    """Every chosen T-type sequence moves each phase by at most one level per period, the applied
    position included, whether or not the budget bound (default budget, horizon 3 and 5)."""
    for horizon in (3, 5):
        m = mpcc_model("tlevel", horizon=horizon)
        _, t, lib = built(m)
        x = states(m, t, 60_000, seed=4)
        out = lib.step_batch(x)
        ok = out["fault"] == 0
        assert out["budget_hit"][ok].any() and not out["budget_hit"][ok].all()
        d = sequence_digits(out["seq"][ok], 3).reshape(-1, horizon, 3)
        prev = prev_digits(t, x["prev_vector"][ok])
        path = np.concatenate([prev[:, None, :], d], axis=1)
        assert np.abs(np.diff(path, axis=1)).max() <= 1


@pytest.mark.parametrize("config", ["spmsm", "tlevel"])
def test_budget_events_counted_and_best_so_far_applied(config: str):
    """With a budget that binds: n_nodes == budget and budget_hit == 1 exactly where the search was cut;
    the applied sequence's distance is cost_best (its own eq. (11)), never below the optimum, never
    above that of a smaller budget; a budget below one dive (3N nodes) applies the initial guess, the
    applied state held over the horizon."""
    horizon = 3
    x = None
    costs = {}
    for budget in (5, 20, 60, UNLIMITED):
        m = mpcc_model(config, horizon=horizon, node_budget=budget)
        _, t, lib = built(m)
        if x is None:
            x = states(m, t, 30_000, seed=9)
        out = lib.step_batch(x)
        ok = out["fault"] == 0
        y = out[ok]
        hit = y["budget_hit"] == 1
        assert np.all(y["n_nodes"][hit] == budget) and np.all(y["n_nodes"][~hit] <= budget)
        digits = sequence_digits(y["seq"], t.n_levels)
        own = distance(problem(t), y["ubar"], digits, penalties(t, x))
        assert np.array_equal(own.view(np.uint32), y["cost_best"].view(np.uint32))
        costs[budget] = y["cost_best"]
        prev = prev_digits(t, x[t.adapter.prev_field][ok])
        if budget < 3 * horizon:
            assert hit.all()
            assert np.array_equal(digits, np.tile(prev, (1, horizon)))
        if budget == UNLIMITED:
            assert not hit.any()
        else:
            assert hit.any()
    assert np.all(costs[5] >= costs[20]) and np.all(costs[20] >= costs[60]) and np.all(costs[60] >= costs[UNLIMITED])
    assert np.any(costs[60] > costs[UNLIMITED])
