"""From the T-type decision to the 12 gates: the generated modulator and its example interrupt routine
(docs/modulator.md).

A leg of the T-type inverter has four switches: T1 (upper, to the + rail),
T2 and T3 (the bidirectional pair between the leg and the DC midpoint) and
T4 (lower, to the - rail).  Level P = T1 + T2 on, O = T2 + T3 on, N = T3 + T4
on.  T1 and T3 are complementary, and so are T2 and T4, so a leg is two
complementary PWM channels with hardware dead time:

- the *outer* channel: reference "leg not at P"; main output T3,
  complementary output T1 (STM32H743 TIM1 CHx / CHxN, F28377 ePWM1..3 A / B);
- the *inner* channel: reference "leg at N"; main output T4, complementary
  output T2 (STM32H743 TIM8 CHx / CHxN, F28377 ePWM4..6 A / B).

Dead time delays every turn-on, so P -> O passes through "T2 alone" and
O -> N through "T3 alone", never through a pattern that shorts a capacitor.

Every sequence of the step raises one leg by one level per segment
([N, b, c, P, c, b, N], ``virtual``) and is symmetric, so each channel's
reference is active over a run of segments at the start of the period and
the mirrored run at its end: one compare per half period (head, tail).  The
seven segment times become counts that sum to the period exactly; each
compare is widened to the minimum pulse (never dropped, so no two edges
merge); a leg that would jump P <-> N between two periods gets an O dwell of
one minimum pulse (the outer channel's tail of the earlier period or head of
the later one): every leg passes through O.

This module derives the tables and register words once; the templates
(templates/ttype/modulator.*.j2, isr_*.c.j2) format them.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from codegen.model import Model
from codegen.numfmt.float32 import c_float_literal, f32
from codegen.pwm import (
    CSF_HIGH,
    CSF_LOW,
    PwmTiming,
    adc_placeholders,
    f28_epwm_setup,
    isr_inputs,
    pwm_timing,
    render_modulator_files,
    stm32_gpio_setup,
    stm32_timer_setup,
)
from codegen.render import base_context
from codegen.topologies.ttype import vectors as v
from codegen.topologies.ttype.derive import ThreeLevelTables
from codegen.topologies.ttype.records import INPUT, N_SEGMENTS, SAFE_STATE

__all__ = ["GATES", "LEVEL_GATES", "CHANNELS", "Channel", "gate_word", "channel_word", "sequence_runs",
           "PULSES_PER_PERIOD", "timing", "render_modulator"]

#: switch names of one leg, bit order of the gate word (bit 4 leg + k)
GATES: tuple[str, ...] = ("T1", "T2", "T3", "T4")
#: switches on at each level (T1..T4)
LEVEL_GATES: dict[int, tuple[int, int, int, int]] = {1: (1, 1, 0, 0), 0: (0, 1, 1, 0), -1: (0, 0, 1, 1)}
#: the control period must hold this many minimum pulses: the segments Ts/6 are at least two minimum
#: pulses long, so widening a compare to the minimum pulse never merges two edges nor shortens an O
#: dwell below one minimum pulse
PULSES_PER_PERIOD = 12
LEGS = ("a", "b", "c")


@dataclass(frozen=True)
class Channel:
    """One complementary PWM channel: index, leg, kind, reference, gates and pins per target."""

    index: int
    leg: int
    kind: str  # "outer" | "inner"
    reference: str  # when the reference signal is active
    main_gate: str  # driven by CHx / EPWMxA (the reference, rising edge delayed)
    comp_gate: str  # driven by CHxN / EPWMxB (its complement, rising edge delayed)
    stm32_timer: str
    stm32_channel: int
    stm32_pins: tuple[str, str]  # (CHx, CHxN)
    stm32_af: int
    epwm: int
    epwm_pins: tuple[str, str]  # (EPWMxA, EPWMxB)

    def active(self, level: int) -> bool:
        """Whether the reference is active at leg level ``level``."""
        return level != 1 if self.kind == "outer" else level == -1


_STM32_PINS = {("TIM1", 1): ("PE9", "PE8"), ("TIM1", 2): ("PE11", "PE10"), ("TIM1", 3): ("PE13", "PE12"),
               ("TIM8", 1): ("PC6", "PA5"), ("TIM8", 2): ("PC7", "PB0"), ("TIM8", 3): ("PC8", "PB1")}
_STM32_AF = {"TIM1": 1, "TIM8": 3}

#: channel index: 0..2 the outer channels of legs a, b, c; 3..5 the inner ones
CHANNELS: tuple[Channel, ...] = tuple(
    Channel(index=k * 3 + leg, leg=leg, kind=kind,
            reference=f"leg {LEGS[leg]} not at P" if kind == "outer" else f"leg {LEGS[leg]} at N",
            main_gate=f"T3{LEGS[leg]}" if kind == "outer" else f"T4{LEGS[leg]}",
            comp_gate=f"T1{LEGS[leg]}" if kind == "outer" else f"T2{LEGS[leg]}",
            stm32_timer=timer, stm32_channel=leg + 1, stm32_pins=_STM32_PINS[(timer, leg + 1)],
            stm32_af=_STM32_AF[timer], epwm=k * 3 + leg + 1,
            epwm_pins=(f"GPIO{2 * (k * 3 + leg)}", f"GPIO{2 * (k * 3 + leg) + 1}"))
    for k, (kind, timer) in enumerate((("outer", "TIM1"), ("inner", "TIM8"))) for leg in range(3))


def gate_word(state: int) -> int:
    """The 12-bit gate word of a state: bit 4 leg + k = switch T(k+1) of leg a, b, c on."""
    word = 0
    for leg, level in enumerate(v.STATES[state].levels):
        for k, on in enumerate(LEVEL_GATES[level]):
            word |= on << (4 * leg + k)
    return word


def channel_word(state: int) -> int:
    """The 6-bit word of the channels' reference signals in a state: bit = channel index."""
    levels = v.STATES[state].levels
    return sum(1 << ch.index for ch in CHANNELS if ch.active(levels[ch.leg]))


