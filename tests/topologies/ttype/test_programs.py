"""63-MPDTC resolve programs (codegen/topologies/ttype/programs.py): every candidate row is its
program's row turned by a 120-degree rotation of the legs, group by group, member by member and
pattern by pattern, so the step's program cases resolve each row with the row's own arithmetic."""
from __future__ import annotations

import cmath
import math
from collections import Counter

from codegen.config import load_config
from codegen.topologies.ttype import plugin as PLUGIN
from codegen.topologies.ttype import programs as pg
from codegen.topologies.ttype import vectors as v

from conftest import TTYPE


def tables():
    return PLUGIN.derive(load_config(TTYPE, {"controller.strategy": "mpdtc63"}))


def test_the_rotation_turns_every_state_by_120_degrees():
    for s in v.STATES:
        r = v.STATES[pg.rotate_state(s.index)]
        turned = complex(s.alpha, s.beta) * cmath.exp(2j * math.pi / 3)
        assert abs(complex(r.alpha, r.beta) - turned) < 1e-12, s.name
        # a phase at O stays at O, moved to the next leg: the pattern's bits move with it
        p = 4 * int(s.io[0]) + 2 * int(s.io[1]) + int(s.io[2])
        assert 4 * int(r.io[0]) + 2 * int(r.io[1]) + int(r.io[2]) == pg.rotate_pattern(p)


def test_every_row_is_its_program_rotated_member_by_member():
    t = tables()
    p = pg.resolve_programs(t)
    assert len(p.row_program) == len(p.row_rotation) == len(t.row_groups)
    for r, groups in enumerate(t.row_groups):
        prog = p.programs[p.row_program[r]]
        m = p.row_rotation[r]
        assert len(prog) == len(groups), r
        for g_prog, g_row in zip(prog, groups):
            members = [p.vec_rot[m][x] for x in t.groups[g_prog]]
            assert members == list(t.groups[g_row]), (r, g_prog, g_row)
            for x, y in zip(t.groups[g_prog], t.groups[g_row]):
                # the program reads pattern q where the row's member has pattern pat_rot[m][q]
                assert [p.pat_rot[m][q] for q in t.seq_pat[x]] == list(t.seq_pat[y]), (r, x, y)


def test_rotations_compose_to_the_identity_and_fold_the_rows_threefold():
    t = tables()
    p = pg.resolve_programs(t)
    sigma, pi = p.vec_rot[1], p.pat_rot[1]
    assert [sigma[sigma[sigma[x]]] for x in range(63)] == list(range(63))
    assert [pi[pi[pi[q]]] for q in range(8)] == list(range(8))
    assert list(p.vec_rot[2]) == [sigma[sigma[x]] for x in range(63)]
    # 324 rows (150 distinct group lists), 57 programs; every rotation is used
    assert len(t.row_groups) == 324 and len({tuple(r) for r in t.row_groups}) == 150
    assert len(p.programs) == 57
    assert set(Counter(p.row_rotation)) == {0, 1, 2}
    # a program is the first row (in row order) that the rotations do not reach from earlier ones
    first = {}
    for r, i in enumerate(p.row_program):
        first.setdefault(i, r)
    assert [tuple(t.row_groups[first[i]]) for i in range(len(p.programs))] == list(p.programs)
    assert all(p.row_rotation[first[i]] == 0 for i in first)


def test_the_rotation_moves_the_sector_of_u_star_by_four():
    """Most rows (s, k) are the rotation of row (sigma^-1 s, k - 4): the 30-degree sectors turn
    with the legs (the rows the derivation makes by fallback are their own programs)."""
    t = tables()
    p = pg.resolve_programs(t)
    n = t.n_sectors
    mapped = 0
    for r, groups in enumerate(t.row_groups):
        s, k = divmod(r, n)
        r1 = pg.rotate_state(s) * n + (k + pg.SECTOR_STEP) % n
        rotated = [[p.vec_rot[1][x] for x in t.groups[g]] for g in groups]
        mapped += rotated == [list(t.groups[g]) for g in t.row_groups[r1]]
    assert mapped == 302


