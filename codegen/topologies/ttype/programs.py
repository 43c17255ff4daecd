"""The 63-MPDTC step's resolve programs: the candidate rows up to a 120-degree rotation.

Rotating every switching state's legs (Sa, Sb, Sc) -> (Sc, Sa, Sb) turns its space
vector by +120 degrees, maps the 63 vectors onto themselves (a virtual vector's
7-segment sequence onto another's) and the sector of u* k onto k + 4.  Most
candidate rows are the rotation of another row: row (s, k) holds, group by group
and member by member in order, the rotated vectors of row (s', k - 4) with s the
rotated s'.  The step then resolves a row with the table entry of its *program*
(the canonical row's groups, ``step_programs`` below: 57 entries for 324 rows)
applied to the rotated midpoint currents, and rotates the resolved vectors back:

- a member's segment pattern p = 4 ka + 2 kb + kc (i_o = ka i_a + kb i_b + kc i_c,
  eq. (2) corrected) becomes pi(p) = 4 kc + 2 ka + kb, so the program reads
  ``io_rot[p] = io[pi^m(p)]``: the same values, copied, so every member's
  arithmetic (and its bits) is the row's own;
- the program's vector v stands for sigma^m(v) (``vec_rot[m][v]``).

Every claimed mapping is checked here, at derivation: a row the rotation does
not reproduce exactly (group order, member order, patterns) is a program of its
own (rotation 0).

``step_programs`` lays the programs out as the step's table (``ProgramTable``, one
entry a program; 27-MPDTC: its one row, one program, no rotation).  The step
computes each |V_o(k+2)| once, in a *slot*: slots 0-7 the basic members', one per
midpoint-current pattern p (a basic member's |V_o(k+2)| depends on its pattern
only), slot 8 + i the program's i-th virtual member's (its neutral-point
deadbeat).  A group lists its members as (vector, slot) in member order, a member
whose slot an earlier member of its group has left out: its |V_o(k+2)| is that
member's, never strictly smaller (27-MPDTC's PPP after NNN).  The step compares at
most ``GROUP_WIDTH`` entries a group and takes a later one only when it is strictly
smaller (ties: the earlier, the reference's rule).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from codegen.topologies.ttype import vectors as v

N_ROTATIONS = 3
N_PATTERNS = 8
#: sector steps of one 120-degree rotation (12 sectors of 30 degrees)
SECTOR_STEP = 4
#: the step's |V_o(k+2)| slot of a program's first virtual member (slots 0-7: the patterns)
FIRST_VIRTUAL_SLOT = N_PATTERNS
#: entries a group compares (a one-member group: its member twice)
GROUP_WIDTH = 2


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


@dataclass(frozen=True)
class ProgramTable:
    """One program as the step's table entry, in the program's frame (its row's vectors are
    ``vec_rot[m][v]``, its patterns read the midpoint currents stored in rotation m).

    ``virt_pat``: the virtual members' segment patterns [N, b, c, P] in row order (group by group,
    member by member), member i's deadbeat in slot ``FIRST_VIRTUAL_SLOT + i``; ``members[j]``: group
    j's entries (vector, slot) in member order, at most ``GROUP_WIDTH`` (module docstring);
    ``labels``: the groups' labels; ``n_members``: every member of the groups (the output's
    n_members)."""

    labels: tuple[str, ...]
    virt_pat: tuple[tuple[int, ...], ...]
    members: tuple[tuple[tuple[int, int], ...], ...]
    n_members: int


@dataclass(frozen=True)
class StepPrograms:
    """The step's program table: ``programs`` and, per row, ``row_program`` and ``row_rotation``;
    ``vec_rot``, ``pat_rot`` as in ``ResolvePrograms`` (27-MPDTC: one program, rotation 0 only)."""

    programs: tuple[ProgramTable, ...]
    row_program: tuple[int, ...]
    row_rotation: tuple[int, ...]
    vec_rot: tuple[tuple[int, ...], ...]
    pat_rot: tuple[tuple[int, ...], ...]

    @property
    def max_virtual(self) -> int:
        """The most virtual members a program resolves (each a neutral-point deadbeat)."""
        return max(len(p.virt_pat) for p in self.programs)


def program_table(t: Any, groups: tuple[int, ...]) -> ProgramTable:
    """The table entry of the row (or program) with group indices ``groups`` of tables ``t``."""
    virt: list[tuple[int, ...]] = []
    members = []
    for g in groups:
        entries: list[tuple[int, int]] = []
        for x in t.groups[g]:
            if t.is_virtual[x]:
                slot = FIRST_VIRTUAL_SLOT + len(virt)
                virt.append(tuple(t.seq_pat[x]))
            else:
                slot = t.seq_pat[x][0]
            if slot not in {s for _, s in entries}:
                entries.append((x, slot))
        if len(entries) > GROUP_WIDTH:
            raise ValueError(f"group {t.group_labels[g]}: {len(entries)} members of distinct |V_o(k+2)| "
                             f"(the step compares {GROUP_WIDTH})")
        members.append(tuple(entries))
    return ProgramTable(tuple(t.group_labels[g] for g in groups), tuple(virt), tuple(members),
                        sum(t.group_n[g] for g in groups))


def step_programs(t: Any) -> StepPrograms:
    """The step's program table of tables ``t``: 63-MPDTC its resolve programs, 27-MPDTC its one row."""
    if t.n_sectors == 1:
        identity = (tuple(range(len(t.seq))),), (tuple(range(N_PATTERNS)),)
        return StepPrograms((program_table(t, t.row_groups[0]),), (0,) * len(t.row_groups),
                            (0,) * len(t.row_groups), *identity)
    p = resolve_programs(t)
    return StepPrograms(tuple(program_table(t, g) for g in p.programs), p.row_program, p.row_rotation,
                        p.vec_rot, p.pat_rot)


def ends_alone(n: int, width: int) -> bool:
    """Whether a loop over ``n`` items, ``width`` at a time (width > 1), then two, then one by one,
    leaves one item alone at its end."""
    return width > 1 and (n % width if width > 2 else n) % 2 == 1


def block_width(counts: Any, most: int) -> int:
    """Items a step's loop takes at a time (then two, then one) over loops of ``counts`` items,
    at most ``most`` (the number format's independent chains): the widest that leaves no item
    alone at the end of any of the loops (a lone chain waits on each of its operations), else
    ``most``."""
    return next((w for w in range(most, 1, -1) if not any(ends_alone(n, w) for n in set(counts))), most)
