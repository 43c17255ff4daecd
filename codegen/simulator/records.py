"""Records of the closed-loop simulator, defined once: C structs, cffi cdef and numpy from one list.

Every struct the simulator API exchanges with Python (parameters, carried
state, trace) is a :class:`SimStruct`: an ordered :class:`~codegen.records.Record`
of fixed-width fields (name with unit, kind, length, doc), optionally
preceded by a shared base struct as its first member ``common``.  The
generated ``sim_api.h`` (:mod:`codegen.simulator.api`) prints the C typedefs
from these lists; the driver (:mod:`codegen.simulator.driver`) allocates the
trace arrays and builds the Python ``Trace`` classes from the same lists.

The shared part lives here: the motor state of the plant, the parameters,
state and trace every topology has.  Each topology adds its own fields in
its ``sim.py``.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from codegen.numfmt.float32 import FLOAT32
from codegen.records import F32, F64, I32, I64, U16, Field, Record, RecordLayout

__all__ = [
    "SimStruct", "StructMember", "MOTOR_STATE", "SIM_PARAMS", "SIM_STATE", "SIM_TRACE",
]

#: name of the member holding the base struct
BASE_MEMBER = "common"


@dataclass(frozen=True)
class StructMember:
    """One printed C member: type, name, array length (1 = scalar), comment."""

    ctype: str
    name: str
    length: int
    doc: str


@dataclass(frozen=True)
class SimStruct:
    """A C typedef of the simulator API: own fields after an optional shared base.

    ``pointers``: every field is a caller-allocated array (``T *name``) with
    ``length`` values per control period (the trace).
    """

    ctype: str
    doc: str
    record: Record
    base: SimStruct | None = None
    pointers: bool = False
    #: a nested struct member of another SimStruct type (name, struct), printed before the fields
    nested: tuple[tuple[str, SimStruct], ...] = ()

    @cached_property
    def layout(self) -> RecordLayout:
        """The record bound to a number format (fixed-width kinds: the format is irrelevant)."""
        return self.record.bind(FLOAT32)

    @property
    def fields(self) -> tuple[Field, ...]:
        """Own fields, in C member order."""
        return self.record.fields

    def all_fields(self) -> tuple[Field, ...]:
        """Base fields (if any) then own fields."""
        return (self.base.all_fields() if self.base else ()) + self.fields

    def owner(self, name: str) -> SimStruct:
        """The struct (this one or a base) that declares field ``name``."""
        if any(f.name == name for f in self.fields):
            return self
        if self.base is not None:
            return self.base.owner(name)
        raise KeyError(name)

    def np_type(self, f: Field) -> np.dtype:
        """numpy dtype of one value of field ``f``."""
        return self.layout.np_type(f)

    @cached_property
    def members(self) -> tuple[StructMember, ...]:
        """C members in order: ``common`` base, nested structs, then the fields."""
        out: list[StructMember] = []
        if self.base is not None:
            out.append(StructMember(self.base.ctype, BASE_MEMBER, 1, self.base.doc))
        out += [StructMember(s.ctype, name, 1, s.doc) for name, s in self.nested]
        star = " *" if self.pointers else ""
        for f in self.fields:
            length = 1 if self.pointers else f.length
            out.append(StructMember(self.layout.c_type(f) + star, f.name, length, f.doc))
        return tuple(out)


def _f(name: str, kind: str, doc: str, length: int = 1) -> Field:
    return Field(name, kind, length, doc)


#: Plant motor state (SI units), the first part of every plant's state.
MOTOR_STATE = SimStruct("pmsm_state_t", "plant motor state (dq frame, d axis on the magnet)", Record("pmsm_state", (
    _f("i_d_a", F64, "d-axis stator current, A"),
    _f("i_q_a", F64, "q-axis stator current, A"),
    _f("omega_m_rad_s", F64, "mechanical rotor speed, rad/s"),
    _f("theta_e_rad", F64, "electrical rotor angle, rad, in [0, 2*pi) between calls"),
)))

#: Parameters every simulator takes: motor, stiff DC link, timing, speed PI (SI units).
SIM_PARAMS = SimStruct("sim_params_t", "motor, DC link, timing, speed loop (every topology)", Record("sim_params", (
    _f("rs_ohm", F64, "stator resistance Rs, ohm"),
    _f("ld_h", F64, "d-axis inductance Ld, H"),
    _f("lq_h", F64, "q-axis inductance Lq, H"),
    _f("psi_f_wb", F64, "permanent-magnet flux linkage psi_f, Wb"),
    _f("pole_pairs", I32, "pole pairs p"),
    _f("j_kgm2", F64, "rotor + load inertia J, kg*m^2 (> 0 unless the speed is imposed)"),
    _f("b_nms", F64, "viscous friction B, N*m*s/rad"),
    _f("udc_v", F64, "DC-link voltage Udc, V (stiff source)"),
    _f("dt_s", F64, "control (sampling) period, s"),
    _f("kp", F64, "speed PI proportional gain, N*m/(rad/s)"),
    _f("ki", F64, "speed PI integral gain, N*m/rad"),
    _f("limit_nm", F64, "speed PI output and integrator clamp, +-N*m"),
    _f("speed_imposed", I32, "1: omega_m follows speed_ref, T* = load_nm"),
)))

#: State every simulator carries from one run call to the next (chunked runs).
SIM_STATE = SimStruct("sim_state_t", "carried state every topology has", Record("sim_state", (
    _f("pi_integral_nm", F64, "speed PI integrator, N*m"),
    _f("k", I64, "index of the next period (t = k*dt_s)"),
)), nested=(("motor", MOTOR_STATE),))

#: Trace members every simulator records at the sample instant t_k (one value per period).
SIM_TRACE = SimStruct("sim_trace_t", "sample-instant values and decision every topology records", Record("sim_trace", (
    _f("t_s", F64, "k*dt_s, s"),
    _f("speed_ref_rad_s", F64, "mechanical speed reference, rad/s"),
    _f("omega_m_rad_s", F64, "plant mechanical speed, rad/s"),
    _f("te_nm", F64, "plant torque, N*m"),
    _f("torque_ref_nm", F64, "T* given to the controller (double, before the float cast), N*m"),
    _f("psi_wb", F64, "plant stator-flux magnitude, Wb"),
    _f("ia_a", F64, "plant phase current a, A"),
    _f("ib_a", F64, "plant phase current b, A"),
    _f("ic_a", F64, "plant phase current c = -i_a - i_b, A"),
    _f("theta_e_rad", F64, "plant electrical angle in [0, 2*pi), rad"),
    _f("vector", U16, "controller decision out.vector"),
    _f("n_eval", U16, "out.n_eval (candidates evaluated, Cal)"),
    _f("fault", U16, "out.fault bits"),
    _f("te_est_nm", F32, "out.te_est_nm (controller torque estimate), N*m"),
    _f("psi_est_wb", F32, "out.psi_est_wb (controller flux estimate), Wb"),
)), pointers=True)
