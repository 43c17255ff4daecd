"""Switching constraint and derived 63-MPDTC candidate table
(mpdtc-three-level.md "Switching constraint", "Candidate table (Table 3)";
seed 000 section 2.2, Table 3)."""
from __future__ import annotations

import numpy as np
import pytest

from codegen.topologies.ttype import candidates as cd
from codegen.topologies.ttype import published as pub
from codegen.topologies.ttype import tables_text as rp
from codegen.topologies.ttype import transitions as tr
from codegen.topologies.ttype import vectors as v
from codegen.topologies.ttype import virtual as vv

S = v.state_by_name


def labels(prev: str, sector: int = 0) -> tuple[str, ...]:
    return cd.row_labels(cd.derive_candidate_table().row(S(prev), sector))


# --- transitions -------------------------------------------------------------

@pytest.mark.parametrize("prev, nxt, ok", [
    ("OOO", "POO", True), ("OOO", "ONN", True), ("OOO", "PPO", True),
    ("OOO", "PON", False),  # zero -> medium: line a-c jumps Udc
    ("OOO", "PNN", False),  # zero -> large
    ("ONN", "POO", True),  # all three legs up one level: line voltages unchanged
    ("ONN", "PON", True), ("PNN", "PON", True),
    ("PNN", "OON", False),  # u_ab changes by Udc
    ("PNN", "NNN", False),  # leg a two levels
    ("PPN", "POO", False), ("PON", "OON", True), ("PPP", "ONN", False),
])
def test_transition_examples(prev: str, nxt: str, ok: bool) -> None:
    assert tr.state_transition_allowed(S(prev), S(nxt)) is ok


def test_transition_matrix() -> None:
    m = tr.allowed_matrix()
    assert m.shape == (27, 27) and m.dtype == bool
    assert np.array_equal(m, m.T) and m.diagonal().all()
    for p in range(27):
        for n in range(27):
            if m[p, n]:
                assert tr.line_jump_max(p, n) <= 1
    assert tr.line_jump_max(S("PNN"), S("NPP")) == 4  # 2 Udc under 27-MPDTC


def test_virtual_follows_its_start_state() -> None:
    u_s1_u2 = vv.virtual_by_name("u_s1^u2").id
    u_l1 = vv.virtual_by_name("u_L1").id
    assert not tr.vector_allowed_after_state(S("PNN"), u_s1_u2)  # starts OON
    assert tr.vector_allowed_after_state(S("PNN"), u_l1)  # starts ONN
    for prev in range(63):
        for nxt in (S("PON"), u_s1_u2):
            assert tr.may_follow(prev, nxt) == tr.state_transition_allowed(vv.end_state(prev), vv.start_state(nxt))


def test_63_vector_set() -> None:
    assert tr.ZERO_STATE_63 == v.OOO
    assert not tr.is_63_candidate(v.PPP) and not tr.is_63_candidate(v.NNN)
    assert sum(tr.is_63_candidate(i) for i in range(63)) == 61
    assert len(cd.applied_states_63()) == 25


# --- candidate table ---------------------------------------------------------

def test_spec_required_rows() -> None:
    assert set(labels("OOO")) == {"u0", "u1", "u_s1", "u_m1", "u_L1"}
    assert set(labels("PNN")) == {"u1", "u_s1^u1", "u_m1^u1", "u_L1", "u7", "u8"}
    assert set(labels("PON")) == {"u1", "u_s1", "u_m1", "u_L1", "u7", "u8"}
    assert set(labels("PPN")) == {"u_s1^u2", "u_m1^u2", "u8"}
    assert all(rp.required_rows_check().values())


def test_onn_gives_7_groups() -> None:
    row = cd.derive_candidate_table().row(S("ONN"), 0)
    assert row.n_groups == 7 and not row.fallback
    assert labels("ONN") == ("u0", "u1", "u7", "u_L1", "u_s1", "u_m1", "u8")


def test_group_members() -> None:
    t = cd.derive_candidate_table()
    row = t.row(v.OOO, 0)
    assert row.groups[0] == (v.OOO,)
    assert (S("ONN"), S("POO")) in row.groups
    names = {tuple(vv.vector_name(m) for m in g) for g in row.groups}
    assert ("u_s1^u1", "u_s1^u2") in names and ("u_m1^u1", "u_m1^u2") in names
    assert t.max_members == 2


