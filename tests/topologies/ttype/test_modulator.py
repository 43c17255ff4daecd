"""The generated T-type modulator (docs/modulator.md), compiled for the host and driven by the Python
reference's decisions.

Decisions: chains of the reference step over the random test states (codegen/topologies/ttype/states.py),
each state's prev_vector / t_n_prev_s the chain's previous decision (after gates off: OOO and 0, as the
header says), so consecutive decisions are what the step gives in a row.  Every decision goes through
the C plan, consecutive plans through the C join, and the compares through a model of the timers with
dead time (tests/fixtures/modwave.py).  Checked: the segment counts sum to the period exactly, every
compare lies in [0, A] and is the nominal edge (widened to the minimum pulse); in every leg only the
three levels and the two dead-time intermediates (T2 alone between P and O, T3 alone between O and N),
never T1 with T4 or a capacitor-shorting pattern, never P <-> N without an O dwell of at least the
minimum pulse less the dead time; every gate pulse at least the minimum pulse less the dead time; for
63-MPDTC the line-voltage jump of one level step at every edge, including between periods.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.config import load_config
from codegen.pwm import pwm_timing
from codegen.topologies.ttype import modulator as mod
from codegen.topologies.ttype import plugin
from codegen.topologies.ttype import vectors as v
from tests.fixtures.modwave import build_modulator, channel_waveforms, gate_waveforms, on_pulses, pieces

from conftest import TTYPE, example

TARGETS = ("stm32h743", "tms320f28377")
CHAINS, STEPS = 150, 20  # 3000 decisions per strategy
P, O, N = (1, 1, 0, 0), (0, 1, 1, 0), (0, 0, 1, 1)
T2_ALONE, T3_ALONE = (0, 1, 0, 0), (0, 0, 1, 0)
LEVEL_OF = {P: 1, O: 0, N: -1}


def cdef(prefix: str, real: str) -> str:
    return f"""
typedef struct {{ uint16_t head[6]; uint16_t tail[6]; }} {prefix}_mod_plan_t;
uint16_t {prefix}_mod_gates(uint16_t state);
uint16_t {prefix}_mod_channels(uint16_t state);
void {prefix}_mod_segment_counts(const {real} seg_s[7], uint32_t counts[7]);
void {prefix}_mod_plan(const uint16_t states[7], const {real} seg_s[7], {prefix}_mod_plan_t *plan);
void {prefix}_mod_join({prefix}_mod_plan_t *applied, {prefix}_mod_plan_t *next);
"""


def decision_chains(model, tables, chains: int, steps: int, seed: int) -> np.ndarray:
    """(steps, chains) output records: each chain's decisions in a row."""
    states = plugin.random_states(model, tables, chains * steps, seed).reshape(steps, chains)
    out = []
    for k in range(steps):
        x = states[k].copy()
        if out:
            prev = out[-1]
            off = prev["gates_off"] != 0
            x["prev_vector"] = np.where(off, v.OOO, prev["vector"])
            x["t_n_prev_s"] = np.where(off, 0, prev["t_n_s"])
        out.append(plugin.step_batch(tables, x))
    return np.stack(out)


class Case:
    """One strategy on one target: the compiled modulator and the reference's decision chains."""

    def __init__(self, strategy: str, target: str, tmp, number_format: str | None = None, **controller: object):
        self.controller = controller
        if controller:  # the example with other controller fields
            self.model = load_config(TTYPE, {"controller.strategy": strategy,
                                             **{f"controller.{k}": x for k, x in controller.items()}})
            self.tables = plugin.derive(self.model)
        else:
            self.model, self.tables = example("tlevel", strategy, number_format)
        self.prefix = self.model.prefix
        files = mod.render_modulator(self.model, self.tables, target)
        real = self.tables.nf.c_type
        self.ffi, self.lib = build_modulator(files, self.prefix, cdef(self.prefix, real), tmp)
        self.real = real
        self.timing = pwm_timing(self.model, target, mod.PULSES_PER_PERIOD)
        self.a = self.timing.period_counts
        self.m = self.timing.min_pulse_counts
        self.out = decision_chains(self.model, self.tables, CHAINS, STEPS, seed=5)

    def fn(self, name: str):
        return getattr(self.lib, f"{self.prefix}_mod_{name}")

    def plan(self, o) -> object:
        p = self.ffi.new(f"{self.prefix}_mod_plan_t *")
        self.fn("plan")(self.ffi.new("uint16_t[7]", [int(s) for s in o["states"]]),
                        self.ffi.new(f"{self.real}[7]", [x.item() for x in o["seg_s"]]), p)
        return p

    def counts(self, o) -> list[int]:
        c = self.ffi.new("uint32_t[7]")
        self.fn("segment_counts")(self.ffi.new(f"{self.real}[7]", [x.item() for x in o["seg_s"]]), c)
        return list(c)

    def chain_compares(self, j: int) -> tuple[np.ndarray, np.ndarray, int]:
        """(head, tail) of chain j's periods after the joins, and how many joins changed a compare."""
        plans = [self.plan(self.out[k, j]) for k in range(STEPS)]
        joins = 0
        for k in range(STEPS - 1):
            before = (list(plans[k].tail), list(plans[k + 1].head))
            self.fn("join")(plans[k], plans[k + 1])
            joins += (list(plans[k].tail), list(plans[k + 1].head)) != before
        head = np.array([list(p.head) for p in plans])
        tail = np.array([list(p.tail) for p in plans])
        return head, tail, joins


