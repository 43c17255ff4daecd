"""Virtual vectors: triangles, derived 7-segment sequences (mpdtc-three-level.md
"Virtual vectors (section 2.1, Table 2)"; seed 000 eq. (8)-(9), Table 2)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.topologies.ttype import published as pub
from codegen.topologies.ttype import vectors as v
from codegen.topologies.ttype import virtual as vv


def test_24_triangles() -> None:
    assert len(vv.TRIANGLES) == 24
    kinds = [t.kind for t in vv.TRIANGLES]
    assert (kinds.count("small"), kinds.count("medium"), kinds.count("large")) == (6, 6, 12)
    assert len({t.vertices for t in vv.TRIANGLES}) == 24
    assert vv.TRIANGLES[0].vertices == (0, 1, 2)  # u_s1 = {u0, u1, u2}
    assert vv.TRIANGLES[6].vertices == (1, 2, 8)  # u_m1 = {u1, u2, u8}
    assert vv.TRIANGLES[12].vertices == (1, 7, 8)  # u_L1 = {u1, u7, u8}
    assert vv.TRIANGLES[23].vertices == (1, 7, 18)  # u_L12


def test_36_virtual_vectors_24_voltages() -> None:
    assert len(vv.VIRTUAL) == 36
    assert [x.id for x in vv.VIRTUAL] == list(range(27, 63))
    assert len({x.name for x in vv.VIRTUAL}) == 36
    assert len({x.key for x in vv.VIRTUAL}) == 24
    assert len({(round(x.alpha, 12), round(x.beta, 12)) for x in vv.VIRTUAL}) == 24
    kinds = [x.kind for x in vv.VIRTUAL]
    assert (kinds.count("small"), kinds.count("medium"), kinds.count("large")) == (12, 12, 12)
    # no virtual voltage coincides with a basic one
    assert not {x.key for x in vv.VIRTUAL} & {vv.vector_key(i) for i in range(27)}
    assert vv.N_VECTORS == 63


def test_names_and_angles() -> None:
    for k in range(1, 7):
        for kind in ("s", "m"):
            for split in (k, k % 6 + 1):
                x = vv.virtual_by_name(f"u_{kind}{k}^u{split}")
                assert x.angle_deg == pytest.approx(30 + 60 * (k - 1))
                assert x.group_name == f"u_{kind}{k}"
    for k in range(1, 13):
        x = vv.virtual_by_name(f"u_L{k}")
        assert 30 * (k - 1) < x.angle_deg < 30 * k
    with pytest.raises(ValueError):
        vv.virtual_by_name("u_L13")


def test_centroid_is_mean_of_vertices() -> None:
    for x in vv.VIRTUAL:
        tri = vv.TRIANGLES[x.triangle]
        ux, uy = v.basic_voltages()
        assert x.alpha == pytest.approx(np.mean(ux[list(tri.vertices)]), abs=1e-15)
        assert x.beta == pytest.approx(np.mean(uy[list(tri.vertices)]), abs=1e-15)


def test_sequence_rule() -> None:
    for x in vv.VIRTUAL:
        seq = x.sequence
        assert len(seq) == 7 and seq == seq[::-1]
        assert seq[0] == v.n_type(x.split) and seq[3] == v.p_type(x.split)
        tri = vv.TRIANGLES[x.triangle]
        assert {v.STATES[s].number for s in seq} == set(tri.vertices)
        for a, b in zip(seq, seq[1:]):
            d = [q - p for p, q in zip(v.STATES[a].levels, v.STATES[b].levels)]
            assert sorted(abs(e) for e in d) == [0, 0, 1]  # one leg, one level
        assert x.start_state == x.end_state == seq[0]


def test_paths_unique() -> None:
    for x in vv.VIRTUAL:
        assert len(vv.sequence_paths(vv.TRIANGLES[x.triangle], x.split)) == 1


def test_seed_table2_exact() -> None:
    for row in pub.TABLE2_SEQUENCES:
        assert vv.virtual_by_name(row.name).sequence_names() == row.sequence
    assert vv.virtual_by_name("u_s1^u1").sequence_names() == "ONN-OON-OOO-POO-OOO-OON-ONN"
    assert vv.virtual_by_name("u_L2").sequence_names() == "OON-PON-PPN-PPO-PPN-PON-OON"


def test_split_versions() -> None:
    for tri in vv.TRIANGLES:
        versions = [x for x in vv.VIRTUAL if x.triangle == tri.index]
        assert len(versions) == (1 if tri.kind == "large" else 2)


def test_segment_times_average_is_centroid() -> None:
    ts = 50e-6
    ux, uy = v.state_voltages()
    for x in vv.VIRTUAL:
        for t_n in (0.0, ts / 6, 0.3 * ts / 3, ts / 3):
            t = vv.segment_times(t_n, ts)
            assert t.sum() == pytest.approx(ts, rel=1e-15)
            assert t[0] == t[6] == t_n / 2 and t[3] == pytest.approx(ts / 3 - t_n)
            avg = (t @ ux[list(x.sequence)] / ts, t @ uy[list(x.sequence)] / ts)
            assert avg[0] == pytest.approx(x.alpha, abs=1e-14)
            assert avg[1] == pytest.approx(x.beta, abs=1e-14)
    with pytest.raises(ValueError):
        vv.segment_times(ts / 2, ts)
    assert vv.SEGMENT_ROLES == ("N", "b", "c", "P", "c", "b", "N")


def test_id_space() -> None:
    assert vv.vector_name(21) == "PON" and vv.start_state(21) == 21
    x = vv.virtual_by_name("u_m1^u2")
    assert vv.vector_name(x.id) == "u_m1^u2"
    assert vv.start_state(x.id) == vv.end_state(x.id) == v.state_by_name("OON")
    assert vv.vector_group_name(x.id) == "u_m1" and vv.vector_group_name(v.OOO) == "u0"
    assert vv.vector_magnitude(x.id) == pytest.approx(math.hypot(x.alpha, x.beta))
    ux, uy = vv.vector_voltages()
    assert ux.shape == (63,) and ux[x.id] == x.alpha
    with pytest.raises(ValueError):
        vv.vector_name(63)