def test_every_row_consistent() -> None:
    t = cd.derive_candidate_table()
    assert len(t.rows) == 27 * 12
    for r in t.rows:
        src = r.source_sector
        for g in r.groups:
            assert len({vv.vector_key(m) for m in g}) == 1
            for m in g:
                assert tr.vector_allowed_after_state(r.prev_state, m)
                assert tr.is_63_candidate(m)
                assert m == v.OOO or cd.in_sector(vv.vector_angle_deg(m), src)
        keys = [vv.vector_key(g[0]) for g in r.groups]
        assert len(keys) == len(set(keys))
        assert r.groups == cd.sector_groups(r.prev_state, src)


def test_group_counts_after_fallback() -> None:
    t = cd.derive_candidate_table()
    for s in cd.applied_states_63() + (v.NNN,):
        for k in range(12):
            r = t.row(s, k)
            assert 3 <= r.n_groups <= 7 and not r.short
    assert set(rp.group_count_histogram()) == set(pub.PUBLISHED_GROUP_COUNTS)
    # PPP (never applied: 63-MPDTC's zero is OOO) cannot reach 3 groups anywhere
    assert all(t.row(v.PPP, k).short and t.row(v.PPP, k).n_groups == 2 for k in range(12))


def test_fallback_is_nearest_ccw_first() -> None:
    t = cd.derive_candidate_table()
    for s in cd.applied_states_63():
        for k in range(12):
            r = t.row(s, k)
            if not r.fallback:
                assert len(cd.sector_groups(s, k)) >= 3
                continue
            order = cd.sector_search_order(k)
            pos = order.index(r.source_sector)
            assert all(len(cd.sector_groups(s, j)) < 3 for j in order[:pos])
    assert cd.sector_search_order(0)[:5] == (0, 1, 11, 2, 10)


def test_seed_fallback_example() -> None:
    ok, text = rp.fallback_example_check()
    assert ok, text
    r = cd.derive_candidate_table().row(S("PNN"), 5)
    assert r.source_sector == 1


def test_sector_border_membership() -> None:
    assert cd.in_sector(0.0, 0) and cd.in_sector(0.0, 11) and cd.in_sector(30.0, 1)
    assert cd.in_sector(359.9999999999, 0) and not cd.in_sector(31.0, 0)
    assert set(cd.sector_vectors(0)) >= {S("PON"), S("PNN"), S("POO"), S("ONN")}


def test_determinism() -> None:
    a = cd.derive_candidate_table()
    cd.derive_candidate_table.cache_clear()
    b = cd.derive_candidate_table()
    assert a == b and a is not b
    assert rp.tables_report() == rp.tables_report()


# --- seed Table 3 comparison ---------------------------------------------------

def test_published_table3_transcription() -> None:
    assert [r.prev for r in pub.TABLE3_SECTOR_I] == list(range(19))
    for r in pub.TABLE3_SECTOR_I:
        assert len(r.candidates) == r.printed.count(",") + 1


def test_table3_comparison() -> None:
    checks = rp.table3_check()
    status = {c.prev_label: c.status for c in checks}
    differs = {k for k, s in status.items() if s == "DIFFERS"}
    assert differs == {"u2 (OON)", "u2 (PPO)", "u3 (NON)", "u3 (OPO)", "u4 (NOO)", "u4 (OPP)",
                       "u6 (POP)", "u13 (NPP)"}
    for k in ("u0 (OOO)", "u7 (PNN)", "u8 (PON)", "u9 (PPN)", "u1 (ONN)", "u6 (ONO)"):
        assert status[k] == "MATCH"


def test_table2_and_report() -> None:
    assert all(c.match for c in rp.table2_check())
    text = rp.tables_report()
    assert "u7 (PNN): {u1, u7, u_L1, u_s1^u1, u_m1^u1, u8}  MATCH" in text
    assert "DIFFERS" in text and "ONN-PNN-PON-POO-PON-PNN-ONN" in text
