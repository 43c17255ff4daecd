"""The PWM timers of the embedded targets, as the generated modulator uses them (docs/modulator.md).

What the modulator of every topology shares: the timer clock of each target,
the PWM period in counts, the dead time (in the target's own register
encoding) and the minimum pulse, all derived here once from the config; and
the register words of the example interrupt routine's timer set-up.  The
topology packages decide which channels drive which switch; nothing here
knows a topology.

Counter model (both targets): an up-down counter of half-period A counts
(STM32H743 TIMx_ARR, F28377 TBPRD) runs 0 -> A -> 0 once per control period
(2 A ticks); a channel's reference signal is active while the counter is
below its compare value (STM32 PWM mode 1, RM0433 39.3.13 and figure
"Center-aligned PWM waveforms (ARR=8)": compare 0 holds it at 0, compare =
ARR at 1).  A compare written as the first half's ("head") value makes the
signal active for the first ``head`` ticks of the period, one written as
the second half's ("tail") value for the last ``tail`` ticks.

Timer clocks (the ports' clock trees, firmware/ports/*/board.c):

- STM32H743: SYSCLK 400 MHz, APB2 100 MHz (D2PPRE2 = /2), so the TIM1/TIM8
  kernel clock is 2 x APB2 = 200 MHz (RM0433 8.5.11, TIMPRE = 0); the dead
  time counts tDTS = 1/200 MHz (TIMx_CR1.CKD = 00) in the BDTR.DTG encoding
  (RM0433 39.4.18).
- TMS320F28377: SYSCLK 200 MHz, EPWMCLK = SYSCLK/2 = 100 MHz
  (PERCLKDIVSEL.EPWMCLKDIV reset value), TBCLK = EPWMCLK / CLKDIV
  (HSPCLKDIV = /1); the dead band counts TBCLK (DBRED, DBFED, 14 bits).

Dead time and minimum pulse are generate-time constants
(:data:`DEFAULT_DEAD_TIME_S`, :data:`DEFAULT_MIN_PULSE_S`); the control
period must hold a topology-given number of minimum pulses, else the config
is refused naming ``controller.dt_s``.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from codegen.errors import ConfigError
from codegen.model import Model
from codegen.numfmt.float32 import c_float_literal, f32

__all__ = ["DEFAULT_DEAD_TIME_S", "DEFAULT_MIN_PULSE_S", "TIMERS", "TimerTarget", "PwmTiming", "pwm_timing",
           "stm32_dtg", "RegWrite", "modulated_targets", "stm32_timer_setup", "stm32_gpio_setup", "f28_epwm_setup",
           "CSF_NONE", "CSF_LOW", "CSF_HIGH", "ADC_BITS", "adc_placeholders", "IsrInput", "isr_sample", "isr_inputs"]

#: dead time of every complementary pair (both edges), s: a common value for 600-1200 V IGBTs
DEFAULT_DEAD_TIME_S = 1.0e-6
#: shortest pulse of any channel's reference signal, s (> dead time: every gate pulse lasts at least
#: the minimum pulse less the dead time, and a level passed through dwells at least this long)
DEFAULT_MIN_PULSE_S = 2.0e-6


@dataclass(frozen=True)
class TimerTarget:
    """The PWM timer of one target."""

    target: str
    #: counter clock before the prescaler, Hz
    kernel_hz: float
    #: largest half-period register value (16-bit ARR, TBPRD)
    max_period: int
    #: the prescaler divisions the port may choose, smallest first
    dividers: tuple[int, ...]
    #: name of the half-period register
    period_register: str
    #: name of the dead-time setting
    dead_time_register: str
    #: largest dead time the register holds, in its own clock
    max_dead_time_ticks: int
    #: the port's clock tree in one line
    clock_doc: str


TIMERS: dict[str, TimerTarget] = {t.target: t for t in (
    TimerTarget("stm32h743", 200e6, 0xFFFF, tuple(range(1, 65537)), "TIMx_ARR", "TIMx_BDTR.DTG", 1008,
                "TIM1/TIM8 kernel clock 200 MHz (SYSCLK 400 MHz, APB2 100 MHz, timers at 2 x APB2; RM0433 8.5.11)"),
    TimerTarget("tms320f28377", 100e6, 0xFFFF, (1, 2, 4, 8, 16, 32, 64, 128), "TBPRD", "DBRED/DBFED", 0x3FFF,
                "EPWMCLK 100 MHz (SYSCLK 200 MHz, EPWMCLKDIV = /2), TBCLK = EPWMCLK / CLKDIV, HSPCLKDIV = /1"),
)}


def modulated_targets() -> tuple[str, ...]:
    """The targets ``generate`` writes a modulator for (the host target drives no power stage)."""
    return tuple(TIMERS)


def render_modulator_files(model: Model, target: str, topology_dir: str,
                           context: Callable[[], dict[str, Any]]) -> dict[str, str]:
    """File name -> text of ``<prefix>_modulator.h/.c`` and ``<prefix>_isr_example.c`` for ``target`` from
    ``templates/<topology_dir>/`` and the topology's ``context()`` (none for the host target, which drives
    no power stage)."""
    if target not in modulated_targets():
        return {}
    from codegen.render import render_files

    p = model.prefix
    return render_files({f"{p}_modulator.h": f"{topology_dir}/modulator.h.j2",
                         f"{p}_modulator.c": f"{topology_dir}/modulator.c.j2",
                         f"{p}_isr_example.c": f"{topology_dir}/isr_{target}.c.j2"}, context())


def stm32_dtg(ticks: int) -> tuple[int, int]:
    """(DTG, realised ticks): the smallest BDTR.DTG dead time of at least ``ticks`` tDTS (RM0433
    TIMx_BDTR: DTG[7:5] = 0xx: DTG[7:0] x tDTS; 10x: (64 + DTG[5:0]) x 2 tDTS; 110: (32 + DTG[4:0])
    x 8 tDTS; 111: (32 + DTG[4:0]) x 16 tDTS)."""
    if ticks <= 127:
        return max(ticks, 0), max(ticks, 0)
    if ticks <= 254:
        n = -(-ticks // 2)
        return 0x80 | (n - 64), 2 * n
    if ticks <= 504:
        n = -(-ticks // 8)
        return 0xC0 | (n - 32), 8 * n
    if ticks <= 1008:
        n = -(-ticks // 16)
        return 0xE0 | (n - 32), 16 * n
    raise ValueError(f"dead time of {ticks} tDTS exceeds the BDTR.DTG range (1008)")


@dataclass(frozen=True)
class PwmTiming:
    """The PWM timer of one target set for one config: period, dead time, minimum pulse."""

    target: str
    timer: TimerTarget
    #: prescaler division (STM32: TIMx_PSC + 1; F28377: CLKDIV)
    divider: int
    #: counter tick rate, Hz
    tick_hz: float
    #: half period A in ticks: ARR / TBPRD; the PWM period is 2 A ticks
    period_counts: int
    #: the realised PWM period, s, and its relative difference from controller.dt_s
    pwm_period_s: float
    period_error: float
    #: dead time in counter ticks (what a pulse loses), realised s, and its register value
    dead_time_counts: int
    dead_time_s: float
    dead_time_register_value: int
    #: minimum pulse of a channel's reference signal, counter ticks and s
    min_pulse_counts: int
    min_pulse_s: float
    #: ticks per second of the control period: 2 A / dt_s (segment times -> counts)
    counts_per_s: float

    @property
    def ticks_per_period(self) -> int:
        """2 A: counter ticks per PWM period."""
        return 2 * self.period_counts

    @property
    def control_period_s(self) -> float:
        """controller.dt_s, the period the PWM period approximates (``pwm_period_s / (1 + period_error)``)."""
        return self.pwm_period_s / (1.0 + self.period_error)


def pwm_timing(model: Model, target: str, pulses_per_period: int, *, dead_time_s: float = DEFAULT_DEAD_TIME_S,
               min_pulse_s: float = DEFAULT_MIN_PULSE_S) -> PwmTiming:
    """The timer of ``target`` for ``model``: the smallest prescaler whose half period fits the
    register, the half period rounded to whole ticks, the dead time rounded up to the register's
    step, the minimum pulse rounded up to whole ticks.  ``pulses_per_period``: how many minimum
    pulses the control period must hold (the topology's modulator says); a shorter
    ``controller.dt_s`` is a :class:`ConfigError`."""
    timer = TIMERS[target]
    dt = model.controller.dt_s
    if not 0.0 < dead_time_s < min_pulse_s:
        raise ValueError(f"dead time {dead_time_s} s must be positive and below the minimum pulse {min_pulse_s} s")
    need = pulses_per_period * min_pulse_s
    if dt < need:
        raise ConfigError(model.source, "controller.dt_s", dt,
                          f"the {target} modulator needs dt_s >= {need:g} s ({pulses_per_period} x the minimum "
                          f"pulse {min_pulse_s:g} s; dead time {dead_time_s:g} s; docs/modulator.md)")
    for divider in timer.dividers:
        tick = timer.kernel_hz / divider
        a = round(dt * tick / 2.0)
        if a <= timer.max_period:
            break
    else:  # pragma: no cover - dt_s <= 1e-3 always fits
        raise ConfigError(model.source, "controller.dt_s", dt, f"too long for the {target} PWM timer")
    if target == "stm32h743":  # the dead time counts the kernel clock (CKD = 00), not the prescaled one
        dtg, realised = stm32_dtg(math.ceil(dead_time_s * timer.kernel_hz - 1e-9))
        dead_s = realised / timer.kernel_hz
        reg = dtg
    else:
        reg = math.ceil(dead_time_s * tick - 1e-9)
        if reg > timer.max_dead_time_ticks:
            raise ValueError(f"dead time {dead_time_s} s exceeds DBRED at {tick:g} Hz")
        dead_s = reg / tick
    dead_counts = math.ceil(dead_s * tick - 1e-9)
    m = math.ceil(min_pulse_s * tick - 1e-9)
    pwm_period = 2 * a / tick
    return PwmTiming(target, timer, divider, tick, a, pwm_period, pwm_period / dt - 1.0, dead_counts, dead_s, reg,
                     m, m / tick, 2 * a / dt)


@dataclass(frozen=True)
class RegWrite:
    """One register write of an example set-up: ``reg = value`` or, with ``mask``, ``reg = (reg &
    ~mask) | value``; ``bits`` the register width (16 or 32)."""

    reg: str
    value: int
    comment: str
    mask: int | None = None
    bits: int = 32

    @property
    def value_text(self) -> str:
        return f"0x{self.value:0{self.bits // 4}X}u"

    @property
    def mask_text(self) -> str:
        return f"0x{(self.mask or 0):0{self.bits // 4}X}u"


# --- register words of the example set-up (docs/modulator.md "Example interrupt routine") ----------------

#: RM0433 TIM1/TIM8 register bits the set-up writes
_CR1_CMS_CENTER1 = 1 << 5  # CMS = 01: centre-aligned mode 1
_CR1_ARPE = 1 << 7
_CR2_MMS_ENABLE = 1 << 4  # MMS = 001: TRGO = counter enable (starts the slave)
_CR2_MMS2_UPDATE = 2 << 20  # MMS2 = 0010: TRGO2 = update event (the ADC trigger)
_SMCR_SMS_TRIGGER = 6  # SMS = 0110: the slave starts at its trigger (TS = 000: ITR0 = TIM1 for TIM8)
_OC_PWM1 = 6  # OCxM = 0110: PWM mode 1 (active while CNT < CCRx)
_BDTR_OSSI = 1 << 10
_BDTR_OSSR = 1 << 11


def _ccmr(channels: tuple[int, ...], preload: bool) -> tuple[int, int]:
    """(CCMR1, CCMR2) for PWM mode 1 on ``channels`` (1..4), with the compare preload (OCxPE) or not."""
    words = [0, 0]
    for ch in channels:
        word, half = divmod(ch - 1, 2)
        words[word] |= ((_OC_PWM1 << 4) | ((1 << 3) if preload else 0)) << (8 * half)
    return words[0], words[1]


def stm32_timer_setup(timing: PwmTiming, timer: str, channels: tuple[int, ...], preload: bool, role: str,
                      initial: tuple[int, ...]) -> list[RegWrite]:
    """The register writes that set ``timer`` ("TIM1", "TIM8") up for the modulator, counter stopped:
    centre-aligned mode 1 with ARR = A, an update event at every underflow and overflow (RCR = 0),
    PWM mode 1 on ``channels`` (CHx and CHxN, active high, dead time DTG), off-state = idle level 0
    (every gate off while MOE = 0); ``role``: "master" (TRGO = enable for a slave, TRGO2 = update for
    the ADC), "slave" (starts on TIM1's TRGO, ITR0), or "alone" (TRGO2 only)."""
    base = f"{timer}_BASE"
    ccmr1, ccmr2 = _ccmr(channels, preload)
    ccer = sum(0x5 << (4 * (ch - 1)) for ch in channels)  # CCxE, CCxNE; CCxP = CCxNP = 0 (active high)
    cr2 = _CR2_MMS2_UPDATE | (_CR2_MMS_ENABLE if role == "master" else 0)
    smcr = _SMCR_SMS_TRIGGER if role == "slave" else 0
    w = [RegWrite(f"TIM_CR1({base})", _CR1_CMS_CENTER1 | _CR1_ARPE, "centre-aligned mode 1, ARR preloaded, stopped"),
         RegWrite(f"TIM_CR2({base})", cr2, "OISx = OISxN = 0 (idle: gates off)" +
                  ("; TRGO = enable (TIM8 start), TRGO2 = update (ADC)" if role == "master" else
                   "; TRGO2 = update" if role == "alone" else "")),
         RegWrite(f"TIM_SMCR({base})", smcr, "slave: trigger mode on ITR0 (TIM1 TRGO): starts a few kernel "
                  "clocks after TIM1 (trigger resynchronisation), well inside the dead time" if role == "slave" else
                  "no slave mode"),
         RegWrite(f"TIM_PSC({base})", timing.divider - 1, f"counter clock {timing.tick_hz / 1e6:g} MHz"),
         RegWrite(f"TIM_ARR({base})", timing.period_counts,
                  f"A = {timing.period_counts}: PWM period 2 A = {timing.pwm_period_s * 1e6:.6g} us"),
         RegWrite(f"TIM_RCR({base})", 0, "an update event at every underflow and overflow"),
         RegWrite(f"TIM_CCMR1({base})", ccmr1, "PWM mode 1" + (", compare preloaded" if preload else
                                                                 ", compare written at once (no preload)")),
         RegWrite(f"TIM_CCMR2({base})", ccmr2, "PWM mode 1 on CH3" if 3 in channels else "CH3, CH4 unused")]
    for ch, value in zip(channels, initial):
        w.append(RegWrite(f"TIM_CCR{ch}({base})", value, f"CH{ch}: the safe decision"))
    w += [RegWrite(f"TIM_BDTR({base})", _BDTR_OSSI | _BDTR_OSSR | timing.dead_time_register_value,
                   f"dead time DTG = 0x{timing.dead_time_register_value:02X} ({timing.dead_time_s * 1e9:.0f} ns), "
                   "OSSI = OSSR = 1, MOE = 0 (outputs at their idle level: off)"),
          RegWrite(f"TIM_CCER({base})", ccer, "CHx and CHxN enabled, active high"),
          RegWrite(f"TIM_EGR({base})", 1, "UG: load PSC, ARR, RCR and the compares")]
    return w


#: (GPIO port letter, pin, alternate function) -> the MODER/OSPEEDR/AFR writes of one port
def stm32_gpio_setup(pins: tuple[tuple[str, int, int], ...]) -> list[RegWrite]:
    """MODER (alternate), OSPEEDR (very high) and AFRL/AFRH of every port ``pins`` use."""
    out: list[RegWrite] = []
    for port in sorted({p for p, _, _ in pins}):
        own = sorted((n, af) for p, n, af in pins if p == port)
        mode = sum(2 << (2 * n) for n, _ in own)
        mask2 = sum(3 << (2 * n) for n, _ in own)
        names = ", ".join(f"P{port}{n}" for n, _ in own)
        out.append(RegWrite(f"GPIO_MODER(GPIO{port}_BASE)", mode, f"{names}: alternate function", mask2))
        out.append(RegWrite(f"GPIO_OSPEEDR(GPIO{port}_BASE)", mask2, f"{names}: very high speed", mask2))
        for reg, lo in (("AFRL", 0), ("AFRH", 8)):
            sel = [(n, af) for n, af in own if lo <= n < lo + 8]
            if sel:
                out.append(RegWrite(f"GPIO_{reg}(GPIO{port}_BASE)", sum(af << (4 * (n - lo)) for n, af in sel),
                                    ", ".join(f"P{port}{n} AF{af}" for n, af in sel),
                                    sum(0xF << (4 * (n - lo)) for n, _ in sel)))
    return out


#: F28377 ePWM field values (SPRUHX5 ePWM registers)
_TBCTL_UPDOWN = 2
_TBCTL_FREE = 2 << 14
_AQ_CLEAR, _AQ_SET = 1, 2
#: ZRO = set, PRD = clear, CAU = clear, CAD = set: active while the counter is below CMPA in either half
AQCTLA_BELOW_CMPA = _AQ_SET | (_AQ_CLEAR << 2) | (_AQ_CLEAR << 4) | (_AQ_SET << 6)
#: DBCTL: OUT_MODE = 3 (rising and falling delay), POLSEL = 2 (active high complementary), IN_MODE = 0 (A)
DBCTL_AHC = 0x3 | (0x2 << 2)
#: CMPCTL LOADAMODE, AQSFRC RLDCSF and ETSEL SOCASEL codes by load instant
LOAD_CODES = {"zero": 0, "period": 1, "zero-or-period": 2}
#: AQCSFRC.CSFA: continuous software force of output A
CSF_NONE, CSF_LOW, CSF_HIGH = 0, 1, 2


def f28_epwm_setup(timing: PwmTiming, module: int, load: str, soc: str | None, initial_force: int,
                   macros: str) -> list[RegWrite]:
    """The register writes that set ePWM ``module`` up for the modulator (TBCLKSYNC still 0): up-down
    count with TBPRD = A, CMPA and the continuous software force loaded at ``load`` ("zero",
    "zero-or-period" or "immediate"), action qualifier ZRO = set, CAU = clear, PRD = clear, CAD = set
    (A active while the counter is below CMPA), dead band: EPWMxA = A with its rising edge delayed,
    EPWMxB = not A with its rising edge delayed (active high complementary), trip zone forces both
    outputs low; ``soc``: SOCA at "zero" or "zero-or-period" (ePWM1, the ADC trigger) or None;
    ``initial_force``: the continuous force (``CSF_*``) of output A until the first decision; ``macros``:
    the prefix of the register macros the example defines (``<PREFIX>_EPWM_TBCTL(base)``, ...)."""
    clkdiv = timing.divider.bit_length() - 1
    reg = f"{macros}_EPWM_BASE({module}u)"
    immediate = load == "immediate"
    cmpctl = (1 << 4) if immediate else LOAD_CODES[load]  # SHDWAMODE = 1: immediate
    rldcsf = 3 if immediate else LOAD_CODES[load]
    w = [RegWrite(f"{macros}_EPWM_TBCTL({reg})", _TBCTL_FREE | (clkdiv << 10) | _TBCTL_UPDOWN,
                  f"up-down count, TBCLK = EPWMCLK/{timing.divider}, free run at a debug halt", bits=16),
         RegWrite(f"{macros}_EPWM_TBPRD({reg})", timing.period_counts,
                  f"A = {timing.period_counts}: PWM period 2 A = {timing.pwm_period_s * 1e6:.6g} us", bits=16),
         RegWrite(f"{macros}_EPWM_TBCTR({reg})", 0, "counter at zero: every module starts together (TBCLKSYNC)", bits=16),
         RegWrite(f"{macros}_EPWM_CMPCTL({reg})", cmpctl, "CMPA written at once" if immediate else
                  f"CMPA shadowed, loaded at {load.replace('-', ' ')}", bits=16),
         RegWrite(f"{macros}_EPWM_AQCTLA({reg})", AQCTLA_BELOW_CMPA, "ZRO set, CAU clear, PRD clear, CAD set", bits=16),
         RegWrite(f"{macros}_EPWM_AQSFRC({reg})", rldcsf << 6, "continuous force written at once" if immediate else
                  f"continuous force loaded at {load.replace('-', ' ')}", bits=16),
         RegWrite(f"{macros}_EPWM_AQCSFRC({reg})", initial_force, "the safe decision's level until the first decision",
                  bits=16),
         RegWrite(f"{macros}_EPWM_DBRED({reg})", timing.dead_time_register_value,
                  f"rising-edge delay {timing.dead_time_s * 1e9:.0f} ns", bits=16),
         RegWrite(f"{macros}_EPWM_DBFED({reg})", timing.dead_time_register_value,
                  f"falling-edge delay {timing.dead_time_s * 1e9:.0f} ns", bits=16),
         RegWrite(f"{macros}_EPWM_DBCTL({reg})", DBCTL_AHC, "A = delayed A, B = delayed not A (active high complementary)",
                  bits=16),
         RegWrite(f"{macros}_EPWM_TZCTL({reg})", 0x2 | (0x2 << 2), "a trip forces EPWMxA and EPWMxB low (gates off)",
                  bits=16)]
    if soc is not None:
        w += [RegWrite(f"{macros}_EPWM_ETSEL({reg})", (1 << 11) | (LOAD_CODES[soc] + 1) << 8,
                       f"SOCA at {soc.replace('-', ' ')}: the ADC samples", bits=16),
              RegWrite(f"{macros}_EPWM_ETPS({reg})", 1 << 8, "SOCA at every event", bits=16)]
    return w


#: ADC resolution of the example interrupt routine's samples (STM32H743 ADC1: 16 bits; F28377 ADCA/B:
#: 12 bits single-ended)
ADC_BITS: dict[str, int] = {"stm32h743": 16, "tms320f28377": 12}


def adc_placeholders(target: str, current_full_a: float, voltage_full_v: float) -> dict[str, object]:
    """Placeholder sensor scaling of the example (the user sets the board's): a bipolar current
    sensor spanning +-``current_full_a`` over the ADC range around mid-scale, a voltage divider giving
    ``voltage_full_v`` at full scale; with the float32 C literals of mid-scale and both gains."""
    full = float(1 << ADC_BITS[target])
    amps, volts = 2.0 * current_full_a / full, voltage_full_v / full
    return {"adc_full": full, "adc_mid": full / 2.0, "amps_per_count": amps, "volts_per_count": volts,
            "current_span_a": current_full_a, "voltage_span_v": voltage_full_v,
            "mid_literal": c_float_literal(f32(full / 2.0)), "amps_literal": c_float_literal(f32(amps)),
            "volts_literal": c_float_literal(f32(volts))}


@dataclass(frozen=True)
class IsrInput:
    """One real input of the example interrupt routine: the field, its SI expression and meaning."""

    field: str
    expr: str
    comment: str


def isr_sample(target: str, macros: str, index: int) -> str:
    """C expression (float) of the example's ``index``-th ADC sample (0..3) on ``target``: STM32H743
    ADC1 injected data JDR1..JDR4; F28377 ADCA results 0, 1 and ADCB results 0, 1."""
    if target == "stm32h743":
        return f"(float)(ADC_JDR{index + 1}(ADC1_BASE) & 0xFFFFu)"
    return f"(float){macros}_ADC{'AB'[index // 2]}RESULT({index % 2}u)"


def isr_inputs(target: str, prefix: str, voltages: tuple[tuple[str, str], ...]) -> list[IsrInput]:
    """The real inputs of a step as the example fills them: the phase currents and the DC-link
    ``voltages`` (field, meaning) from ADC samples 0, 1, 2, ..., angle, speed and torque reference from
    the board's functions."""
    macros = prefix.upper()
    cur = [IsrInput(f, f"({isr_sample(target, macros, i)} - {macros}_ISR_ADC_MID) * {macros}_ISR_AMPS_PER_COUNT",
                    f"phase-{ph} current, A (positive into the motor)")
           for i, (f, ph) in enumerate((("ia_a", "a"), ("ib_a", "b")))]
    vol = [IsrInput(f, f"{isr_sample(target, macros, 2 + i)} * {macros}_ISR_VOLTS_PER_COUNT", doc)
           for i, (f, doc) in enumerate(voltages)]
    hooks = [IsrInput("theta_e_rad", f"{prefix}_board_theta_e_rad()", "electrical angle, rad, wrapped to [0, 2 pi)"),
             IsrInput("omega_e_rad_s", f"{prefix}_board_omega_e_rad_s()", "electrical speed, rad/s"),
             IsrInput("torque_ref_nm", f"{prefix}_board_torque_ref_nm()", "torque reference, N*m")]
    return cur + hooks[:2] + vol + hooks[2:]
