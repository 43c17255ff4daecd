"""From the two-level decision to the 6 gates: the generated modulator and its example interrupt routine
(docs/modulator.md).

A finite-control-set decision holds one switching state for the whole
period: leg bit 1 = upper switch on (lower off) for the whole period, 0 =
lower switch on.  Each leg is one complementary channel with hardware dead
time: main output = upper switch, complementary output = lower switch
(STM32H743 TIM1 CHx / CHxN, F28377 ePWM1..3 A / B), reference active = leg
at 1.  The reference is active while the counter is below the compare, so
compare A (the half period, ARR / TBPRD) gives 100 % (upper on all period)
and 0 gives 0 % (lower on all period).

When the decision takes effect depends on ``controller.delay_compensation``
(the step's assumption; the simulator's plant applies the decision of k
during [k+d, k+d+1), d = 1 with compensation, 0 without):

- on: the decision computed in period k is for period k+1: the example
  writes it into the shadow (preload) registers, which load it at the next
  period start (STM32H743: written at the counter peak, since TIM1 updates
  at the underflow and at the overflow; F28377: CMPA and the continuous
  force load at CTR = 0 only);
- off: the step assumes its decision acts at once: the example writes the
  compares unbuffered right after the step, so the decision acts from
  t_k + (conversion + step time), not from t_k as the simulator idealises.

This module derives the tables and register words once; the templates
(templates/twolevel/modulator.*.j2, isr_*.c.j2) format them.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from codegen.model import Model
from codegen.numfmt.float32 import c_float_literal, f32
from codegen.pwm import (
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
from codegen.topologies.twolevel.derive import TwoLevelTables
from codegen.topologies.twolevel.records import INPUT

__all__ = ["LEGS", "Leg", "PULSES_PER_PERIOD", "gate_word", "timing", "render_modulator"]

#: a state lasts at least one period: the period must hold two minimum pulses (upper and lower)
PULSES_PER_PERIOD = 2
N_STATES = 8
#: the safe decision (zero vector 000: every lower switch on)
SAFE_SW = 0


@dataclass(frozen=True)
class Leg:
    """One leg: its bit in the switching state, the channel and pins per target."""

    index: int
    name: str
    bit: int  # 4 (a), 2 (b), 1 (c): sw = Sa*4 + Sb*2 + Sc
    stm32_channel: int
    stm32_pins: tuple[str, str]  # (CHx upper, CHxN lower)
    epwm: int
    epwm_pins: tuple[str, str]  # (EPWMxA upper, EPWMxB lower)


LEGS: tuple[Leg, ...] = tuple(
    Leg(i, n, 4 >> i, i + 1, pins, i + 1, (f"GPIO{2 * i}", f"GPIO{2 * i + 1}"))
    for i, (n, pins) in enumerate((("a", ("PE9", "PE8")), ("b", ("PE11", "PE10")), ("c", ("PE13", "PE12")))))


def gate_word(sw: int) -> int:
    """Gate word of switching state ``sw``: bit 2 leg = upper switch of leg a, b, c on, bit 2 leg + 1 =
    lower switch on."""
    return sum((1 << (2 * leg.index)) if sw & leg.bit else (2 << (2 * leg.index)) for leg in LEGS)


def timing(model: Model, target: str) -> PwmTiming:
    """The PWM timer of ``target`` for ``model`` (codegen.pwm)."""
    return pwm_timing(model, target, PULSES_PER_PERIOD)


def _input_encoding(t: TwoLevelTables) -> dict[str, str]:
    """Per real input field, the float32 scale 2^q that turns an SI value into the step's format."""
    if not t.nf.quantised:
        return {}
    sc = t.nf.scaling
    assert sc is not None
    return {f.name: c_float_literal(f32(math.ldexp(1.0, sc.q(f.unit)))) for f in INPUT.fields if f.kind == "real"}


def modulator_context(model: Model, t: TwoLevelTables, target: str) -> dict[str, Any]:
    """Template context of the modulator and the example interrupt routine of ``target``."""
    pwm = timing(model, target)
    delayed = model.controller.delay_compensation
    ctx = {**base_context(model, target), "target": target, "pwm": pwm, "a": pwm.period_counts,
           "legs": LEGS, "n_states": N_STATES, "safe_sw": SAFE_SW, "strategy": t.strategy,
           "states": [{"sw": sw, "name": f"{sw:03b}", "gates": gate_word(sw)} for sw in range(N_STATES)],
           "delayed": delayed, "encode": _input_encoding(t), "is_f28": target == "tms320f28377",
           "fault_action": t.fault_action}
    if target == "stm32h743":
        pins = tuple((p[1], int(p[2:]), 1) for leg in LEGS for p in leg.stm32_pins)
        ctx["setup"] = {"gpio": stm32_gpio_setup(pins), "ports": sorted({p for p, _, _ in pins}),
                        "tim1": stm32_timer_setup(pwm, "TIM1", (1, 2, 3), delayed, "alone", (0, 0, 0))}
    else:
        load = "zero" if delayed else "immediate"
        ctx["setup"] = {"epwm": [f28_epwm_setup(pwm, leg.epwm, load, "zero" if leg.epwm == 1 else None, CSF_LOW,
                                                 model.prefix.upper()) for leg in LEGS]}
    inv = model.inverter
    ctx["adc"] = adc_placeholders(target, 1.25 * inv.i_trip_a, 1.25 * inv.udc_max_v)
    ctx["inputs"] = isr_inputs(target, model.prefix, (("udc_v", "DC-link voltage, V"),))
    return ctx


def render_modulator(model: Model, t: TwoLevelTables, target: str) -> dict[str, str]:
    """File name -> text of ``<prefix>_modulator.h/.c`` and ``<prefix>_isr_example.c`` for ``target``
    (none for the host target, which drives no power stage)."""
    return render_modulator_files(model, target, "twolevel", lambda: modulator_context(model, t, target))