def _entries_of_row(t, groups):
    """The row's groups as the step's table lists them, in the row's own frame: per group its
    members (vector, slot) in member order, slot the basic member's pattern or 8 + i for the row's
    i-th virtual member, a member whose slot an earlier member of its group has left out."""
    out, n_virt = [], 0
    for g in groups:
        entries = []
        for x in t.groups[g]:
            if t.is_virtual[x]:
                slot, n_virt = pg.FIRST_VIRTUAL_SLOT + n_virt, n_virt + 1
            else:
                slot = t.seq_pat[x][0]
            if slot not in [s for _, s in entries]:
                entries.append((x, slot))
        out.append(entries)
    return out


def test_every_row_is_its_program_table_entry_rotated():
    """The step's table (step_programs): a row's program entry, its vectors mapped by vec_rot[m] and
    its patterns by pat_rot[m], is the row's own groups, members, patterns and slots."""
    t = tables()
    sp = pg.step_programs(t)
    assert [p.labels for p in sp.programs] == [tuple(t.group_labels[g] for g in prog)
                                               for prog in pg.resolve_programs(t).programs]
    for r, groups in enumerate(t.row_groups):
        prog, m = sp.programs[sp.row_program[r]], sp.row_rotation[r]
        vec, pat = sp.vec_rot[m], sp.pat_rot[m]
        assert prog.n_members == sum(t.group_n[g] for g in groups), r
        row_virt = [x for g in groups for x in t.groups[g] if t.is_virtual[x]]
        assert [tuple(pat[q] for q in vp) for vp in prog.virt_pat] == [tuple(t.seq_pat[x]) for x in row_virt], r
        want = _entries_of_row(t, groups)
        got = [[(vec[v], s if s >= pg.FIRST_VIRTUAL_SLOT else pat[s]) for v, s in entries] for entries in prog.members]
        assert got == want, r
        assert all(1 <= len(e) <= pg.GROUP_WIDTH for e in prog.members)


def test_the_table_resolves_every_row_as_the_reference_rule_does():
    """The step's resolution through the table, in the program's frame (the midpoint currents
    stored rotated, |V_o(k+2)| by slot, a group's later entry taken only if strictly smaller), picks
    the member the reference's rule picks on the row itself (first member, a later one only if its
    |V_o(k+2)| is strictly smaller), for random midpoint currents; same formula both sides."""
    import numpy as np

    t = tables()
    sp = pg.step_programs(t)
    rng = np.random.default_rng(27)
    ts, k_vo, tn_min = 50e-6, 500.0, 50e-6 / 6

    def basic(io, vo1, p):
        return abs(vo1 + k_vo * (ts * io[p]))

    def virtual(io, vo1, sp4):
        a = (io[sp4[1]] + io[sp4[2]]) + io[sp4[3]]
        d = io[sp4[0]] - io[sp4[3]]
        tn = (-2e-3 * vo1 - ts / 3 * a) / d if d != 0 else tn_min
        tn = min(max(tn, tn_min), ts / 3)
        return abs(vo1 + k_vo * (ts / 3 * a + tn * d))

    for _ in range(20):
        io, vo1 = rng.normal(0, 10, 8), rng.normal(0, 5)
        for r, groups in enumerate(t.row_groups):
            prog, m = sp.programs[sp.row_program[r]], sp.row_rotation[r]
            io_rot = [io[q] for q in sp.pat_rot[m]]  # io_patterns: io[p] = i_o(pat_rot[m][p])
            av = [basic(io_rot, vo1, p) for p in range(8)] + [virtual(io_rot, vo1, vp) for vp in prog.virt_pat]
            for entries, g in zip(prog.members, groups):
                e = list(entries) + [entries[0]] * (pg.GROUP_WIDTH - len(entries))
                got = sp.vec_rot[m][e[1][0] if av[e[1][1]] < av[e[0][1]] else e[0][0]]
                best, want = None, None
                for x in t.groups[g]:
                    v_o = virtual(io, vo1, t.seq_pat[x]) if t.is_virtual[x] else basic(io, vo1, t.seq_pat[x][0])
                    if best is None or v_o < best:
                        best, want = v_o, x
                assert got == want, (r, g)
