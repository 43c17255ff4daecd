"""T-type three-level MPDTC step (mpdtc-three-level.md, numerics.md): strict
compilation for every target profile, deterministic rendering, bit-for-bit
equality of the generated C and the Python reference, and the decision's
properties (switching constraint, T_N range, segment times)."""
from __future__ import annotations

import numpy as np
import pytest

from codegen.config import load_config
from codegen.stages.verify import verify_strategy
from codegen.topologies.ttype import plugin as PLUGIN
from codegen.topologies.ttype import reference
from codegen.topologies.ttype import transitions as tr
from codegen.topologies.ttype import vectors as v
from codegen.topologies.ttype import virtual as vv
from codegen.topologies.ttype.derive import t_n_min
from codegen.topologies.ttype.records import FAULT, INPUT_DTYPE, SAFE_STATE
from codegen.topologies.ttype.states import adversarial_states, random_states

from conftest import (
    TTYPE,
    TTYPE_STRATEGIES,
    assert_c28x_clean,
    assert_symbols_prefixed,
    compile_m7,
    compile_strict,
)

STRATEGIES = TTYPE_STRATEGIES


def model(strategy: str):
    return load_config(TTYPE, {"controller.strategy": strategy})


def derive(m):
    """The T-type tables of ``m`` (through the plugin interface)."""
    return PLUGIN.derive(m)


def render(m, t, target: str) -> dict[str, str]:
    """File name -> generated C text for ``target``."""
    return PLUGIN.render(m, t, target)


@pytest.fixture(scope="module", params=STRATEGIES)
def built(request):
    m = model(request.param)
    t = derive(m)
    return m, t, PLUGIN.host_library(m, t)


def _write(tmp_path, files):
    for name, text in files.items():
        (tmp_path / name).write_text(text)


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_compiles_strict_for_every_target(tmp_path, strategy):
    m = model(strategy)
    t = derive(m)
    for target in ("host", "stm32h743", "tms320f28377"):
        d = tmp_path / target
        d.mkdir()
        files = render(m, t, target)
        _write(d, files)
        src = d / f"{m.prefix}_mpc.c"
        compile_strict(src, d / "x.o")
        if target == "stm32h743":
            compile_m7(src, d / "m7.o")
        if target == "tms320f28377":
            for name, text in files.items():
                assert_c28x_clean(name, text)
        assert "#define MPC_TOPOLOGY_THREE_LEVEL 1" in files["mpc_binding.h"]


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_every_symbol_is_prefixed(tmp_path, strategy):
    m = model(strategy)
    _write(tmp_path, render(m, derive(m), "host"))
    assert_symbols_prefixed(tmp_path / f"{m.prefix}_mpc.c", tmp_path / "x.o", m.prefix)


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_rendering_is_deterministic(strategy):
    m = model(strategy)
    for target in ("host", "stm32h743", "tms320f28377"):
        a = render(m, derive(m), target)
        b = render(model(strategy), derive(model(strategy)), target)
        assert a == b


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_bit_for_bit_200k(strategy):
    r = verify_strategy(model(strategy), 200_000, log=lambda _m: None).as_dict()
    assert r["states"] >= 200_000
    assert r["mismatches"] == 0, r["first_mismatch"]
    assert 0 < r["faulted_states"] < r["states"] // 5


@pytest.mark.slow
@pytest.mark.parametrize("strategy", STRATEGIES)
def test_bit_for_bit_1e6(strategy):
    r = verify_strategy(model(strategy), 1_000_000, log=lambda _m: None).as_dict()
    assert r["mismatches"] == 0, r["first_mismatch"]


