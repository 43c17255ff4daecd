"""The float32 guard compares bit patterns (a fast path for all checks at once, then the exact checks);
the reference compares values: the same faults for every input (limits exactly, one ulp either side,
signed zeros, infinities, NaNs of either sign with three payloads each, subnormals), and the generated sin/cos
table-index rounding is C99's roundf."""
from __future__ import annotations

import ctypes
import ctypes.util

import numpy as np
import pytest

from codegen.kernels.guard import Check, guard_ops
from codegen.numfmt.float32 import FLOAT32, Float32
from codegen.stages.verify import mismatch_mask
from codegen.topologies.ttype.records import FAULT as TTYPE_FAULT
from codegen.topologies.ttype.records import GUARD as TTYPE_GUARD
from codegen.topologies.twolevel.records import FAULT as TWO_LEVEL_FAULT
from codegen.topologies.twolevel.records import GUARD as TWO_LEVEL_GUARD
from codegen.topology import topology_of

from conftest import EXAMPLES, model_for

CASES = {
    "two-level": (EXAMPLES / "seed001_spmsm.toml", {"strategy": "conventional", "tables": "published"},
                  TWO_LEVEL_GUARD),
    "t-type": (EXAMPLES / "seed000_tlevel.toml", {"strategy": "mpdtc63"}, TTYPE_GUARD),
}
FAULT = {"two-level": TWO_LEVEL_FAULT, "t-type": TTYPE_FAULT}

_SPECIAL_BITS = (0x7F800000, 0xFF800000, 0x7FC00000, 0xFFC00000, 0x7F800001, 0xFF800001, 0x7FFFFFFF,
                 0xFFFFFFFF, 0x00000001, 0x80000001, 0x00000000, 0x80000000, 0x7F7FFFFF, 0xFF7FFFFF)


def edge_values(limit: np.float32) -> np.ndarray:
    """A limit's neighbourhood and every special float32 pattern."""
    inf = np.float32(np.inf)
    near = [limit, np.nextafter(limit, inf), np.nextafter(limit, np.float32(0))]
    near += [-v for v in near]
    return np.concatenate([np.array(near, np.float32), np.array(_SPECIAL_BITS, np.uint32).view(np.float32)])


def edge_states(base: np.ndarray, check: Check, limit: np.float32) -> list[np.ndarray]:
    """The base state with each checked field at each edge value (a range check under an index
    condition: with the index at both ends of its range and just outside it)."""
    rows = []
    indices = (check.first - 1, check.first, check.last) if check.kind == "real_in_range_when" else (None,)
    for field in check.fields:
        for idx in indices:
            for v in edge_values(limit):
                x = base.copy()
                x[field] = v
                if idx is not None:
                    x[check.index] = idx
                rows.append(x)
    return rows


def _edge_run(name: str) -> tuple[np.ndarray, np.ndarray, str]:
    path, overrides, guard = CASES[name]
    m = model_for(path, **overrides)
    topo = topology_of(m)
    t = topo.derive(m)
    base = topo.random_states(m, t, 1, seed=3)
    rows = []
    for check in guard:
        if check.limit:
            rows += edge_states(base, check, np.float32(t.const(check.limit)))
    x = np.concatenate(rows)
    source = topo.render(m, t, "host")[f"{m.prefix}_mpc.c"]
    return topo.step_batch(t, x), topo.host_library(m, t).step_batch(x), source


@pytest.mark.parametrize("name", sorted(CASES))
def test_bit_pattern_guard_gives_the_reference_faults(name: str) -> None:
    guard = CASES[name][2]
    ref, c, source = _edge_run(name)
    for check in guard:
        if check.limit:  # the bit form is in use for every limit
            assert f"_{check.limit}_BITS" in source, check.limit
    assert np.array_equal(ref["fault"], c["fault"])
    for check in guard:
        if check.limit:  # both sides of every limit were reached: its fault bit set and clear
            bit = ref["fault"] & FAULT[name][check.fault]
            assert bit.any() and not bit.all(), check.fault
    assert not mismatch_mask(ref, c)[0].any()


#: a limit of each check kind taken out of the bit form: the guard's value-compare fallback
WITHOUT_BITS = {"two-level": ("UDC_MIN_V", "UDC_MAX_V", "I_TRIP_A"), "t-type": ("UC_MIN_V", "TS3_S", "ANGLE_GUARD_RAD")}


@pytest.mark.parametrize("name", sorted(CASES))
def test_limits_without_bit_patterns_fall_back_to_value_compares(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    # a limit whose float32 pattern the guard cannot use (a config could round one to zero) is
    # compared as a value, in the fast path and the exact checks alike
    real = Float32.guard_bits
    m = model_for(CASES[name][0], **CASES[name][1])
    t = topology_of(m).derive(m)
    dropped = {repr(t.const(n)) for n in WITHOUT_BITS[name]}
    monkeypatch.setattr(Float32, "guard_bits", lambda self, x: None if repr(x) in dropped else real(self, x))
    ref, c, source = _edge_run(name)
    for limit in WITHOUT_BITS[name]:
        assert f"_{limit}_BITS" not in source, limit
    assert np.array_equal(ref["fault"], c["fault"])
    assert not mismatch_mask(ref, c)[0].any()


def test_round_away_is_c99_roundf() -> None:
    libm = ctypes.CDLL(ctypes.util.find_library("m"))
    libm.roundf.restype, libm.roundf.argtypes = ctypes.c_float, [ctypes.c_float]
    ulp_below_half = np.nextafter(np.float32(0.5), np.float32(0))
    x = np.array([0.5, -0.5, 1.5, 2.5, -2.5, ulp_below_half, -ulp_below_half, 0.0, -0.0, -0.3, 162.49998, 163.5,
                  8388607.5, 1e30, -1e30], np.float32)
    x = np.concatenate([x, np.random.default_rng(7).uniform(-200, 200, 20_000).astype(np.float32)])
    got = FLOAT32.ops.round_away(x)
    want = np.array([libm.roundf(float(v)) for v in x], np.float32)
    assert np.array_equal(got.view(np.uint32), want.view(np.uint32))  # equal bits, signed zeros included


@pytest.mark.parametrize("name", CASES)
def test_the_bound_counts_every_compare_of_the_fast_path(name: str) -> None:
    """guard_ops (the cycle bounds' guard operations) counts one compare per compare the generated
    fast path makes, plus the branch on their union, and the sum i_a + i_b as an add."""
    path, overrides, guard = CASES[name]
    m = model_for(path, **overrides)
    topo = topology_of(m)
    source = topo.render(m, topo.derive(m), "host")[f"{m.prefix}_mpc.c"]
    fast = source[source.index(f"static inline uint16_t {m.prefix}_guard("):]
    fast = fast[:fast.index("\n}\n")]
    compares = sum(fast.count(f"{m.prefix}_{op}(") for op in ("abs_over", "below", "above"))
    compares += fast.count("(uint32_t)in->")  # an index's upper limit, an index range test
    ops = guard_ops(guard)
    assert compares == ops["cmp"] - 1
    assert ops["add"] == fast.count(" isum = ")  # the sum i_a + i_b (the one operation writing a value)
