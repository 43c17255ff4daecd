"""The step's number format, bound to its scaling, and its constants in that format.

Both topologies derive their tables through :func:`step_format`: the
constants are computed in float64 by the topology, the format (for fixed
point: its Q formats, ``codegen.numfmt.scaling``) is chosen from every
constant and from the signal ranges the config implies, and each constant
is rounded once to it.  Ranges (float64, SI):

* current: the dq magnitude of phase currents at the trip limit, 2/sqrt(3) i_trip;
* flux: psi_f + max(L_d, L_q) 2/sqrt(3) i_trip;
* torque: 1.5 p flux-bound current-bound;
* voltage: the larger of udc_max_v and the back-EMF at the speed guard;
* the topology's cost bound (its worst case).

A signal or constant the format cannot hold is a :class:`ConfigError`
naming the config field that sets the offending range (found by
sensitivity, :mod:`codegen.kernels.rangecause`), its value, the signal, its
range, the format and what to change.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Iterable

from codegen.errors import ConfigError
from codegen.kernels.consts import Const, guard_limits, in_format
from codegen.kernels.rangecause import advice
from codegen.kernels.trig import sincos_constants
from codegen.model import Model
from codegen.numfmt import NumberFormat, number_format
from codegen.numfmt.scaling import BaseRanges, RepresentationError, Signal

__all__ = ["step_format", "range_error", "motor_ranges", "CONST_FIELDS"]

#: the config field each constant comes from (named by a representation error)
CONST_FIELDS: dict[str, str] = {
    "I_TRIP_A": "inverter.i_trip_a", "UDC_MIN_V": "inverter.udc_min_v", "UDC_MAX_V": "inverter.udc_max_v",
    "UC_MIN_V": "inverter.udc_min_v", "UC_MAX_V": "inverter.udc_max_v", "OMEGA_GUARD_RAD_S": "motor.rated_speed_rpm",
    "TORQUE_REF_GUARD_NM": "speed_loop.limit_nm", "LD_H": "motor.ld_h", "LQ_H": "motor.lq_h", "LS_H": "motor.ld_h",
    "PSI_F_WB": "motor.psi_f_wb", "PSI_F_SQ": "motor.psi_f_wb", "TE_K": "motor.pole_pairs",
    "TE_PSI": "motor.psi_f_wb", "INV_TE_PSI": "motor.psi_f_wb", "TE_GEO_K": "motor.ld_h",
    "PSI_REF_WB": "controller.psi_ref_wb", "INV_PSI_REF": "controller.psi_ref_wb",
    "INV_TN": "motor.rated_torque_nm", "EPS_T_NM": "controller.eps_t_nm", "RS_OHM": "motor.rs_ohm",
    "VDT_K": "controller.dt_s", "VMAG_K": "controller.predictor", "A_D": "controller.dt_s", "A_Q": "controller.dt_s", "A_S": "controller.dt_s",
    "TS_S": "controller.dt_s", "INV_TS": "controller.dt_s", "TS3_S": "controller.dt_s", "TS6_S": "controller.dt_s",
    "TN_MIN_S": "controller.t_n_min_s", "K_VO": "inverter.c_f", "TWO_C": "inverter.c_f",
    "LAMBDA_PSI": "controller.lambda_psi_nm_per_wb", "LAMBDA_VO": "controller.lambda_vo_nm_per_v",
    "ASC_OMEGA_MIN_RAD_S": "controller.asc_min_speed_rpm", "MTPA_INV_STEP": "controller.psi_ref",
    "T_FLOOR_NM": "controller.cost",
}


def motor_ranges(model: Model) -> tuple[BaseRanges, list[Signal]]:
    """The ranges that fix the bases, and the motor signals of every step (float64, SI)."""
    m, inv = model.motor, model.inverter
    i_max = 2.0 / math.sqrt(3.0) * inv.i_trip_a
    flux = m.psi_f_wb + max(m.ld_h, m.lq_h) * i_max
    omega = guard_limits(model, "UDC_MIN_V", "UDC_MAX_V", 1.0)["OMEGA_GUARD_RAD_S"]  # the speed guard
    volts = max(inv.udc_max_v, omega * flux)
    base = BaseRanges(i_max_a=inv.i_trip_a, u_max_v=volts, omega_max_rad_s=omega, flux_max_wb=flux)
    sigs = [
        Signal("i_dq (2/sqrt(3) i_trip)", "A", i_max, "inverter.i_trip_a"),
        Signal("psi (psi_f + L i_max)", "Wb", flux, "inverter.i_trip_a"),
        Signal("te (1.5 p psi_max i_max)", "N*m", 1.5 * m.pole_pairs * flux * i_max, "inverter.i_trip_a"),
        Signal("back-EMF (omega_guard psi_max)", "V", omega * flux, "motor.rated_speed_rpm"),
    ]
    return base, sigs


def _value(model: Model, field: str) -> object:
    obj: object = model
    for part in field.split("."):
        obj = getattr(obj, part, None)
    return obj


ConstsOf = Callable[[Model], Iterable[Const]]
ExtraOf = Callable[[Model], Iterable[Signal]]


def _choose(model: Model, consts: list[Const], extra: Iterable[Signal]) -> NumberFormat:
    """The step's number format for ``consts`` and the ``extra`` ranges (RepresentationError if it
    cannot hold them)."""
    c = model.controller
    base, sigs = motor_ranges(model)
    # the sin/cos constants' precision is the approximation's (a tested property), not checked per constant
    approximation = {name for name, *_ in sincos_constants(number_format(c.number_format))}
    sigs += [Signal(k.name, k.unit, abs(float(k.value)), CONST_FIELDS.get(k.name, "controller.number_format"),
                    exact=k.name not in approximation) for k in consts]
    sigs += list(extra)
    return number_format(c.number_format).for_step(sigs, base, c.fixed_q)


def step_format(model: Model, consts: Iterable[Const] | ConstsOf,
                extra: Iterable[Signal] | ExtraOf = ()) -> tuple[NumberFormat, tuple[Const, ...]]:
    """(the step's number format, its constants in that format) from float64 constants ``consts`` and
    the topology's ``extra`` signal ranges (its cost bound), each given as values or as the function
    that gives them for a model.  ConfigError if the format cannot hold them (:func:`range_error`;
    given as functions, the error can name the field that sets the range and the value that fits)."""
    values = list(consts(model) if callable(consts) else consts)
    try:
        nf = _choose(model, values, extra(model) if callable(extra) else extra)
    except RepresentationError as exc:
        raise range_error(model, exc, extra if callable(extra) else None,
                          consts if callable(consts) else None) from None
    return nf, in_format(nf, values)


def range_error(model: Model, exc: RepresentationError, extra_of: ExtraOf | None = None,
                consts_of: ConstsOf | None = None) -> ConfigError:
    """The one-line ConfigError of a signal or constant the format cannot hold: it names the config field
    that sets the offending range (found by sensitivity over the step's range signals, the motor ranges
    and ``extra_of(model)``: :mod:`codegen.kernels.rangecause`) and says what to change (with
    ``consts_of`` and ``extra_of``: the largest value of that field the format holds); under a global
    Q it names ``controller.fixed_q``."""
    c = model.controller

    def ranges_of(m: Model) -> list[Signal]:
        return motor_ranges(m)[1] + list(extra_of(m) if extra_of is not None else ())

    def fits(m: Model) -> bool:
        assert consts_of is not None and extra_of is not None
        try:
            _choose(m, list(consts_of(m)), extra_of(m))
        except (ArithmeticError, ValueError):  # RepresentationError, or a model the constants reject
            return False
        return True

    named, text = advice(model, exc, ranges_of, fits if consts_of is not None and extra_of is not None else None)
    field = "controller.fixed_q" if c.fixed_q is not None else named or exc.field
    return ConfigError(model.source, field, _value(model, field), f"{exc} ({c.number_format} format): {text}")
