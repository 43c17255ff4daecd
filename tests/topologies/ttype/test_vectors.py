"""Three-level switching states and basic vectors (mpdtc-three-level.md
"Inverter, vectors, neutral point"; seed 000 Fig. 2, Table 1)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.topologies.ttype import published as pub
from codegen.topologies.ttype import vectors as v


def test_27_states_19_distinct_vectors() -> None:
    assert len(v.STATES) == 27
    assert len({s.name for s in v.STATES}) == 27
    assert len({s.key for s in v.STATES}) == 19
    assert len(v.BASIC_STATES) == 19
    assert sorted(i for b in v.BASIC_STATES for i in b) == list(range(27))
    # identical key <=> identical voltage
    ux, uy = v.state_voltages()
    for s in v.STATES:
        for t in v.STATES:
            same = math.hypot(ux[s.index] - ux[t.index], uy[s.index] - uy[t.index]) < 1e-12
            assert same == (s.key == t.key)


def test_index_and_names() -> None:
    assert v.STATES[0].name == "NNN" and v.STATES[13].name == "OOO" and v.STATES[26].name == "PPP"
    for s in v.STATES:
        assert v.state_index(s.levels) == s.index
        assert v.state_by_name(s.name) == s.index
        assert v.state_by_name(s.name.lower()) == s.index
    with pytest.raises(ValueError):
        v.state_by_name("PXN")
    with pytest.raises(ValueError):
        v.state_index((2, 0, 0))


def test_kinds_and_magnitudes() -> None:
    counts = {k: sum(s.kind == k for s in v.STATES) for k in v.MAGNITUDE}
    assert counts == {"zero": 3, "small": 12, "medium": 6, "large": 6}
    for s in v.STATES:
        assert math.hypot(s.alpha, s.beta) == pytest.approx(v.MAGNITUDE[s.kind], abs=1e-15)
    assert v.MAGNITUDE["small"] == pytest.approx(1 / 3)
    assert v.MAGNITUDE["medium"] == pytest.approx(math.sqrt(3) / 3)
    assert v.MAGNITUDE["large"] == pytest.approx(2 / 3)


def test_seed_table1_classes() -> None:
    for kind, names in pub.TABLE1_VECTOR_CLASSES.items():
        assert {v.STATES[v.state_by_name(n)].kind for n in names} == {kind}
    assert sum(len(n) for n in pub.TABLE1_VECTOR_CLASSES.values()) == 27


def test_space_vector_definition() -> None:
    """u = (2/3)(Sa + a Sb + a^2 Sc) Udc/2, per unit of Udc."""
    a = complex(-0.5, math.sqrt(3) / 2)
    udc = 220.0
    for s in v.STATES:
        sa, sb, sc = s.levels
        u = (2 / 3) * (sa + a * sb + a * a * sc) * udc / 2
        assert s.alpha * udc == pytest.approx(u.real, abs=1e-12)
        assert s.beta * udc == pytest.approx(u.imag, abs=1e-12)
    ux, uy = v.state_voltages()
    assert ux.dtype == np.float64 and uy.shape == (27,)


def test_seed_numbering() -> None:
    names = {n: tuple(v.STATES[i].name for i in v.BASIC_STATES[n]) for n in range(19)}
    assert names[0] == ("NNN", "OOO", "PPP")
    assert names[1] == ("ONN", "POO")
    assert names[2] == ("OON", "PPO")
    assert names[7] == ("PNN",) and names[8] == ("PON",) and names[9] == ("PPN",)
    assert names[10] == ("OPN",) and names[18] == ("PNO",) and names[17] == ("PNP",)
    for n in range(1, 7):
        for i in v.BASIC_STATES[n]:
            assert v.STATES[i].angle_deg == pytest.approx(60 * (n - 1))
    for n in range(7, 19):
        (i,) = v.BASIC_STATES[n]
        s = v.STATES[i]
        assert s.angle_deg == pytest.approx(30 * (n - 7))
        assert s.kind == ("large" if n % 2 else "medium")
    ux, uy = v.basic_voltages()
    assert ux[7] == pytest.approx(2 / 3) and uy[7] == 0.0


def test_small_pairs() -> None:
    for n in range(1, 7):
        nt, pt = v.STATES[v.n_type(n)], v.STATES[v.p_type(n)]
        assert nt.small_type == "N" and 1 not in nt.levels
        assert pt.small_type == "P" and -1 not in pt.levels
        assert tuple(x + 1 for x in nt.levels) == pt.levels
    with pytest.raises(ValueError):
        v.n_type(7)


def test_neutral_point_coefficients() -> None:
    assert v.STATES[v.state_by_name("POO")].io == (0, 1, 1)
    assert v.STATES[v.state_by_name("ONN")].io == (1, 0, 0)
    assert v.STATES[v.state_by_name("PON")].io == (0, 1, 0)
    for name in ("PNN", "PPP", "NNN"):
        assert v.STATES[v.state_by_name(name)].io == (0, 0, 0)
    assert v.STATES[v.OOO].io == (1, 1, 1)
    # with balanced currents the two states of a small pair draw opposite i_o
    rng = np.random.default_rng(0)
    m = v.io_matrix()
    for _ in range(20):
        ia, ib = rng.normal(size=2)
        i = np.array([ia, ib, -ia - ib])
        for n in range(1, 7):
            assert m[v.n_type(n)] @ i == pytest.approx(-(m[v.p_type(n)] @ i))
        assert m[v.OOO] @ i == pytest.approx(0.0)
