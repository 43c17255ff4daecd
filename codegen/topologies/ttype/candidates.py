"""Candidate table of 63-MPDTC, derived (mpdtc-three-level.md "Candidate table
(Table 3), derived"; seed 000 section 2.2, Fig. 5, Table 3).

For every previous state p (all 27 states; a virtual vector's end state is its
start state, so a row per state covers every previously applied vector) and
every sector k = 0..11 (the seed's sectors I..XII; sector k is the closed
interval [30k, 30(k+1)] deg of u*'s angle):

1. Members: the 63-MPDTC vectors (the 24 non-zero basic states and the 36
   virtual vectors) allowed after p (``transitions``) whose angle lies in the
   closed sector interval (a vector on a border belongs to both sectors;
   angles compared with 1e-9 deg tolerance), plus OOO when OOO is allowed
   after p.  PPP and NNN are never candidates.
2. Groups: members with identical voltage (exact lattice keys) form one group:
   a small pair (P- and N-type states) and the two split versions of a
   virtual small/medium.  At run time a group is resolved to one member by
   the predicted |V_o(k+2)| before the full cost is evaluated.
3. Fallback: if sector k gives fewer than 3 groups, the row takes the groups
   of the nearest sector j with at least 3 groups.  The distance is measured
   from the sector itself (u*'s angle inside it is unknown when the table is
   derived): the number of 30-deg steps between sector centres,
   min(|j-k|, 12-|j-k|); equal distance: the counter-clockwise sector j = k+d.
   This reproduces the seed's worked example (previous u7, u* in sector VI ->
   sector II: u_s1^u1, u_m1^u1, u8).  If no sector has 3 groups (only the
   previous state PPP, which 63-MPDTC never applies since its zero is OOO:
   every sector then offers OOO and one P-type small state), the nearest
   sector with the largest group count is used, same tie rule; such rows are
   flagged ``short``.

Order (deterministic): the zero group (OOO) first, then groups by angle
measured counter-clockwise from the source sector's start border (0..30 deg),
then by magnitude.  Members inside a group: ascending vector id (basic states
by state index, i.e. the N-type state before the P-type state; then split
versions in counter-clockwise order of the split pair).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cache

from codegen.topologies.ttype import transitions as tr
from codegen.topologies.ttype import vectors as v
from codegen.topologies.ttype import virtual as vv

N_SECTORS = 12
SECTOR_DEG = 30.0
MIN_GROUPS = 3
ANGLE_TOL_DEG = 1e-9
SECTOR_NAMES: tuple[str, ...] = ("I", "II", "III", "IV", "V", "VI", "VII", "VIII", "IX", "X", "XI", "XII")

Group = tuple[int, ...]  # vector ids 0..62 with one voltage


@dataclass(frozen=True)
class CandidateRow:
    """Candidates when ``prev_state`` was applied last and u* lies in ``sector``."""

    prev_state: int  # 0..26
    sector: int  # 0..11 (sector of u*)
    source_sector: int  # sector whose candidates are used (== sector unless fallback)
    groups: tuple[Group, ...]
    short: bool = False  # fewer than 3 groups even after fallback (PPP only)

    @property
    def n_groups(self) -> int:
        return len(self.groups)

    @property
    def fallback(self) -> bool:
        return self.source_sector != self.sector

    @property
    def members(self) -> tuple[int, ...]:
        return tuple(m for g in self.groups for m in g)


@dataclass(frozen=True)
class CandidateTable:
    """27 x 12 rows; row index = prev_state * 12 + sector."""

    rows: tuple[CandidateRow, ...]

    def row(self, prev_state: int, sector: int) -> CandidateRow:
        if not (0 <= prev_state < v.N_STATES and 0 <= sector < N_SECTORS):
            raise ValueError(f"row ({prev_state}, {sector}) outside 27 x 12")
        return self.rows[prev_state * N_SECTORS + sector]

    @property
    def n_groups(self) -> tuple[int, ...]:
        """Group count of every row, row order."""
        return tuple(r.n_groups for r in self.rows)

    @property
    def max_groups(self) -> int:
        return max(self.n_groups)

    @property
    def max_members(self) -> int:
        return max(len(g) for r in self.rows for g in r.groups)


def in_sector(angle_deg: float, sector: int) -> bool:
    """Angle in the closed interval [30 sector, 30 (sector+1)] deg (modulo 360)."""
    centre = SECTOR_DEG * sector + SECTOR_DEG / 2
    d = (angle_deg - centre + 180.0) % 360.0 - 180.0
    return abs(d) <= SECTOR_DEG / 2 + ANGLE_TOL_DEG


def _angle_from_start(vid: int, sector: int) -> float:
    rel = (vv.vector_angle_deg(vid) - SECTOR_DEG * sector) % 360.0
    return 0.0 if rel > 360.0 - 1.0 else rel  # 359.999.. on the start border


@cache
def sector_vectors(sector: int) -> tuple[int, ...]:
    """Non-zero 63-MPDTC vectors (ids) whose angle lies in the closed sector."""
    return tuple(i for i in range(vv.N_VECTORS)
                 if tr.is_63_candidate(i) and vv.vector_magnitude(i) > 0.0
                 and in_sector(vv.vector_angle_deg(i), sector))


@cache
def sector_groups(prev_state: int, sector: int) -> tuple[Group, ...]:
    """Step 1-2 of the rule (no fallback): ordered groups of sector ``sector``."""
    members = [i for i in sector_vectors(sector) if tr.vector_allowed_after_state(prev_state, i)]
    by_key: dict[tuple[int, int], list[int]] = {}
    for i in members:
        by_key.setdefault(vv.vector_key(i), []).append(i)
    groups = sorted(
        (tuple(sorted(g)) for g in by_key.values()),
        key=lambda g: (_angle_from_start(g[0], sector), vv.vector_magnitude(g[0]), g[0]),
    )
    if tr.vector_allowed_after_state(prev_state, tr.ZERO_STATE_63):
        groups.insert(0, (tr.ZERO_STATE_63,))
    return tuple(groups)


def sector_search_order(sector: int) -> tuple[int, ...]:
    """Sectors by distance from ``sector`` (itself first), counter-clockwise first on ties."""
    order = [sector]
    for d in range(1, N_SECTORS // 2 + 1):
        for j in ((sector + d) % N_SECTORS, (sector - d) % N_SECTORS):
            if j not in order:
                order.append(j)
    return tuple(order)


def derive_row(prev_state: int, sector: int) -> CandidateRow:
    """Rule 1-3 for one (previous state, sector)."""
    counts = {j: len(sector_groups(prev_state, j)) for j in range(N_SECTORS)}
    order = sector_search_order(sector)
    for j in order:
        if counts[j] >= MIN_GROUPS:
            return CandidateRow(prev_state, sector, j, sector_groups(prev_state, j))
    best = max(counts.values())
    j = next(j for j in order if counts[j] == best)
    return CandidateRow(prev_state, sector, j, sector_groups(prev_state, j), short=True)


@cache
def derive_candidate_table() -> CandidateTable:
    """The full 27 x 12 table (derived once)."""
    return CandidateTable(tuple(derive_row(p, k) for p in range(v.N_STATES) for k in range(N_SECTORS)))


@cache
def applied_states_63() -> tuple[int, ...]:
    """States 63-MPDTC can have applied last: end states of its 63 vectors (25: not PPP, NNN)."""
    return tuple(sorted({vv.end_state(i) for i in range(vv.N_VECTORS) if tr.is_63_candidate(i)}))


def group_label(group: Group) -> str:
    """Seed notation of a group: 'u1', 'u0', 'u_L1', 'u_s1' (both versions),
    'u_s1^u2' (one split version only)."""
    first = group[0]
    if not vv.is_virtual(first):
        return vv.vector_group_name(first)
    x = vv.virtual_of(first)
    if x.kind == "large" or len(group) == 2:
        return x.group_name
    return x.name


def row_labels(row: CandidateRow) -> tuple[str, ...]:
    return tuple(group_label(g) for g in row.groups)
