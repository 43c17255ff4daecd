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
