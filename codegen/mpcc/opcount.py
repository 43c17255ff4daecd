"""Essential operations of the long-horizon step (docs/mpcc.md), counted from its algorithm
(``reference.py``, ``decoder.py``), for the cycle lower bounds of ``mpcgen bench --emulated``
(``codegen.stages.cycles.op_totals``, ``model_bound``, ``overlap_bound``); shared by every topology.

Counts, not measurements: the FP operations that write a register, the compares and branches,
square roots, divisions, loads and stores the algorithm cannot do without.  The units:

- ``per_step``: the guard, two sin/cos, Clarke, g b and its inverse (the one division), the angles
  by rotation (6 per angle), the delay compensation, the estimates (one square root), the free
  response and r' (12 per period), U_bar (eq. (5): per row 2N products and sums of W1 r', the
  three W2 u_prev terms one sum each: a position is -1, 0 or 1, its product a sign, exact), with a
  DC-link midpoint the neutral-point block (eq. (14): V_o, the phase currents of z, the 8 patterns'
  charge sums, V_o(k+2), its normalisation, square and weight; a pattern without a midpoint phase
  adds no charge), the sequence's states and the topology's decision (``Adapter.decision_ops``);
- ``first_candidate``: the initial guess's whole distance (eq. (10)-(11): L (L - 1)/2 terms, 3
  operations a level; with a midpoint, + its penalty);
- ``per_candidate`` (``n_eval``, the initial guess and every leaf): the compare with the best;
- ``per_node`` (``n_nodes``): the radius test and the budget test, the child's distance read,
  its digit kept on the path;
- ``per_expansion`` (the root and every entered node above level 0): U_bar_i and H_ii read;
- ``per_term`` (the terms H_ij u_j of eq. (10) over the expansions, L - 1 - i at level i): one
  sum and the load of H_ij (the product by a position is a sign);
- ``per_child`` (every allowed digit of an expansion): e = c - H_ii u, e^2, D (eq. (11)), its place
  in the sorted children (a compare) and its store;
- ``per_leaf_child`` (with a midpoint: the children at level 0): + P(m) (eq. (14)), its load.

The multiplicities (:func:`multiplicities`) are the output record's ``n_eval`` and ``n_nodes`` and
the reference decoder's counts of expansions, terms and children (``decoder.Result``), checked
against the record.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from codegen.errors import MpcgenError
from codegen.kernels.guard import guard_ops
from codegen.kernels.trig import SINCOS_TABLE_LOADS, sincos_ops
from codegen.mpcc.tables import MpccTables

__all__ = ["essential_ops", "multiplicities", "neutral_point_ops"]

_KEYS = ("add", "mul", "cmp", "sqrt", "div", "load", "store")


def _ops(fp: int = 0, **counts: int) -> dict[str, int]:
    """Counts in the bound's keys.  The long-horizon step runs in float32 only (fixed point is refused
    at load), where a sum and a product cost the same: every FP operation that writes a register is
    counted here as ``fp`` and lands on ``add``; the add/mul split matters to fixed-point costs only."""
    return {k: int(counts.get(k, 0)) + (fp if k == "add" else 0) for k in _KEYS}


def neutral_point_ops(delay: bool) -> dict[str, int]:
    """The neutral-point block of eq. (14), per step: V_o = (uc1 - uc2)/2 (2); with delay compensation
    the third sampled phase current and V_o(k+1) = V_o + Ts/(2C) i_o(u_prev) (1 + 2, the pattern's
    sum at least nothing); the phase currents of z (i_b: 3, i_c: 1); per pattern m the charge sum
    (|m| - 1 additions: 5 over the 8 patterns), V_o(k+2) = V_o + Ts/(2C) i_o (2; pattern 0 none:
    i_o = 0), the normalisation, the square and the weight (3): 5 + 14 + 24; the 8 penalties kept,
    V_o(k+1) stored; 4 constants read."""
    fp = 2 + (3 if delay else 0) + 3 + 1 + 5 + 2 * 7 + 3 * 8
    return _ops(fp=fp, load=4, store=8 + 1)


def essential_ops(t: MpccTables) -> dict[str, dict[str, int]]:
    """``{"per_step", "first_candidate", "per_candidate", "per_node", "per_expansion", "per_term",
    "per_child"}`` (and ``"per_leaf_child"`` with a DC-link midpoint), counts with keys ``add``,
    ``mul``, ``cmp``, ``sqrt``, ``div``, ``load``, ``store`` (every FP write on ``add``: :func:`_ops`)."""
    a = t.adapter
    n, nv, d = t.horizon, t.n_vars, t.delay
    sincos, sincos_consts = sincos_ops(t.nf)
    sincos_fp = sincos["add"] + sincos["mul"]
    guard = guard_ops(a.guard)
    fp = guard["add"] + 1 + 2 * sincos_fp + 3  # guard, omega_e Ts, two sin/cos, Clarke
    fp += len(a.udc_fields) - 1 + 3  # Udc, g b, w, i_q*
    fp += 6 * (n + d)  # theta_1 .. theta_{N+d} by rotation
    fp += 18 if d else 0  # z = a i + g b K u_prev - b e(theta_0)
    fp += 3 + 3 + 3 + 1 + 3  # i_q(k+d), psi alpha, psi beta, Te, |psi|^2
    fp += 12 * n  # free response (6), r_alpha, r_beta (2 + 2), r' (2) per period
    fp += nv * (2 * (2 * n) - 1 + 3)  # U_bar = W1 r' + W2 u_prev, each row
    n_inputs = 5 + len(a.udc_fields) + 1  # currents, angle, speed, torque reference; DC link; applied state
    n_consts = 12 + len(guard_limit_names(a)) + 1 + sincos_consts  # step constants, guard limits, 1/sqrt3
    load = n_inputs + n_consts + 2 * SINCOS_TABLE_LOADS + 3 + nv * (2 * n + 3)  # + the 3 positions, W1, W2
    store = 6 + nv + n + 1 + 3 + 2  # estimates, U_bar, seq, cost_best, the counters, fault, gates_off
    per_step = _ops(fp=fp, cmp=guard["cmp"], sqrt=1, div=1, load=load, store=store)
    if t.neutral_point:
        np_ops = neutral_point_ops(bool(d))
        per_step = {k: per_step[k] + np_ops[k] for k in _KEYS}
    extra = dict(a.decision_ops)
    per_step = {k: per_step[k] + extra.get(k, 0) for k in _KEYS}
    n_terms = nv * (nv - 1) // 2
    first = _ops(fp=n_terms + 3 * nv + (1 if t.neutral_point else 0), cmp=0,
                 load=n_terms + 2 * nv + (1 if t.neutral_point else 0))
    ops = {
        "per_step": per_step,
        "first_candidate": first,
        "per_candidate": _ops(cmp=1),
        "per_node": _ops(cmp=2, load=1, store=1),
        "per_expansion": _ops(load=2),
        "per_term": _ops(fp=1, load=1),
        "per_child": _ops(fp=3, cmp=1, store=1),
    }
    if t.neutral_point:
        ops["per_leaf_child"] = _ops(fp=1, load=1)
    return ops


def guard_limit_names(a: Any) -> tuple[str, ...]:
    """The constants the guard compares with (one load each)."""
    names: list[str] = []
    for c in a.guard:
        for attr in ("limit", "lo", "hi"):
            v = getattr(c, attr, None)
            if isinstance(v, str) and v and v not in names:
                names.append(v)
    return tuple(names)


def multiplicities(t: MpccTables, states: np.ndarray, expected: np.ndarray) -> dict[str, np.ndarray]:
    """Per state of ``states`` (input records; ``expected`` their output records), how many times each
    unit of :func:`essential_ops` other than ``per_step`` runs: ``n_eval``, ``n_nodes`` from the
    record, the expansions, terms and children from the reference decoder (its node and leaf counts
    must be the record's: a MpcgenError otherwise).  A state the guard stops runs none of them."""
    from codegen.mpcc.reference import solve

    ok, _front, res = solve(t, states)
    n = len(states)
    counts = {}
    for name, v in (("per_expansion", res.expansions), ("per_term", res.terms), ("per_child", res.children),
                    ("per_leaf_child", res.leaf_children)):
        full = np.zeros(n, np.int64)
        assert v is not None
        full[ok] = v
        counts[name] = full
    nodes = np.zeros(n, np.int64)
    nodes[ok] = res.nodes
    if not np.array_equal(nodes, expected["n_nodes"].astype(np.int64)):
        raise MpcgenError("the reference decoder's node counts differ from the output records' n_nodes")
    mult = {"per_candidate": expected["n_eval"].astype(np.int64), "per_node": nodes, **counts}
    if not t.neutral_point:
        del mult["per_leaf_child"]
    return mult
