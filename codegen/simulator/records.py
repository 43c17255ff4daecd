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
from codegen.records import Field, Record, RecordLayout, fields

__all__ = [
    "SimStruct", "StructMember", "MOTOR_STATE", "SIM_PARAMS", "SIM_STATE", "SIM_TRACE", "ENCODER_WINDOW",
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


#: Plant motor state (SI units), the first part of every plant's state.
MOTOR_STATE = SimStruct("pmsm_state_t", "plant motor state (dq frame, d axis on the magnet)", Record("pmsm_state", fields("""
    i_d_a          f64   1  d-axis stator current, A
    i_q_a          f64   1  q-axis stator current, A
    omega_m_rad_s  f64   1  mechanical rotor speed, rad/s
    theta_e_rad    f64   1  electrical rotor angle, rad, in [0, 2*pi) between calls
""")))

#: Parameters every simulator takes: the plant's motor and stiff DC link (the controller's values unless
#: ``[plant]`` overrides them), timing, speed PI, the plant's actuation delay, inverter and sensor
#: non-idealities (SI units; every non-ideality 0 = off).
SIM_PARAMS = SimStruct("sim_params_t", "plant motor, DC link, timing, speed loop, non-idealities (every topology)", Record("sim_params", fields("""
    rs_ohm               f64   1  plant stator resistance Rs, ohm
    ld_h                 f64   1  plant d-axis inductance Ld, H
    lq_h                 f64   1  plant q-axis inductance Lq, H
    psi_f_wb             f64   1  plant permanent-magnet flux linkage psi_f, Wb
    pole_pairs           i32   1  pole pairs p
    j_kgm2               f64   1  plant rotor + load inertia J, kg*m^2 (> 0 unless the speed is imposed)
    b_nms                f64   1  plant viscous friction B, N*m*s/rad
    udc_v                f64   1  plant DC-link voltage Udc, V (stiff source; the controller measures it)
    dt_s                 f64   1  control (sampling) period, s
    kp                   f64   1  speed PI proportional gain, N*m/(rad/s)
    ki                   f64   1  speed PI integral gain, N*m/rad
    limit_nm             f64   1  speed PI output and integrator clamp, +-N*m
    speed_imposed        i32   1  1: omega_m follows speed_ref, T* = load_nm
    delay_periods        i32   1  actuation delay d (0..2): the decision from the samples of k acts during [k+d, k+d+1)
    dead_time_s          f64   1  inverter dead time at every leg edge, s (0: off)
    device_drop_v        f64   1  forward drop of each conducting device, against the phase current, V (0: off)
    current_gain_error   f64   1  relative gain error of the current sensors (0: off)
    current_offset_a     f64   1  current-sensor offset, A (0: off)
    adc_bits             i32   1  current ADC resolution over +-adc_full_scale_a, bits (0: off)
    adc_full_scale_a     f64   1  current ADC full scale, A
    noise_a              f64   1  standard deviation of additive Gaussian current noise, A (0: off)
    noise_seed           i64   1  seed of the noise generator
    encoder_bits         i32   1  encoder resolution, 2^bits counts per mechanical revolution (0: ideal angle and speed)
    measurement_delay_s  f64   1  the samples are taken this long before t_k, s (0..dt_s; 0: at t_k)
    integrator           i32   1  plant integrator: 0 RK4 sub-steps, 1 exact (Taylor series per constant-voltage piece, sim_exact.h)
""")))

#: Encoder counts kept for the speed estimate (the difference over this many periods).
ENCODER_WINDOW = 16

#: State every simulator carries from one run call to the next (chunked runs).
SIM_STATE = SimStruct("sim_state_t", "carried state every topology has", Record("sim_state", fields("""
    pi_integral_nm       f64   1       speed PI integrator, N*m
    k                    i64   1       index of the next period (t = k*dt_s)
    theta_m_rad          f64   1       plant mechanical angle at t_k, unwrapped, rad (the encoder's shaft)
    sampled_theta_m_rad  f64   1       plant mechanical angle at t_k - measurement_delay_s, rad
    enc_counts           i64   WINDOW  encoder counts of the last WINDOW samples (period j in slot j mod WINDOW)
""", WINDOW=ENCODER_WINDOW)), nested=(("motor", MOTOR_STATE), ("sampled", MOTOR_STATE)))

#: Trace members every simulator records at the sample instant t_k (one value per period).
SIM_TRACE = SimStruct("sim_trace_t", "sample-instant values and decision every topology records", Record("sim_trace", fields("""
    t_s              f64   1  k*dt_s, s
    speed_ref_rad_s  f64   1  mechanical speed reference, rad/s
    omega_m_rad_s    f64   1  plant mechanical speed, rad/s
    te_nm            f64   1  plant torque, N*m
    torque_ref_nm    f64   1  T* given to the controller (double, before the float cast), N*m
    psi_wb           f64   1  plant stator-flux magnitude, Wb
    ia_a             f64   1  plant phase current a, A
    ib_a             f64   1  plant phase current b, A
    ic_a             f64   1  plant phase current c = -i_a - i_b, A
    theta_e_rad      f64   1  plant electrical angle in [0, 2*pi), rad
    ia_meas_a        f64   1  i_a as the controller sees it (sensor chain, measurement delay), A
    ib_meas_a        f64   1  i_b as the controller sees it, A
    theta_e_meas_rad f64   1  electrical angle as the controller sees it (encoder), in [0, 2*pi), rad
    omega_m_meas_rad_s f64 1  mechanical speed as the controller and the speed PI see it, rad/s
    vector           u16   1  controller decision out.vector
    n_eval           u16   1  out.n_eval (candidates evaluated, Cal)
    fault            u16   1  out.fault bits
    gates_off        u16   1  out.gates_off (1: the step asks for every switch off; it acts as the decision does, in [t_k+d, t_k+d+1))
    inverter_open    u16   1  1: every switch was off during [t_k, t_k+1) (the gates_off of k-d), the currents in the diodes
    te_est_nm        f32   1  out.te_est_nm (controller torque estimate), N*m
    psi_est_wb       f32   1  out.psi_est_wb (controller flux estimate), Wb
""")), pointers=True)