def sequence_runs(seq: tuple[int, ...]) -> tuple[int, ...]:
    """Per channel, the number of leading segments of ``seq`` in which its reference is active.

    Asserts what the modulator assumes of every sequence: symmetric, and each channel's reference
    active on a run at the start and the mirrored run at the end (levels rise towards the middle)."""
    if tuple(seq) != tuple(reversed(seq)):
        raise AssertionError(f"sequence {seq} is not symmetric")
    runs = []
    for ch in CHANNELS:
        act = [ch.active(v.STATES[s].levels[ch.leg]) for s in seq]
        n = 0
        while n < len(act) and act[n]:
            n += 1
        if any(act[n:len(act) - n]):
            raise AssertionError(f"sequence {seq}: channel {ch.index} is active inside the period")
        runs.append(n)
    return tuple(runs)


def timing(model: Model, target: str) -> PwmTiming:
    """The PWM timer of ``target`` for ``model`` (codegen.pwm)."""
    return pwm_timing(model, target, PULSES_PER_PERIOD)


def _seconds_to_counts(t: ThreeLevelTables, pwm: PwmTiming) -> dict[str, Any]:
    """How the modulator turns a time in the step's format into counts: float32, one multiply by
    2 A / dt_s; fixed point (Q q seconds), (x * mul) >> shift in 64 bits, mul < 2^31."""
    if not t.nf.quantised:
        return {"fixed": False, "counts_per_s": c_float_literal(f32(pwm.counts_per_s)),
                "acc_type": "float", "real": t.nf.c_type}
    q = t.nf.scaling.q("s")  # type: ignore[union-attr]
    ratio = pwm.counts_per_s * math.ldexp(1.0, -q)  # counts per LSB of the step's seconds
    shift = q + (30 - math.frexp(pwm.counts_per_s)[1])
    mul = round(ratio * math.ldexp(1.0, shift))
    assert 0 < mul < 2**31 and shift < 63
    return {"fixed": True, "mul": mul, "shift": shift, "acc_type": "int64_t", "real": t.nf.c_type,
            "q_s": q}


