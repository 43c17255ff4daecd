"""The 63-MPDTC step's resolve programs: the candidate rows up to a 120-degree rotation.

Rotating every switching state's legs (Sa, Sb, Sc) -> (Sc, Sa, Sb) turns its space
vector by +120 degrees, maps the 63 vectors onto themselves (a virtual vector's
7-segment sequence onto another's) and the sector of u* k onto k + 4.  Most
candidate rows are the rotation of another row: row (s, k) holds, group by group
and member by member in order, the rotated vectors of row (s', k - 4) with s the
rotated s'.  The step then resolves a row with the code of its *program* (the
canonical row's groups, written out at generation) applied to the rotated
midpoint currents, and rotates the resolved vectors back:

- a member's segment pattern p = 4 ka + 2 kb + kc (i_o = ka i_a + kb i_b + kc i_c,
  eq. (2) corrected) becomes pi(p) = 4 kc + 2 ka + kb, so the program reads
  ``io_rot[p] = io[pi^m(p)]``: the same values, copied, so every member's
  arithmetic (and its bits) is the row's own;
- the program's vector v stands for sigma^m(v) (``vec_rot[m][v]``).

Every claimed mapping is checked here, at derivation: a row the rotation does
not reproduce exactly (group order, member order, patterns) is a program of its
own (rotation 0).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from codegen.topologies.ttype import vectors as v

N_ROTATIONS = 3
N_PATTERNS = 8
#: sector steps of one 120-degree rotation (12 sectors of 30 degrees)
SECTOR_STEP = 4


@dataclass(frozen=True)
class ResolvePrograms:
    """``programs[i]``: the canonical row's group indices; per row ``row_program`` and
    ``row_rotation`` (m); ``vec_rot[m][v]`` = sigma^m(v); ``pat_rot[m][p]`` = pi^m(p)."""

    programs: tuple[tuple[int, ...], ...]
    row_program: tuple[int, ...]
    row_rotation: tuple[int, ...]
    vec_rot: tuple[tuple[int, ...], ...]
    pat_rot: tuple[tuple[int, ...], ...]


def rotate_state(s: int) -> int:
    """sigma: the state whose space vector is state s's turned by +120 degrees."""
    a, b, c = v.STATES[s].levels
    return v.state_index((c, a, b))


def rotate_pattern(p: int) -> int:
    """pi: the midpoint-current pattern of a rotated state, p = 4 ka + 2 kb + kc -> 4 kc + 2 ka + kb."""
    return 4 * (p & 1) + 2 * ((p >> 2) & 1) + ((p >> 1) & 1)


def _powers(f: Any, n: int) -> tuple[tuple[int, ...], ...]:
    """f^0, f^1, f^2 over range(n)."""
    out = [tuple(range(n))]
    for _ in range(1, N_ROTATIONS):
        out.append(tuple(f(x) for x in out[-1]))
    return tuple(out)


def resolve_programs(t: Any) -> ResolvePrograms:
    """The programs of the 63-MPDTC tables ``t`` (rows indexed prev_state * n_sectors + sector)."""
    by_seq = {tuple(s): i for i, s in enumerate(t.seq)}
    sigma = tuple(by_seq[tuple(rotate_state(s) for s in seq)] for seq in t.seq)
    for x in range(len(t.seq)):
        if tuple(t.seq_pat[sigma[x]]) != tuple(rotate_pattern(p) for p in t.seq_pat[x]):
            raise ValueError(f"vector {x}: its rotation's segment patterns are not the rotated patterns")
    vec_rot = _powers(lambda x: sigma[x], len(t.seq))
    pat_rot = _powers(rotate_pattern, N_PATTERNS)

    def rotated(groups: tuple[tuple[int, ...], ...], m: int) -> tuple[tuple[int, ...], ...]:
        return tuple(tuple(vec_rot[m][x] for x in g) for g in groups)

    for g, members in enumerate(t.groups):  # the step's cases pick between at most two members of one kind
        if len(members) not in (1, 2) or len({bool(t.is_virtual[x]) for x in members}) != 1:
            raise ValueError(f"group {t.group_labels[g]}: members {members} are not one or two of one kind")
    programs: list[tuple[int, ...]] = []
    contents: list[tuple[tuple[int, ...], ...]] = []
    row_program, row_rotation = [], []
    for groups in t.row_groups:
        members = tuple(tuple(t.groups[g]) for g in groups)
        found = next(((i, m) for i, c in enumerate(contents) for m in range(N_ROTATIONS)
                      if rotated(c, m) == members), None)
        if found is None:
            found = (len(programs), 0)
            programs.append(tuple(groups))
            contents.append(members)
        row_program.append(found[0])
        row_rotation.append(found[1])
    return ResolvePrograms(tuple(programs), tuple(row_program), tuple(row_rotation), vec_rot, pat_rot)