#: (strategy, target, controller overrides): the example, and 63-MPDTC with the T_N clamp at 0, whose
#: segments T_N/2 and Ts/3 - T_N reach below the minimum pulse (the compares are widened)
CASES = [(s, t, {}) for s in ("mpdtc27", "mpdtc63") for t in TARGETS] + [("mpdtc63", "stm32h743", {"t_n_min_s": 0.0})]


@pytest.fixture(scope="module", params=CASES,
                ids=lambda p: f"{p[0]}-{p[1]}" + "".join(f"-{k}{x:g}" for k, x in p[2].items()))
def case(request, tmp_path_factory) -> Case:
    strategy, target, controller = request.param
    return Case(strategy, target, tmp_path_factory.mktemp(f"mod_{strategy}_{target}"), **controller)


def test_gate_and_reference_words_follow_the_levels(case):
    for s in v.STATES:
        gates = case.fn("gates")(s.index)
        chans = case.fn("channels")(s.index)
        for leg, level in enumerate(s.levels):
            assert tuple((gates >> (4 * leg + k)) & 1 for k in range(4)) == {1: P, 0: O, -1: N}[level]
            assert (chans >> leg) & 1 == (level != 1) and (chans >> (3 + leg)) & 1 == (level == -1)
    assert case.fn("gates")(27) == case.fn("gates")(v.OOO) and case.fn("channels")(99) == case.fn("channels")(v.OOO)


def test_every_sequence_is_one_run_per_channel_at_each_end(case):
    """What the modulator assumes of the step's 63 vectors: symmetric, each reference a run at the
    start and the mirrored run at the end (sequence_runs asserts it)."""
    for seq in case.tables.seq:
        runs = mod.sequence_runs(seq)
        assert all(0 <= r <= 7 for r in runs)


def _nominal(case, o) -> tuple[list[int], list[set[int]]]:
    """Float64 edges of the first half and, per channel, the compares the C may give: the nominal edge
    (+-1 count for its float32 rounding) widened to the minimum pulse."""
    cps = case.timing.counts_per_s
    seg = case.tables.nf.decode("s", o["seg_s"]) if case.tables.nf.quantised else o["seg_s"].astype(np.float64)
    edges = [0.0]
    for j in range(3):
        edges.append(min(max(edges[-1], float(np.sum(seg[: j + 1])) * cps), case.a))
    a, m = case.a, case.m

    def widen(c: int) -> int:
        c = min(max(c, 0), a)
        return c if c in (0, a) else m if c < m else a - m // 2 if c > a - m // 2 else c

    runs = mod.sequence_runs(tuple(int(s) for s in o["states"]))
    allowed = []
    for r in runs:
        if r > 3:
            allowed.append({a})
        else:
            n = edges[r]  # a run of zero-length segments at the start is kept for the minimum pulse
            low = 1 if r > 0 else 0
            allowed.append({widen(max(c, low)) for c in (math.floor(n) - 1, math.floor(n), math.ceil(n),
                                                          math.ceil(n) + 1)})
    return [round(e) for e in edges], allowed


def test_segment_counts_sum_to_the_period_and_compares_are_the_edges(case):
    n = 0
    for o in case.out.reshape(-1):
        c = case.counts(o)
        assert sum(c) == 2 * case.a, (o["vector"], c)
        assert c[0:3] == c[6:3:-1], c  # mirrored
        p = case.plan(o)
        _, allowed = _nominal(case, o)
        for ch in range(6):
            assert 0 <= p.head[ch] <= case.a and 0 <= p.tail[ch] <= case.a
            assert p.head[ch] == p.tail[ch]  # symmetric sequences give symmetric plans
            assert p.head[ch] in allowed[ch], (int(o["vector"]), ch, p.head[ch], allowed[ch])
            assert p.head[ch] in (0, case.a) or case.m <= p.head[ch] <= case.a - case.m // 2
        n += 1
    assert n == CHAINS * STEPS


def _leg_levels(case, ref, end):
    """Ideal level of each leg (from the references, before dead time) on the elementary pieces."""
    starts, ends, val = pieces(ref, end)
    levels = np.where(val[3:6] == 1, -1, np.where(val[0:3] == 1, 0, 1))
    return starts, ends, levels


