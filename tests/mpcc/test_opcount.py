"""The cycle bound of the long-horizon step (codegen/mpcc/opcount.py): the decoder's counts of
expansions, terms and children that its multiplicities use, against an independent scalar search,
and the units' counts against what the docs state (docs/mpcc.md "Node budget")."""
from __future__ import annotations

import numpy as np
import pytest

from codegen.errors import MpcgenError
from codegen.mpcc import opcount
from codegen.mpcc.decoder import pattern, search
from codegen.mpcc.reference import problem, solve
from codegen.stages import cycles

from .helpers import mpcc_model, states

F = np.float32


def _scalar_counts(p, ubar, prev, pen):  # type: ignore[no-untyped-def]
    """One state's (nodes, evals, expansions, terms, children, leaf children) by a plain recursive
    depth-first search of eq. (10)-(13): children sorted on (D, digit), entered while D <= rho^2,
    the budget stopping the search before a node past it."""
    nv, nb = p.n_vars, p.base
    held = [int(prev[i % 3]) for i in range(nv)]

    def dist(dg):  # type: ignore[no-untyped-def]
        d = F(0)
        for i in range(nv - 1, -1, -1):
            c = F(ubar[i])
            for j in range(nv - 1, i, -1):
                c = F(c - F(p.h[i, j] * p.lvl[dg[j]]))
            e = F(c - F(p.h[i, i] * p.lvl[dg[i]]))
            d = F(d + F(e * e))
        if pen is not None:
            d = F(d + pen[int(pattern(p, dg[0], dg[1], dg[2]))])
        return d

    st = {"rho2": dist(held), "best": sum(g * nb ** i for i, g in enumerate(held)), "nodes": 0, "evals": 1,
          "exp": 0, "terms": 0, "child": 0, "leafc": 0, "stop": False}
    dg = list(held)

    def visit(lev, dpar):  # type: ignore[no-untyped-def]
        c = F(ubar[lev])
        for j in range(nv - 1, lev, -1):
            c = F(c - F(p.h[lev, j] * p.lvl[dg[j]]))
        kids = []
        for g in range(nb):
            if p.max_step is not None:
                if lev + 3 < nv and abs(g - dg[lev + 3]) > p.max_step:
                    continue
                if lev < 3 and abs(g - int(prev[lev])) > p.max_step:
                    continue
            e = F(c - F(p.h[lev, lev] * p.lvl[g]))
            d = F(dpar + F(e * e))
            if pen is not None and lev == 0:
                d = F(d + pen[int(pattern(p, g, dg[1], dg[2]))])
            kids.append((d, g))
        st["exp"] += 1
        st["terms"] += nv - 1 - lev
        st["child"] += len(kids)
        st["leafc"] += len(kids) if lev == 0 else 0
        for d, g in sorted(kids):
            if st["stop"] or d > st["rho2"]:
                return
            if st["nodes"] >= p.budget:
                st["stop"] = True
                return
            st["nodes"] += 1
            dg[lev] = g
            if lev == 0:
                st["evals"] += 1
                idx = sum(x * nb ** i for i, x in enumerate(dg))
                if d < st["rho2"] or (d == st["rho2"] and idx < st["best"]):
                    st["rho2"], st["best"] = d, idx
            else:
                visit(lev - 1, d)

    visit(nv - 1, F(0))
    return st["nodes"], st["evals"], st["exp"], st["terms"], st["child"], st["leafc"]


@pytest.mark.parametrize("config", ["spmsm", "tlevel"])
@pytest.mark.parametrize("horizon,budget", [(1, None), (2, None), (3, None), (3, 12)])
def test_decoder_counts_equal_a_scalar_search(config: str, horizon: int, budget: int | None):
    over: dict[str, object] = {"horizon": horizon} | ({"node_budget": budget} if budget else {})
    m = mpcc_model(config, **over)
    from codegen.topology import topology_of

    t = topology_of(m).derive(m)
    x = states(m, t, 150, seed=3)
    ok, fr, res = solve(t, x)
    p = problem(t)
    got = np.stack([res.nodes, res.evals, res.expansions, res.terms, res.children, res.leaf_children], 1)
    want = np.array([_scalar_counts(p, fr["ubar"][k], fr["prev"][k], None if fr["pen"] is None else fr["pen"][k])
                     for k in range(len(fr["ubar"]))])
    assert np.array_equal(got, want)
    # the budget binds on some states of the small budget, on none without it only if the tree fits
    if budget:
        assert res.hit.any() and (res.nodes[res.hit] == budget).all()
    # identities the record alone gives: every entered node above level 0 is expanded, once, and so is the root
    assert np.array_equal(res.expansions, 1 + res.nodes - (res.evals - 1))
    if t.max_step is None:  # no jump rule: every digit is a child
        assert np.array_equal(res.children, t.n_levels * res.expansions)


