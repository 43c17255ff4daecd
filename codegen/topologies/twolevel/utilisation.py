"""Vector utilisation statistics and switch-table derivation (seed 001).

The seed builds the candidate sets of its simplified strategies s2 and s3 by
hand from the vector utilisation of the conventional controller, eq. (6)
``eta_Vi = N_i / N * 100 %``, tabulated per flux sector (Tables 3-4 for the
6 sectors of eq. (11), Tables 5-8 for the 12 sectors of eq. (12)).  This
module automates that step (spec "Deriving switch tables from utilisation"):

1. :func:`count_utilisation` counts, per condition and sector, how often each
   vector was chosen, only over samples with ``|dT| > eps_T``.
2. :func:`select_vectors` applies the rule to one cell: keep V0, then add
   active vectors in decreasing utilisation until they cover at least
   ``coverage`` of the active-vector choices of the cell, at most
   ``max_active`` of them.  :func:`derive_table` applies it to every cell.
3. :func:`format_utilisation` / :func:`format_switch_table` print the tables
   in the seed's layout; :func:`compare_tables` / :func:`format_comparison`
   check a derived table against a published one.

Array layout: counts and percentages are ``(n_conditions, n_sectors, 7)``
(last axis = vector V0..V6); switch tables and condition indices follow
:mod:`codegen.topologies.twolevel.published`.
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import Literal, NamedTuple

import numpy as np

from codegen.topologies.twolevel import published as pub
from codegen.topologies.twolevel.published import Cell, SwitchTable

TableKind = Literal["s2", "s3"]

N_VECTORS = 7
DEFAULT_COVERAGE = 0.90
DEFAULT_MAX_ACTIVE = 3

# Condition labels in condition-index order (see published.py).
CONDITION_LABELS: dict[str, tuple[str, ...]] = {
    "s2": ("dT>0", "dT<0"),
    "s3": ("dT>0,dpsi>0", "dT>0,dpsi<=0", "dT<0,dpsi>0", "dT<0,dpsi<=0"),
}
N_SECTORS: dict[str, int] = {"s2": 6, "s3": 12}

# Relative slack on the coverage test, so that percentages printed with two
# decimals (whose sums are off by ~1e-15 in binary) do not flip a decision.
_COVERAGE_RTOL = 1e-12


class NoUtilisationData(ValueError):
    """A cell has no active-vector choices, so the rule cannot pick anything."""


class ComparisonRow(NamedTuple):
    """One cell of :func:`compare_tables` (sector is 0-based)."""

    condition: int
    sector: int
    derived: Cell
    published: Cell
    equal: bool


def _check_rule_parameters(coverage: float, max_active: int) -> None:
    if not 0.0 < coverage <= 1.0:
        raise ValueError(f"coverage must be in (0, 1], got {coverage!r}")
    if not 1 <= max_active <= 6:
        raise ValueError(f"max_active must be in 1..6, got {max_active!r}")


def select_vectors(
    active_share: Sequence[float],
    coverage: float = DEFAULT_COVERAGE,
    max_active: int = DEFAULT_MAX_ACTIVE,
    *,
    fallback: Sequence[int] | None = None,
) -> Cell:
    """Candidate set of one (condition, sector) cell by the utilisation rule.

    ``active_share`` has 7 entries indexed by vector (counts, or eta_Vi in %
    as in seed Tables 3-8); entry 0 (V0) is ignored because V0 is always kept.
    Active vectors are added in decreasing utilisation (ties: lower vector
    number first) until their sum is ``>= coverage`` times the sum of all
    active utilisations of the cell, with at most ``max_active`` actives.
    A vector with zero utilisation is never added.

    Returns ``(0, *sorted(actives))``.  If the cell has no active choices
    (all of V1..V6 are zero) the rule is undefined: ``fallback`` (a cell,
    e.g. from the published-derived table) is returned if given, otherwise
    :class:`NoUtilisationData` is raised.
    """
    _check_rule_parameters(coverage, max_active)
    share = np.asarray(active_share, dtype=float)
    if share.shape != (N_VECTORS,):
        raise ValueError(f"active_share must have 7 entries (V0..V6), got shape {share.shape}")
    if not np.all(np.isfinite(share)) or np.any(share < 0):
        raise ValueError(f"active_share must be finite and non-negative, got {share.tolist()}")
    active = share[1:]
    total = float(active.sum())
    if total <= 0.0:
        if fallback is not None:
            return tuple(int(v) for v in fallback)
        raise NoUtilisationData("no active-vector utilisation data in this cell")
    order = sorted(range(1, N_VECTORS), key=lambda v: (-share[v], v))
    target = coverage * total * (1.0 - _COVERAGE_RTOL)
    chosen: list[int] = []
    covered = 0.0
    for v in order:
        if covered >= target or len(chosen) >= max_active or share[v] <= 0.0:
            break
        chosen.append(v)
        covered += float(share[v])
    return (0, *sorted(chosen))


def count_utilisation(
    sector: np.ndarray,
    condition: np.ndarray,
    vector: np.ndarray,
    mask: np.ndarray,
    n_sectors: int,
    n_conditions: int,
) -> np.ndarray:
    """Count the vector choices per (condition, sector) cell (N_i of eq. (6)).

    ``sector`` (0-based), ``condition`` (0-based, see published.py) and
    ``vector`` (0..6) are per-sample integer arrays; ``mask`` selects the
    samples that count (the seed uses ``|dT| > eps_T``).  Returns an int64
    array of shape ``(n_conditions, n_sectors, 7)``.
    """
    s = np.asarray(sector).ravel()
    c = np.asarray(condition).ravel()
    v = np.asarray(vector).ravel()
    m = np.asarray(mask, dtype=bool).ravel()
    if not (s.shape == c.shape == v.shape == m.shape):
        raise ValueError(
            f"sector, condition, vector and mask must have equal length, got "
            f"{s.shape}, {c.shape}, {v.shape}, {m.shape}"
        )
    s, c, v = s[m].astype(np.int64), c[m].astype(np.int64), v[m].astype(np.int64)
    for name, arr, hi in (("sector", s, n_sectors), ("condition", c, n_conditions), ("vector", v, N_VECTORS)):
        if arr.size and (arr.min() < 0 or arr.max() >= hi):
            raise ValueError(f"{name} out of range 0..{hi - 1}: [{arr.min()}, {arr.max()}]")
    flat = (c * n_sectors + s) * N_VECTORS + v
    counts = np.bincount(flat, minlength=n_conditions * n_sectors * N_VECTORS)
    return counts.astype(np.int64).reshape(n_conditions, n_sectors, N_VECTORS)


def utilisation_percent(counts: np.ndarray) -> np.ndarray:
    """eta_Vi of eq. (6) per cell: counts / cell total * 100 (0 for empty cells)."""
    counts = np.asarray(counts, dtype=float)
    totals = counts.sum(axis=-1, keepdims=True)
    return np.divide(counts * 100.0, totals, out=np.zeros_like(counts), where=totals > 0)


def published_utilisation(kind: TableKind) -> np.ndarray:
    """The seed's utilisation tables as ``(n_conditions, n_sectors, 7)`` percent.

    ``"s2"``: Tables 3-4 (2 x 6 x 7); ``"s3"``: Tables 5-8 (4 x 12 x 7).
    """
    tables = {"s2": pub.S2_UTILISATION, "s3": pub.S3_UTILISATION}[kind]
    return np.stack([np.asarray(t, dtype=float).T for t in tables])


def derive_table(
    counts_or_percent: np.ndarray,
    coverage: float = DEFAULT_COVERAGE,
    max_active: int = DEFAULT_MAX_ACTIVE,
    *,
    fallback: SwitchTable | None = None,
) -> SwitchTable:
    """Apply :func:`select_vectors` to every cell of a ``(n_cond, n_sec, 7)`` array.

    ``fallback`` (a switch table of the same shape) supplies the cells that
    have no active-vector data; without it such a cell raises
    :class:`NoUtilisationData` naming the condition and sector.
    """
    data = np.asarray(counts_or_percent, dtype=float)
    if data.ndim != 3 or data.shape[2] != N_VECTORS:
        raise ValueError(f"expected shape (n_conditions, n_sectors, 7), got {data.shape}")
    n_cond, n_sec, _ = data.shape
    labels = CONDITION_LABELS.get({2: "s2", 4: "s3"}.get(n_cond, ""), ())
    rows = []
    for c in range(n_cond):
        cells = []
        for s in range(n_sec):
            fb = fallback[c][s] if fallback is not None else None
            try:
                cells.append(select_vectors(data[c, s], coverage, max_active, fallback=fb))
            except NoUtilisationData:
                label = f" ({labels[c]})" if labels else ""
                raise NoUtilisationData(
                    f"no utilisation data for condition {c}{label} sector {s + 1} "
                    f"(index {s}); train longer or pass fallback="
                ) from None
        rows.append(tuple(cells))
    return tuple(rows)


def compare_tables(derived: SwitchTable, published: SwitchTable) -> list[ComparisonRow]:
    """Cell-by-cell comparison over the conditions present in ``published``.

    ``published`` may cover fewer conditions than ``derived`` (the seed
    publishes a single s3 row: pass ``(PUBLISHED_S3_ROW,)``).
    """
    if len(published) > len(derived):
        raise ValueError(f"published has {len(published)} conditions, derived only {len(derived)}")
    rows: list[ComparisonRow] = []
    for c, pub_row in enumerate(published):
        if len(pub_row) != len(derived[c]):
            raise ValueError(f"condition {c}: {len(derived[c])} derived vs {len(pub_row)} published sectors")
        for s, pub_cell in enumerate(pub_row):
            d, p = tuple(derived[c][s]), tuple(pub_cell)
            rows.append(ComparisonRow(c, s, d, p, d == p))
    return rows


def _cell_text(cell: Sequence[int]) -> str:
    return " ".join(f"V{v}" for v in cell)


def _condition_label(kind: TableKind | None, c: int) -> str:
    if kind is None:
        return f"condition {c}"
    return CONDITION_LABELS[kind][c]


def format_utilisation(percent: np.ndarray, title: str) -> str:
    """Utilisation table in the seed's layout (Tables 3-8).

    ``percent`` is ``(7, n_sectors)``: rows eta_V0..eta_V6 in %, columns
    theta_1..theta_n, printed with two decimals.
    """
    p = np.asarray(percent, dtype=float)
    if p.ndim != 2 or p.shape[0] != N_VECTORS:
        raise ValueError(f"expected shape (7, n_sectors), got {p.shape}")
    width = 9
    lines = [title, " " * 9 + "".join(f"{f'theta_{s + 1}':>{width}}" for s in range(p.shape[1]))]
    for v in range(N_VECTORS):
        lines.append(f"{f'eta_V{v}/%':<9}" + "".join(f"{x:>{width}.2f}" for x in p[v]))
    return "\n".join(lines)


def format_switch_table(table: SwitchTable, kind: TableKind) -> str:
    """One line per sector, e.g. ``sector 1 | dT>0: V0 V2 V3 V4 | dT<0: V0 V1 V5 V6``.

    ``table`` may hold fewer conditions than ``kind`` has (a published row).
    """
    labels = CONDITION_LABELS[kind]
    if len(table) > len(labels):
        raise ValueError(f"{kind} has {len(labels)} conditions, table has {len(table)}")
    n_sec = len(table[0])
    sw = len(str(n_sec))
    cw = max(len(_cell_text(cell)) for row in table for cell in row)
    lines = []
    for s in range(n_sec):
        parts = [f"sector {s + 1:>{sw}}"]
        parts += [f"{labels[c]}: {_cell_text(table[c][s]):<{cw}}" for c in range(len(table))]
        lines.append(" | ".join(parts).rstrip())
    return "\n".join(lines)


def format_comparison(rows: Sequence[ComparisonRow], kind: TableKind | None = None) -> str:
    """Mark each cell ``=`` or ``DIFFERS (published: ...)``; end with "k of n cells equal"."""
    if not rows:
        return "0 of 0 cells equal"
    sw = len(str(max(r.sector for r in rows) + 1))
    cw = max(len(_cell_text(r.derived)) for r in rows)
    lines = []
    for r in rows:
        mark = "=" if r.equal else f"DIFFERS (published: {_cell_text(r.published)})"
        lines.append(
            f"sector {r.sector + 1:>{sw}} | {_condition_label(kind, r.condition)}: "
            f"{_cell_text(r.derived):<{cw}} | {mark}"
        )
    n_equal = sum(r.equal for r in rows)
    lines.append(f"{n_equal} of {len(rows)} cells equal")
    return "\n".join(lines)


def _difference_note(util: np.ndarray, row: ComparisonRow, kind: TableKind, table_name: str) -> str:
    """Explain one differing cell from the utilisation column it came from."""
    col = util[row.condition, row.sector]
    ranked = sorted(range(1, N_VECTORS), key=lambda v: (-col[v], v))
    shares = ", ".join(f"V{v} {col[v]:.2f} %" for v in ranked if col[v] > 0)
    note = (
        f"- sector {row.sector + 1} ({_condition_label(kind, row.condition)}): {table_name} "
        f"theta_{row.sector + 1} active utilisation {shares}; the rule gives "
        f"{{{_cell_text(row.derived)}}}, the paper publishes {{{_cell_text(row.published)}}}."
    )
    kept = [v for v in row.published if v]
    omitted = [v for v in range(1, N_VECTORS) if v not in row.published]
    for k in kept:
        for o in omitted:
            if col[o] > col[k]:
                note += (
                    f"\n  Seed's own inconsistency: {table_name} gives V{o} {col[o]:.2f} % > "
                    f"V{k} {col[k]:.2f} % yet the paper keeps V{k}."
                )
    total = col.sum()
    if abs(total - 100.0) > 0.1:
        note += f"\n  The {table_name} column theta_{row.sector + 1} sums to {total:.2f} %, not 100 %."
    return note


# Seed Table 5 theta_5 repeats Table 4 theta_6 in V4..V6 (probable copy error).
def _table5_theta5_copies_table4() -> bool:
    return all(pub.TABLE5_UTIL_DT_POS_DPSI_POS[v][4] == pub.TABLE4_UTIL_DT_NEG[v][5] for v in (4, 5, 6))


def published_derivation_report(
    coverage: float = DEFAULT_COVERAGE, max_active: int = DEFAULT_MAX_ACTIVE
) -> tuple[str, list[ComparisonRow], list[ComparisonRow]]:
    """Run the rule on the seed's published utilisations and compare.

    s2: derived from Tables 3-4, compared with the published s2 table (seed
    section 4; expected 12 of 12 at coverage 0.90).  s3: all 4 rows derived
    from Tables 5-8, row 0 compared with the published s3 row (seed section 5;
    expected 11 of 12, the difference at sector 5, where Table 5 gives V6
    19.54 % > V4 18.41 % yet the paper keeps V4).

    Returns ``(text, s2_rows, s3_rows)``.
    """
    util2, util3 = published_utilisation("s2"), published_utilisation("s3")
    s2 = derive_table(util2, coverage, max_active)
    s3 = derive_table(util3, coverage, max_active)
    s2_rows = compare_tables(s2, pub.PUBLISHED_S2)
    s3_rows = compare_tables(s3, (pub.PUBLISHED_S3_ROW,))
    out = [
        f"Switch tables derived from the paper's published utilisation "
        f"(coverage {coverage:.2f}, max_active {max_active})",
        "",
        "s2, derived from Tables 3-4:",
        format_switch_table(s2, "s2"),
        "",
        "s2 vs the published table (paper section 4):",
        format_comparison(s2_rows, "s2"),
        "",
        "s3, derived from Tables 5-8:",
        format_switch_table(s3, "s3"),
        "",
        "s3 row dT>0,dpsi>0 vs the published row (paper section 5):",
        format_comparison(s3_rows, "s3"),
    ]
    names = {"s2": ("Table 3", "Table 4"), "s3": ("Table 5", "Table 6", "Table 7", "Table 8")}
    notes = [_difference_note(util2, r, "s2", names["s2"][r.condition]) for r in s2_rows if not r.equal]
    for r in s3_rows:
        if r.equal:
            continue
        note = _difference_note(util3, r, "s3", names["s3"][r.condition])
        if (r.condition, r.sector) == (0, 4) and _table5_theta5_copies_table4():
            copied = "/".join(f"{pub.TABLE4_UTIL_DT_NEG[v][5]:.2f}" for v in (4, 5, 6))
            note += (
                f"\n  Its V4/V5/V6 entries equal Table 4 theta_6 ({copied}): "
                "probably a copy error in the seed."
            )
        notes.append(note)
    if notes:
        out += ["", "Differences:", *notes]
    return "\n".join(out), s2_rows, s3_rows


def published_tables(
    coverage: float = DEFAULT_COVERAGE, max_active: int = DEFAULT_MAX_ACTIVE
) -> tuple[SwitchTable, SwitchTable]:
    """Tables used by a config with ``tables = "published"``.

    s2: the published table of seed section 4, verbatim.  s3: the seed
    publishes only row 0 (dT>0, dpsi>0) and calls the other three "similar",
    so row 0 is the published row (including its sector-5 set {V0 V4 V5})
    and rows 1-3 are derived by :func:`select_vectors` from the seed's
    Tables 6-8 with the given ``coverage`` / ``max_active``.
    """
    derived = derive_table(published_utilisation("s3"), coverage, max_active)
    s3 = (pub.PUBLISHED_S3_ROW, *derived[1:])
    return pub.PUBLISHED_S2, s3
