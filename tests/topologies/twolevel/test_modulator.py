"""The generated two-level modulator (docs/modulator.md), compiled for the host and driven by the Python
reference's decisions.

Decisions: chains of the reference step over the random test states (codegen/topologies/twolevel/states.py),
each state's prev_sw the chain's previous decision (after gates off: 000).  Every decision goes through
the C compare function and the compares through a model of the timers with dead time
(tests/fixtures/modwave.py).  Checked: compare = A for a leg at 1, 0 for a leg at 0, within [0, A]; per
leg the upper and lower switch never on together, each period's state applied (upper on iff the bit is
1, but for the dead time after a change), every gate pulse at least a period less the dead time; the
delay convention of the example's timer set-up (compare preloaded with delay compensation, written at
once without).
"""
from __future__ import annotations

import numpy as np
import pytest

from codegen.config import load_config
from codegen.pwm import pwm_timing
from codegen.topologies.twolevel import modulator as mod
from codegen.topologies.twolevel import plugin
from tests.fixtures.modwave import build_modulator, channel_waveforms, gate_waveforms, on_pulses, pieces

from conftest import SPMSM

TARGETS = ("stm32h743", "tms320f28377")
CHAINS, STEPS = 150, 20  # 3000 decisions per strategy


def cdef(prefix: str, f28: bool) -> str:
    return f"""
void {prefix}_mod_compare(uint16_t sw, uint16_t compare[3]);
uint16_t {prefix}_mod_gates(uint16_t sw);
""" + (f"uint16_t {prefix}_mod_force(uint16_t compare);\n" if f28 else "")


def model_for(strategy: str, delay: bool = False):
    return load_config(SPMSM, {"controller.strategy": strategy, "controller.tables": "published",
                               "controller.delay_compensation": delay})


def decision_chains(model, tables, chains: int, steps: int, seed: int) -> np.ndarray:
    """(steps, chains) output records: each chain's decisions in a row."""
    states = plugin.random_states(model, tables, chains * steps, seed).reshape(steps, chains)
    out = []
    for k in range(steps):
        x = states[k].copy()
        if out:
            x["prev_sw"] = np.where(out[-1]["gates_off"] != 0, 0, out[-1]["sw"])
        out.append(plugin.step_batch(tables, x))
    return np.stack(out)


@pytest.fixture(scope="module", params=[(s, t) for s in ("conventional", "s1", "s3") for t in TARGETS],
                ids=lambda p: f"{p[0]}-{p[1]}")
def case(request, tmp_path_factory):
    strategy, target = request.param
    model = model_for(strategy)
    tables = plugin.derive(model)
    files = mod.render_modulator(model, tables, target)
    ffi, lib = build_modulator(files, model.prefix, cdef(model.prefix, target == "tms320f28377"),
                               tmp_path_factory.mktemp(f"mod2_{strategy}_{target}"))
    timing = pwm_timing(model, target, mod.PULSES_PER_PERIOD)
    return {"model": model, "ffi": ffi, "lib": lib, "timing": timing, "target": target,
            "out": decision_chains(model, tables, CHAINS, STEPS, seed=7)}


def _compare(case, sw: int) -> list[int]:
    c = case["ffi"].new("uint16_t[3]")
    getattr(case["lib"], f"{case['model'].prefix}_mod_compare")(sw, c)
    return list(c)


def test_compares_and_gate_words_of_every_state(case):
    a = case["timing"].period_counts
    p = case["model"].prefix
    for sw in range(8):
        bits = [(sw >> 2) & 1, (sw >> 1) & 1, sw & 1]
        assert _compare(case, sw) == [a * b for b in bits]
        g = getattr(case["lib"], f"{p}_mod_gates")(sw)
        assert [(g >> (2 * leg)) & 3 for leg in range(3)] == [1 if b else 2 for b in bits]  # upper xor lower
    assert _compare(case, 8) == _compare(case, 0) and _compare(case, 0xFFFF) == [0, 0, 0]  # the safe 000
    if case["target"] == "tms320f28377":  # whole periods are the continuous force
        force = getattr(case["lib"], f"{p}_mod_force")
        assert (force(0), force(a), force(a // 2)) == (1, 2, 0)


def test_gates_over_the_decision_chains(case):
    a, dead = case["timing"].period_counts, case["timing"].dead_time_counts
    t = 2 * a
    end = STEPS * t
    out = case["out"]
    for j in range(CHAINS):
        sws = [int(x) for x in out["sw"][:, j]]
        cmp = np.array([_compare(case, sw) for sw in sws])
        assert cmp.min() >= 0 and cmp.max() <= a
        ref = channel_waveforms(cmp, cmp, a)
        for leg in range(3):
            upper, lower = gate_waveforms(ref[leg], end, dead)
            starts, ends, val = pieces([upper, lower], end)
            assert not np.any(val[0] & val[1]), (j, leg)  # never both switches of a leg
            for k, sw in enumerate(sws):  # the decision holds the period, but for the dead time
                bit = (sw >> (2 - leg)) & 1
                inside = (starts >= k * t + dead) & (ends <= (k + 1) * t)
                assert np.all(val[0][inside] == bit) and np.all(val[1][inside] == 1 - bit), (j, leg, k)
            off = (val[0] == 0) & (val[1] == 0)  # both off only for a dead time after a change
            assert np.all(ends[off] - starts[off] == dead), (j, leg)
            for g in (upper, lower):
                assert all(w >= t - dead for w in on_pulses(g, end)), (j, leg)
    assert len(set(out["sw"].ravel().tolist())) >= 7  # the chains use (nearly) every state


@pytest.mark.parametrize("delay", [False, True], ids=["at-once", "delay-compensated"])
@pytest.mark.parametrize("target", TARGETS)
def test_delay_convention_of_the_example(delay, target):
    """With delay compensation the compares are shadowed (loaded at the next period start: STM32 OCxPE
    preload, written at the peak; F28377 CMPA and the continuous force loaded at CTR = 0); without it
    they are written at once (no preload, immediate mode)."""
    model = model_for("s1", delay)
    ctx = mod.modulator_context(model, plugin.derive(model), target)
    text = mod.render_modulator(model, plugin.derive(model), target)[f"{model.prefix}_isr_example.c"]
    if target == "stm32h743":
        ccmr1 = next(w.value for w in ctx["setup"]["tim1"] if w.reg.startswith("TIM_CCMR1"))
        assert bool(ccmr1 & (1 << 3)) == delay and bool(ccmr1 & (1 << 11)) == delay  # OC1PE, OC2PE
        assert ("isr_write(spmsm_isr_next)" in text) == delay  # the peak branch writes the next period
    else:
        cmpctl = next(w.value for w in ctx["setup"]["epwm"][0] if "_CMPCTL(" in w.reg)
        aqsfrc = next(w.value for w in ctx["setup"]["epwm"][0] if "_AQSFRC(" in w.reg)
        assert (cmpctl, aqsfrc >> 6) == ((0, 0) if delay else (1 << 4, 3))  # shadow at zero / immediate
    assert ("delay_compensation = true" in text) == delay and ("delay_compensation = false" in text) != delay