def test_gates_in_every_segment_and_edge(case):
    """The 12 gates over every chain, with dead time: valid patterns, allowed transitions, pulses."""
    end = STEPS * 2 * case.a
    dead, m = case.timing.dead_time_counts, case.m
    joins = 0
    for j in range(CHAINS):
        head, tail, nj = case.chain_compares(j)
        joins += nj
        assert head.min() >= 0 and head.max() <= case.a and tail.min() >= 0 and tail.max() <= case.a
        ref = channel_waveforms(head, tail, case.a)
        for leg in range(3):
            t3, t1 = gate_waveforms(ref[leg], end, dead)       # outer: main T3, complementary T1
            t4, t2 = gate_waveforms(ref[3 + leg], end, dead)   # inner: main T4, complementary T2
            starts, ends, val = pieces([t1, t2, t3, t4], end)
            pats = [tuple(int(x) for x in val[:, i]) for i in range(len(starts))]
            for i, pat in enumerate(pats):
                assert pat in (P, O, N, T2_ALONE, T3_ALONE), (j, leg, starts[i], pat)
                assert not (pat[0] and pat[3]) and not (pat[0] and pat[2])
                if pat in (T2_ALONE, T3_ALONE):  # a dead time between two levels one step apart
                    assert 0 < i < len(pats) - 1, (j, leg)
                    pair = {pats[i - 1], pats[i + 1]}
                    assert pair == ({P, O} if pat == T2_ALONE else {O, N}), (j, leg, starts[i], pats[i - 1:i + 2])
                    assert ends[i] - starts[i] == dead
            lv = [LEVEL_OF[p] for p in pats if p in LEVEL_OF]
            assert all(abs(b - a) == 1 for a, b in zip(lv, lv[1:])), (j, leg)  # never P <-> N
            for i, pat in enumerate(pats):  # an O passed through dwells at least M - dead time
                if pat == O and 0 < i < len(pats) - 1 and LEVEL_OF.get(pats[i - 1], 9) != LEVEL_OF.get(pats[i + 1], 9):
                    assert ends[i] - starts[i] >= m - dead, (j, leg, starts[i])
            for g in (t1, t2, t3, t4):
                assert all(w >= m - dead for w in on_pulses(g, end)), (j, leg)
    if case.tables.strategy == "mpdtc27":
        assert joins > 0  # 27-MPDTC jumps P <-> N between periods: the O dwell is exercised
    else:  # 63-MPDTC never jumps P <-> N in a leg (nor does its safe decision OOO); with T_N = 0 only
        # because a period keeps its start state for the minimum pulse
        assert joins == 0


def test_line_voltage_steps_one_level_at_every_edge_63(case):
    """63-MPDTC's switching constraint (transitions.py: every line voltage changes by at most Udc/2)
    holds at every edge of the applied waveform, segment edges and the edges between periods alike.
    Chains with a fault decision are left out: the safe decision ignores the constraint.  27-MPDTC
    has no such constraint: the same check finds line-voltage steps of Udc there (the control that
    the check sees a jump)."""
    end = STEPS * 2 * case.a
    checked, widest = 0, 0
    for j in range(CHAINS):
        if np.any(case.out["fault"][:, j]):
            continue
        head, tail, _ = case.chain_compares(j)
        _, _, levels = _leg_levels(case, channel_waveforms(head, tail, case.a), end)
        d = np.diff(levels, axis=1)
        line = np.stack([d[0] - d[1], d[1] - d[2], d[2] - d[0]])
        widest = max(widest, int(np.abs(line).max(initial=0)))
        if case.tables.strategy == "mpdtc63":
            assert np.abs(line).max(initial=0) <= 1, j
            assert np.abs(d).max(initial=0) <= 1, j
        checked += 1
    assert checked >= CHAINS // 2
    assert (widest <= 1) == (case.tables.strategy == "mpdtc63"), widest


def test_fixed_point_times_give_the_float_counts(tmp_path):
    """The fixed-point modulator's integer conversion of int32 Q seconds gives the float32 modulator's
    segment counts (+-2) for the same times (each fixed output's seg_s decoded exactly and rounded to
    float32), and its counts sum to the period exactly.  (The two formats' controllers may choose
    different T_N where a small midpoint-current difference divides: that is the step's quantisation,
    numerics.md, not the modulator's.)"""
    fx = Case("mpdtc63", "stm32h743", tmp_path / "fx", "fixed")
    fl = Case("mpdtc63", "stm32h743", tmp_path / "fl")
    sc = fx.tables.scaling
    checked = 0
    for ofx in fx.out.reshape(-1)[:1000]:
        if ofx["fault"]:
            continue
        cx = fx.counts(ofx)
        cl = fl.counts({"seg_s": sc.decode("s", ofx["seg_s"]).astype(np.float32)})
        assert sum(cx) == 2 * fx.a
        assert max(abs(a - b) for a, b in zip(cx, cl)) <= 2, (cx, cl)
        checked += 1
    assert checked > 500