def _input_encoding(t: ThreeLevelTables) -> dict[str, str]:
    """Per real input field, the C expression prefix that turns an SI value into the step's format."""
    if not t.nf.quantised:
        return {}
    sc = t.nf.scaling
    assert sc is not None
    return {f.name: c_float_literal(f32(math.ldexp(1.0, sc.q(f.unit)))) for f in INPUT.fields if f.kind == "real"}


def modulator_context(model: Model, t: ThreeLevelTables, target: str) -> dict[str, Any]:
    """Template context of the modulator and the example interrupt routine of ``target``."""
    pwm = timing(model, target)
    a, m = pwm.period_counts, pwm.min_pulse_counts
    safe_runs = sequence_runs((SAFE_STATE,) * N_SEGMENTS)
    states = [{"index": s.index, "name": s.name, "gates": gate_word(s.index), "chans": channel_word(s.index)}
              for s in v.STATES]
    for seq in t.seq:  # every sequence of the step is what the modulator assumes (asserted once, here)
        sequence_runs(seq)
    ctx = {**base_context(model, target), "target": target, "pwm": pwm, "a": a, "m": m,
           "max_inner": a - m // 2, "n_channels": len(CHANNELS), "n_segments": N_SEGMENTS,
           "last_segment": N_SEGMENTS - 1, "n_states": v.N_STATES,
           "safe_state": SAFE_STATE, "safe_lead": [a if r >= 4 else 0 for r in safe_runs],
           "channels": CHANNELS, "states": states, "strategy": t.strategy,
           **_seconds_to_counts(t, pwm), "encode": _input_encoding(t),
           "is_f28": target == "tms320f28377", "fault_action": t.fault_action}
    if target == "stm32h743":
        pins = tuple((p[1], int(p[2:]), ch.stm32_af) for ch in CHANNELS for p in ch.stm32_pins)
        init = {"TIM1": tuple(ctx["safe_lead"][0:3]), "TIM8": tuple(ctx["safe_lead"][3:6])}
        ctx["setup"] = {
            "gpio": stm32_gpio_setup(pins),
            "ports": sorted({p for p, _, _ in pins}),
            "tim1": stm32_timer_setup(pwm, "TIM1", (1, 2, 3), True, "master", init["TIM1"]),
            "tim8": stm32_timer_setup(pwm, "TIM8", (1, 2, 3), True, "slave", init["TIM8"]),
        }
    else:
        ctx["setup"] = {"epwm": [f28_epwm_setup(pwm, ch.epwm, "zero-or-period", "zero-or-period" if ch.epwm == 1
                                                 else None, CSF_HIGH if ctx["safe_lead"][ch.index] else CSF_LOW,
                                                 model.prefix.upper())
                                 for ch in CHANNELS]}
    inv = model.inverter
    ctx["adc"] = adc_placeholders(target, 1.25 * inv.i_trip_a, 0.625 * inv.udc_max_v)
    ctx["inputs"] = isr_inputs(target, model.prefix, (("uc1_v", "upper DC-link capacitor voltage, V"),
                                                      ("uc2_v", "lower DC-link capacitor voltage, V")))
    return ctx


def render_modulator(model: Model, t: ThreeLevelTables, target: str) -> dict[str, str]:
    """File name -> text of ``<prefix>_modulator.h/.c`` and ``<prefix>_isr_example.c`` for ``target``
    (none for the host target, which drives no power stage)."""
    return render_modulator_files(model, target, "ttype", lambda: modulator_context(model, t, target))