@pytest.mark.parametrize("config", ["spmsm", "tlevel"])
def test_multiplicities_match_the_units(config: str):
    m = mpcc_model(config, node_budget=1000)  # random states: with the default budget most enter all of it
    from codegen.topology import topology_of

    topo = topology_of(m)
    t = topo.derive(m)
    x = states(m, t, 400, seed=5)
    out = topo.step_batch(t, x)
    x, out = x[out["fault"] == 0], out[out["fault"] == 0]
    ops = topo.essential_ops(m, t)
    mult = topo.op_multiplicities(m, t, x, out)
    assert set(ops) - {"per_step", "first_candidate"} == set(mult)  # else op_totals raises
    assert ("per_leaf_child" in ops) == t.neutral_point
    assert np.array_equal(mult["per_candidate"], out["n_eval"]) and np.array_equal(mult["per_node"], out["n_nodes"])
    res = search(problem(t), *(solve(t, x)[1][k] for k in ("ubar", "prev", "pen")))
    assert np.array_equal(mult["per_term"], res.terms) and np.array_equal(mult["per_child"], res.children)
    # the bound grows with the nodes: a state that enters more nodes has at least the other's per-step part
    bound = cycles.model_bound(cycles.op_totals(ops, mult))
    lo, hi = np.argmin(out["n_nodes"]), np.argmax(out["n_nodes"])
    assert out["n_nodes"][hi] > out["n_nodes"][lo] and bound[hi] > bound[lo]
    # a record whose node counts are not the reference's is an error, never a bound
    bad = out.copy()
    bad["n_nodes"][0] += 1
    with pytest.raises(MpcgenError, match="n_nodes"):
        topo.op_multiplicities(m, t, x, bad)


@pytest.mark.parametrize("config,n_levels,neutral", [("spmsm", 2, False), ("tlevel", 3, True)])
@pytest.mark.parametrize("horizon", [1, 3, 5])
def test_unit_counts(config: str, n_levels: int, neutral: bool, horizon: int):
    """The counts the module doc states: the initial guess's distance L (L - 1)/2 terms and 3 operations
    a level (+ the penalty), U_bar 2 (2N) - 1 + 3 operations a row, W1 and W2 read once, the per-node
    and per-child units independent of N, the neutral-point block only with a midpoint."""
    m = mpcc_model(config, horizon=horizon)
    from codegen.topology import topology_of

    t = topology_of(m).derive(m)
    assert t.n_levels == n_levels and t.neutral_point == neutral
    ops = opcount.essential_ops(t)
    L = 3 * horizon
    assert ops["first_candidate"]["mul"] == 0  # float32 only: every FP write counted on "add"
    assert ops["first_candidate"]["add"] == L * (L - 1) // 2 + 3 * L + (1 if neutral else 0)
    assert ops["per_node"] == {"add": 0, "mul": 0, "cmp": 2, "sqrt": 0, "div": 0, "load": 1, "store": 1}
    assert ops["per_child"]["add"] == 3 and ops["per_term"]["add"] == 1
    one = opcount.essential_ops(topology_of(m).derive(mpcc_model(config, horizon=1)))
    # per step: U_bar's rows and the free response grow with N, the rest does not
    assert ops["per_step"]["add"] - one["per_step"]["add"] == (L * (4 * horizon + 2) - 3 * 6) + 12 * (horizon - 1) \
        + 6 * (horizon - 1)
    assert ops["per_step"]["load"] - one["per_step"]["load"] == L * (2 * horizon + 3) - 3 * 5
    assert ops["per_step"]["div"] == 1 and ops["per_step"]["sqrt"] == 1 + (1 if neutral else 0)
    np_fp = opcount.neutral_point_ops(True)["add"]
    assert np_fp == 52 and (("per_leaf_child" in ops) == neutral)