def _decisions(m, t, lib, n=60_000):
    x = np.concatenate([random_states(m, n, seed=5), adversarial_states(m, t, n_target=n // 2, seed=6)])
    out = lib.step_batch(x)
    ok = out["fault"] == 0
    return x[ok], out[ok]


def _rows(t, x, out):
    """Each step's candidate row: the state applied last x the sector of u* (63-MPDTC)."""
    return np.asarray(t.end_state)[x["prev_vector"]] * 12 + (out["sector"].astype(np.int64) - 1)


def _per_row(t, count):
    """count(member vector id) summed over each row's groups' members, per row."""
    return np.array([sum(count(v) for g in row for v in t.groups[g]) for row in t.row_groups])


def test_63_evaluates_3_to_7_costs(built):
    m, t, lib = built
    x, out = _decisions(m, t, lib)
    if t.strategy == "mpdtc27":
        assert (out["n_eval"] == 19).all() and (out["n_members"] == 27).all() and out["costs"].shape[1] == 19
        return
    # PPP is never applied by 63-MPDTC (its zero is OOO); its rows are short
    normal = x["prev_vector"] != v.PPP
    assert ((out["n_eval"][normal] >= 3) & (out["n_eval"][normal] <= 7)).all()
    assert (out["n_eval"] == out["n_groups"]).all()
    # every step evaluates its row's groups (row = state applied last x sector of u*) and resolves
    # every member of them; the states reach every row length of the table
    rows = _rows(t, x, out)
    assert np.array_equal(out["n_eval"], np.asarray(t.row_n)[rows])
    assert np.array_equal(out["n_members"], _per_row(t, lambda v: 1)[rows])
    assert set(np.unique(out["n_eval"][normal]).tolist()) == {n for n in t.row_n if n >= 3}
    # the record holds as many slots as the longest row (7), costs beyond n_eval are zero;
    # the chosen candidate is the cheapest
    slots = out["costs"].shape[1]
    assert slots == out["cand"].shape[1] == t.max_groups == out["n_eval"].max() == 7
    for j in range(slots):
        beyond = j >= out["n_eval"]
        assert (out["costs"][beyond, j] == 0).all() and (out["cand"][beyond, j] == 0).all()
    assert np.array_equal(out["cost_best"], np.min(np.where(np.arange(slots) < out["n_eval"][:, None], out["costs"], np.inf), axis=1).astype(np.float32))


def test_deadbeat_counts_are_the_rows_virtual_members(built):
    """The cycle bound's multiplicities (plugin.op_multiplicities): every virtual member of the
    step's row is counted, and a T_N counted unclamped only when its quotient is inside the range
    (a virtual winner with T_N strictly inside (T_N_min, Ts/3) is one of them)."""
    m, t, _lib = built
    x = np.concatenate([random_states(m, 20_000, seed=7), adversarial_states(m, t, n_target=10_000, seed=8)])
    out = reference.step_batch(t, x)
    x, out = x[out["fault"] == 0], out[out["fault"] == 0]
    mult = PLUGIN.op_multiplicities(m, t, x, out)
    assert np.array_equal(mult["per_candidate"], out["n_eval"]) and np.array_equal(mult["per_member"], out["n_members"])
    virtual, unclamped = mult["per_virtual_member"], mult["per_unclamped"]
    if t.strategy == "mpdtc27":  # no virtual vectors
        assert not virtual.any() and not unclamped.any()
        return
    assert np.array_equal(virtual, _per_row(t, lambda v: t.is_virtual[v])[_rows(t, x, out)])
    assert (unclamped <= virtual).all() and unclamped.any() and (unclamped < virtual).any()
    inside = (out["vector"] >= vv.FIRST_VIRTUAL_ID) & (out["t_n_s"] > np.float32(t_n_min(m))) \
        & (out["t_n_s"] < np.float32(m.controller.dt_s / 3.0))
    assert inside.any() and (unclamped[inside] >= 1).all()


def test_switching_constraint_t_n_and_segments(built):
    m, t, lib = built
    x, out = _decisions(m, t, lib)
    ts = m.controller.dt_s
    tmin = np.float32(t_n_min(m))
    allowed = tr.allowed_matrix()
    if t.strategy == "mpdtc63":
        prev_end = np.array([vv.end_state(int(p)) for p in x["prev_vector"]])
        first = out["states"][:, 0].astype(int)
        assert allowed[prev_end, first].all()
        assert (out["vector"] != v.PPP).all() and (out["vector"] != v.NNN).all()
    # inside a sequence every step obeys the constraint too
    for k in range(6):
        assert allowed[out["states"][:, k], out["states"][:, k + 1]].all()
    virt = out["vector"] >= vv.FIRST_VIRTUAL_ID
    assert ((out["t_n_s"][virt] >= tmin) & (out["t_n_s"][virt] <= np.float32(ts / 3))).all()
    assert (out["t_n_s"][~virt] == 0).all()
    seq = np.array([vv.virtual_of(int(i)).sequence if i >= 27 else (int(i),) * 7 for i in out["vector"]])
    assert np.array_equal(out["states"].astype(int), seq)
    assert (out["seg_s"] >= 0).all()
    assert np.allclose(out["seg_s"].astype(np.float64).sum(axis=1), ts, rtol=1e-6, atol=0)
    assert (out["seg_s"][~virt, 1:] == 0).all()


def test_27_reaches_large_line_jumps_63_does_not():
    """27-MPDTC has no switching constraint (spec), so jumps above Udc/2 occur."""
    m = model("mpdtc27")
    t = derive(m)
    lib = PLUGIN.host_library(m, t)
    x, out = _decisions(m, t, lib, n=20_000)
    basic = x["prev_vector"] < 27
    jumps = [tr.line_jump_max(int(p), int(s)) for p, s in zip(x["prev_vector"][basic], out["states"][basic, 0])]
    assert max(jumps) >= 2


def test_guard_gives_safe_decision(built):
    m, t, lib = built
    x = random_states(m, 8, seed=3)
    x["uc1_v"] = 110.0
    x["uc2_v"] = 110.0
    x["ia_a"] = 1.0
    x["ib_a"] = 1.0
    x["theta_e_rad"] = 0.5
    x["omega_e_rad_s"] = 100.0
    x["torque_ref_nm"] = 1.0
    x["prev_vector"] = 13
    x["t_n_prev_s"] = 0.0
    x["ia_a"][0] = np.nan
    x["uc2_v"][1] = 74.0
    x["uc1_v"][2] = 151.0
    x["prev_vector"][3] = 63
    x["prev_vector"][4] = 40
    x["t_n_prev_s"][4] = np.float32(1.0)
    x["torque_ref_nm"][5] = np.inf
    out = lib.step_batch(x)
    ref = reference.step_batch(t, x)
    assert list(out["fault"][:6]) == [FAULT["CURRENT"], FAULT["UDC_LOW"], FAULT["UDC_HIGH"], FAULT["STATE"],
                                      FAULT["TN_PREV"], FAULT["TORQUE_REF"]]
    assert (out["fault"][6:] == 0).all()
    bad = out[:6]
    assert (bad["states"] == SAFE_STATE).all() and (bad["vector"] == SAFE_STATE).all()
    assert (bad["seg_s"][:, 0] == np.float32(m.controller.dt_s)).all() and (bad["seg_s"][:, 1:] == 0).all()
    assert out.tobytes() == ref.tobytes()


def test_input_names_are_the_simulator_contract():
    assert INPUT_DTYPE.names == ("ia_a", "ib_a", "theta_e_rad", "omega_e_rad_s", "uc1_v", "uc2_v",
                                 "torque_ref_nm", "prev_vector", "t_n_prev_s")
