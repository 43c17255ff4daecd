"""The sphere decoder of docs/mpcc.md eq. (10)-(13), vectorised over lanes, and the exhaustive search.

Both minimise the same float32 objective over sequences U of positions (digits d_i, position
``lvl[d_i]``), the lattice distance accumulated layer by layer from the last row of H::

    c_i = U_bar_i - sum_{j = L-1 .. i+1} H_ij u_j        (in that order, one rounding per operation)  (10)
    D_i = D_{i+1} + (c_i - H_ii u_i)^2,   D_L = 0,   distance = D_0                                   (11)

with the tie-break of the lowest index idx(U) = sum_i d_i B^i (B = |alphabet|).  With a neutral-point
penalty (``Problem.mid``, docs/mpcc.md eq. (14)) the distance of a whole sequence is D_0 + P(u_0): the
lane's float32 penalty ``pen[m]`` of the pattern m = 4 [u_0a = 0] + 2 [u_0b = 0] + [u_0c = 0] of the
first period's positions, added once after the last term of (11), at level 0 (every leaf, the initial
guess and :func:`exhaustive` alike).  P >= 0, so the partial distances stay a lower bound of every
leaf below them and the search stays exact.  The jump rule
(``max_step``): |d(l, p) - d(l+1, p)| <= max_step for consecutive periods, and against the applied
position for l = 0 (variable i = 3 l + p).

:func:`search` is the depth-first search of the generated C (templates/mpcc/mpc.c.j2, ``_search``),
one lane per state, each with its own explicit stack; the loop runs while any lane is active, one C
loop iteration per lane per pass:

* initial guess: the applied positions held over the horizon, its distance (11) the radius rho^2
  and its index the best so far;
* a node at level i is entered when its partial distance D_i <= rho^2 (children of a node visited in
  increasing D_i, ties in digit order); entering a node counts it (``nodes``), and when ``nodes``
  has reached the budget the search stops (``hit``) with the best so far;
* a leaf (i = 0) replaces the best when D_0 < rho^2, or D_0 == rho^2 and its index is lower.

:func:`exhaustive` evaluates (10)-(11) for every feasible sequence and takes the lowest (D_0, idx):
where the budget did not bind, the two agree bit for bit.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["Problem", "Result", "search", "exhaustive", "distance", "pattern"]

F = np.float32


@dataclass(frozen=True)
class Problem:
    """A lattice problem's constants: H (L x L, float32, upper triangular), the positions ``lvl``
    (float32, digit order), the horizon, the jump rule and the node budget."""

    h: np.ndarray
    lvl: np.ndarray
    horizon: int
    max_step: int | None
    budget: int
    mid: int | None = None  # the digit of position 0 when the neutral-point penalty applies, eq. (14)

    @property
    def n_vars(self) -> int:
        return 3 * self.horizon

    @property
    def base(self) -> int:
        return len(self.lvl)


@dataclass(frozen=True)
class Result:
    """Per lane: the best sequence's index, its distance, nodes entered, leaves evaluated (with the
    initial guess), whether the budget stopped the search; and what the expansions did, for the cycle
    bound's multiplicities (``codegen.mpcc.opcount``): nodes expanded (the root and every entered
    node above level 0), terms H_ij u_j of eq. (10) over them, children whose distance (11) was
    computed (the allowed digits), and of those the children at level 0 (the leaves' candidates)."""

    best: np.ndarray  # int64
    cost: np.ndarray  # float32
    nodes: np.ndarray  # int64
    evals: np.ndarray  # int64
    hit: np.ndarray  # bool
    expansions: np.ndarray | None = None  # int64
    terms: np.ndarray | None = None  # int64
    children: np.ndarray | None = None  # int64
    leaf_children: np.ndarray | None = None  # int64


def digits_of(index: np.ndarray, base: int, n_vars: int) -> np.ndarray:
    """(n, L) digits of sequence indices (digit i has place value base^i)."""
    return (np.asarray(index, np.int64)[:, None] // base ** np.arange(n_vars, dtype=np.int64)) % base


def pattern(p: Problem, d0: Any, d1: Any, d2: Any) -> np.ndarray:
    """The midpoint pattern m = 4 [d0 = mid] + 2 [d1 = mid] + [d2 = mid] of first-period digits."""
    return 4 * (np.asarray(d0) == p.mid) + 2 * (np.asarray(d1) == p.mid) + (np.asarray(d2) == p.mid)


def _checked(p: Problem, pen: np.ndarray | None) -> np.ndarray | None:
    """``pen``, given exactly when the problem has a neutral-point penalty."""
    if (p.mid is None) != (pen is None):
        raise ValueError("a neutral-point problem needs its penalties, and only it")
    return pen


def distance(p: Problem, ubar: np.ndarray, digits: np.ndarray, pen: np.ndarray | None = None) -> np.ndarray:
    """Eq. (10)-(11) for one sequence per lane (``digits`` (n, L)), in the decoder's order, and the
    neutral-point penalty ``pen`` (n, 8) of its first period (eq. (14)) when the problem has one."""
    h, lvl, n_vars = p.h, p.lvl, p.n_vars
    d = np.zeros(len(ubar), F)
    for i in range(n_vars - 1, -1, -1):
        c = ubar[:, i]
        for j in range(n_vars - 1, i, -1):
            c = c - h[i, j] * lvl[digits[:, j]]
        e = c - h[i, i] * lvl[digits[:, i]]
        d = d + e * e
    pen = _checked(p, pen)
    if pen is not None:
        d = d + pen[np.arange(len(d)), pattern(p, digits[:, 0], digits[:, 1], digits[:, 2])]
    return d


def held_digits(prev: np.ndarray, horizon: int) -> np.ndarray:
    """(n, 3N) digits of the applied positions ``prev`` (n, 3) held over the horizon."""
    return np.tile(np.asarray(prev, np.int64), (1, horizon))


def search(p: Problem, ubar: np.ndarray, prev: np.ndarray, pen: np.ndarray | None = None) -> Result:
    """The depth-first sphere decoder on every lane (``ubar`` (n, L) float32, ``prev`` (n, 3) digits,
    ``pen`` (n, 8) float32 the neutral-point penalties of eq. (14) when the problem has them)."""
    n, nv, nb = len(ubar), p.n_vars, p.base
    pens = _checked(p, pen)
    pw = nb ** np.arange(nv, dtype=np.int64)
    held = held_digits(prev, p.horizon)
    best = held @ pw
    rho2 = distance(p, ubar, held, pen)
    dg = held.copy()
    dpar = np.zeros((n, nv + 1), F)
    ipar = np.zeros((n, nv + 1), np.int64)
    cv = np.zeros((n, nv, nb), F)
    cdg = np.zeros((n, nv, nb), np.int64)
    nch = np.zeros((n, nv), np.int64)
    pos = np.zeros((n, nv), np.int64)
    lev = np.full(n, nv - 1, np.int64)
    nodes = np.zeros(n, np.int64)
    evals = np.ones(n, np.int64)
    hit = np.zeros(n, bool)
    active = np.ones(n, bool)
    prev = np.asarray(prev, np.int64)
    n_exp, n_terms, n_child, n_leaf_child = (np.zeros(n, np.int64) for _ in range(4))

    def expand(lanes: np.ndarray) -> None:
        """Children of each lane's node at its level ``lev``, sorted by (D, digit)."""
        lv = lev[lanes]
        c = ubar[lanes, lv]
        for j in range(nv - 1, 0, -1):
            c = np.where(j > lv, c - p.h[lv, j] * p.lvl[dg[lanes, j]], c)
        hd, dp = p.h[lv, lv], dpar[lanes, lv + 1]
        ds = np.empty((len(lanes), nb), F)
        ok = np.ones((len(lanes), nb), bool)
        for g in range(nb):
            e = c - hd * p.lvl[g]
            ds[:, g] = dp + e * e
            if pens is not None:  # a leaf: the first period's penalty after the last term (eq. (14))
                m = pattern(p, g, dg[lanes, 1], dg[lanes, 2])
                ds[:, g] = np.where(lv == 0, ds[:, g] + pens[lanes, m], ds[:, g])
            if p.max_step is not None:
                nxt = dg[lanes, np.minimum(lv + 3, nv - 1)]
                first = prev[lanes, lv % 3]
                ok[:, g] = (((lv // 3) + 1 >= p.horizon) | (np.abs(g - nxt) <= p.max_step)) \
                    & ((lv // 3 > 0) | (np.abs(g - first) <= p.max_step))
        rank = np.zeros((len(lanes), nb), np.int64)
        for g in range(nb):
            for o in range(nb):
                if o != g:
                    rank[:, g] += ok[:, o] & ((ds[:, o] < ds[:, g]) | ((ds[:, o] == ds[:, g]) & (o < g)))
        for g in range(nb):
            sel = ok[:, g]
            cv[lanes[sel], lv[sel], rank[sel, g]] = ds[sel, g]
            cdg[lanes[sel], lv[sel], rank[sel, g]] = g
        nch[lanes, lv] = ok.sum(axis=1)
        pos[lanes, lv] = 0
        n_exp[lanes] += 1
        n_terms[lanes] += nv - 1 - lv
        n_child[lanes] += nch[lanes, lv]
        n_leaf_child[lanes] += np.where(lv == 0, nch[lanes, lv], 0)

    expand(np.arange(n))
    while True:
        a = np.flatnonzero(active)
        if not len(a):
            break
        lv = lev[a]
        j = pos[a, lv]
        d = cv[a, lv, np.minimum(j, nb - 1)]
        go = (j < nch[a, lv]) & (d <= rho2[a])
        over = go & (nodes[a] >= p.budget)
        hit[a[over]] = True
        active[a[over]] = False
        enter = go & ~over
        e, lve, je, de = a[enter], lv[enter], j[enter], d[enter]
        nodes[e] += 1
        pos[e, lve] = je + 1
        g = cdg[e, lve, je]
        dg[e, lve] = g
        ipar[e, lve] = ipar[e, lve + 1] + g * pw[lve]
        leaf = lve == 0
        lf, dl = e[leaf], de[leaf]
        evals[lf] += 1
        better = (dl < rho2[lf]) | ((dl == rho2[lf]) & (ipar[lf, 0] < best[lf]))
        rho2[lf[better]] = dl[better]
        best[lf[better]] = ipar[lf[better], 0]
        inner = e[~leaf]
        dpar[inner, lve[~leaf]] = de[~leaf]
        lev[inner] = lve[~leaf] - 1
        if len(inner):
            expand(inner)
        back = a[~go]
        top = lev[back] == nv - 1
        active[back[top]] = False
        lev[back[~top]] += 1
    return Result(best, rho2, nodes, evals, hit, n_exp, n_terms, n_child, n_leaf_child)


def exhaustive(p: Problem, ubar: np.ndarray, prev: np.ndarray, pen: np.ndarray | None = None,
               chunk: int = 512) -> tuple[np.ndarray, np.ndarray]:
    """(index, distance) of the lowest (D_0, idx) over every feasible sequence, eq. (10)-(11) in the
    decoder's order, plus the neutral-point penalty of the first period (eq. (14)) when the problem
    has one: the partial sums of the sequences sharing their last digits are shared (axes ordered
    u_{L-1}, ..., u_i, so the flat index of the final array is idx)."""
    best = np.zeros(len(ubar), np.int64)
    cost = np.zeros(len(ubar), F)
    pen = _checked(p, pen)
    for lo in range(0, len(ubar), chunk):
        b, c = _exhaustive_chunk(p, ubar[lo:lo + chunk], np.asarray(prev[lo:lo + chunk], np.int64),
                                 None if pen is None else pen[lo:lo + chunk])
        best[lo:lo + chunk], cost[lo:lo + chunk] = b, c
    return best, cost


def _exhaustive_chunk(p: Problem, ubar: np.ndarray, prev: np.ndarray,
                      pen: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    n, nv, nb = len(ubar), p.n_vars, p.base
    digits = np.arange(nb)
    d = np.zeros((n,), F)
    feasible = np.ones((n,), bool)
    for i in range(nv - 1, -1, -1):
        c = ubar[:, i]
        for j in range(nv - 1, i, -1):
            c = c[..., None] - p.h[i, j] * p.lvl  # axis for u_j
        e = c[..., None] - p.h[i, i] * p.lvl  # axis for u_i
        d = d[..., None] + e * e
        ok = np.ones(d.shape, bool)
        if p.max_step is not None:
            shape = (1,) * (d.ndim - 1) + (nb,)
            gi = digits.reshape(shape)
            if i // 3 + 1 < p.horizon:  # the same phase one period later: axis of u_{i+3}
                axis = d.ndim - 1 - 3
                gn = digits.reshape((1,) * axis + (nb,) + (1,) * (d.ndim - 1 - axis))
                ok &= np.abs(gi - gn) <= p.max_step
            if i < 3:
                first = prev[:, i].reshape((n,) + (1,) * (d.ndim - 1))
                ok &= np.abs(gi - first) <= p.max_step
        feasible = feasible[..., None] & ok
    if pen is not None:  # the last three axes are u_2, u_1, u_0: each first period's pattern, eq. (14)
        g = np.arange(nb)
        m = pattern(p, g[None, None, :], g[None, :, None], g[:, None, None])  # [d2, d1, d0]
        d = d + pen[:, m].reshape((n,) + (1,) * (d.ndim - 4) + (nb, nb, nb))
    flat_d = d.reshape(n, -1)
    flat_ok = feasible.reshape(n, -1)
    masked = np.where(flat_ok, flat_d, F(np.inf))
    best = np.argmin(masked, axis=1)
    return best.astype(np.int64), flat_d[np.arange(n), best]
