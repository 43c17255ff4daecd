"""Validated, frozen configuration model (SI units throughout).

Data flows one way: TOML file -> ``codegen.config.load_config`` -> ``Model``
(this module) -> derived tables -> (templates -> C) and (Python reference).
Nothing downstream re-reads the TOML file; everything downstream takes a
``Model``.  Field names carry their unit (``_ohm``, ``_h``, ``_wb``, ``_s``,
``_v``, ``_a``, ``_nm``, ``_rpm``).
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
from dataclasses import dataclass, field
from typing import Any, Literal, get_args

#: ``inverter.topology``: a value of :data:`codegen.registry.TOPOLOGY_PACKAGES`
Topology = str
#: ``controller.strategy``: one of the topology's strategies (its ``section.strategies``)
Strategy = str
Predictor = Literal["flux-geometry", "dq-euler"]
TableSource = Literal["derived", "published"]
Target = Literal["host", "stm32h743", "tms320f28377"]
SpeedMode = Literal["mechanical", "imposed"]
FaultAction = Literal["gates-off", "active-short-circuit"]
#: ``scenario.set``: "config", or a run set of the topology's (its ``section.narrowed``)
ScenarioSet = str
Placement = Literal["tcm", "default"]
PsiRef = Literal["constant", "mtpa"]
CostForm = Literal["rated", "reference"]

TARGETS: tuple[str, ...] = get_args(Target)
#: the generated step's speed guard trips above this many times the rated electrical speed
SPEED_GUARD_PER_RATED = 5.0
FAULT_ACTIONS: tuple[str, ...] = get_args(FaultAction)
PLACEMENTS: tuple[str, ...] = get_args(Placement)
#: two-level flux reference psi*: controller.psi_ref_wb, or MTPA from the torque reference
PSI_REFS: tuple[str, ...] = get_args(PsiRef)
#: two-level cost normalisation of the torque error: rated torque, or the torque reference (seed 001 eq. (5))
COST_FORMS: tuple[str, ...] = get_args(CostForm)


@dataclass(frozen=True)
class Motor:
    """PMSM parameters (dq model, amplitude-invariant transforms)."""

    rs_ohm: float
    ld_h: float
    lq_h: float
    psi_f_wb: float
    pole_pairs: int
    rated_speed_rpm: float
    rated_torque_nm: float
    j_kgm2: float
    b_nms: float = 0.0


@dataclass(frozen=True)
class Inverter:
    """Inverter and DC link, plus the measurement guard limits of numerics.md."""

    topology: Topology
    udc_v: float
    udc_min_v: float
    udc_max_v: float
    i_trip_a: float
    #: each DC-link capacitor, F (a three-level topology's field; the others keep the default)
    c_f: float = 1000e-6


@dataclass(frozen=True)
class Derivation:
    """Rule for deriving switch tables from utilisation (mptc-two-level.md)."""

    coverage: float = 0.90
    max_active: int = 3


@dataclass(frozen=True)
class Controller:
    """What the generated step computes.

    One dataclass for every topology: a field that only some topologies have
    (each topology's ``section.fields``) is refused in a config of another
    and keeps its default there, where nothing reads it.
    """

    strategy: Strategy
    delay_compensation: bool
    dt_s: float
    # two-level MPTC (the section marks these required)
    predictor: Predictor = "flux-geometry"
    tables: TableSource = "derived"
    psi_ref_wb: float = 0.0
    eps_t_nm: float = 0.0
    number_format: str = "float32"
    #: fixed point only: one global Q (IQmath style, values in SI units); None: per-signal formats
    fixed_q: int | None = None
    #: s2/s3 switch tables written by ``mpcgen tables --derive`` (relative to the config's folder)
    tables_file: str | None = None
    #: the trained switch tables, loaded (not a config field): read from ``tables_file`` when the config is
    #: loaded, or put here by the training stage (``codegen.topologies.twolevel.tables_file.load_into``):
    #: (SHA-256 of the file, ((strategy, table), ...)), table[condition][sector] = candidate vectors; in
    #: the config hash as the SHA-256 alone; None: none loaded
    trained_tables: tuple[str, tuple[tuple[str, tuple[tuple[tuple[int, ...], ...], ...]], ...]] | None = None
    derivation: Derivation = field(default_factory=Derivation)
    # three-level MPDTC only (mpdtc-three-level.md, eq. (7) and (10)-(11))
    lambda_psi_nm_per_wb: float = 28.0
    lambda_vo_nm_per_v: float = 0.01
    t_n_min_s: float | None = None  # None: Ts/6 as in the seed
    #: what a tripped input guard asks the caller to do with the power stage
    fault_action: FaultAction = "gates-off"
    #: active short circuit only at or above this mechanical speed (below it: gates off), r/min
    asc_min_speed_rpm: float = 0.0
    #: two-level flux reference: "constant" (psi_ref_wb) or "mtpa" (psi* of the MTPA point for |T*|)
    psi_ref: PsiRef = "constant"
    #: two-level cost: "rated" (torque error over T_N) or "reference" (over max(|T*|, T_floor), eq. (5))
    cost: CostForm = "rated"
    #: two-level cost: weight of the squared normalised flux term, g = e_T^2 + lambda_psi e_psi^2
    #: (dimensionless; 1 is the papers' cost, bit for bit: no multiplication is emitted)
    lambda_psi: float = 1.0
    # long-horizon current control with a sphere decoder (strategy family "mpcc", docs/mpcc.md); both
    # topologies' sections mark horizon and lambda_u required for it and refuse them elsewhere
    #: prediction horizon N (periods); the decision is the first element of the optimal sequence
    horizon: int = 1
    #: switching weight of the cost sum ||i* - i||^2 + lambda_u ||du||^2, A^2 per unit position change squared
    lambda_u: float = 0.0
    #: nodes the sphere decoder may visit per step (None: the estimate of codegen.mpcc.lattice.default_node_budget)
    node_budget: int | None = None
    #: T-type long-horizon only: neutral-point weight of the cost term lambda_vo V_o(k+d+1)^2, A^2/V^2
    #: (docs/mpcc.md eq. (14)); the default is the T-type family's when the config leaves it out
    lambda_vo_a2_per_v2: float = 10.0


#: the long-horizon fields of :class:`Controller` and their defaults (left out of ``as_dict`` at them)
MPCC_DEFAULTS: dict[str, object] = {"horizon": 1, "lambda_u": 0.0, "node_budget": None, "lambda_vo_a2_per_v2": 10.0}


@dataclass(frozen=True)
class SpeedLoop:
    """Speed PI on the mechanical speed error in rad/s, output clamped."""

    kp: float
    ki: float
    limit_nm: float


@dataclass(frozen=True)
class Scenario:
    """Closed-loop scenario: piecewise-constant steps given as (time_s, value)."""

    duration_s: float
    speed_ref_rpm: tuple[tuple[float, float], ...]
    load_nm: tuple[tuple[float, float], ...]
    speed_mode: SpeedMode = "mechanical"
    #: "config": run this section's profile; "mpdtc-table5": the MPDTC paper's steady speeds and load step
    set: ScenarioSet = "config"
    #: length of the steady window each metric is taken over (end of each constant-reference segment), s
    window_s: float = 0.2


#: the plant parameters whose unset (None) value is the controller's model's: plant field -> that field
PLANT_DEFAULTS: dict[str, str] = {
    "rs_ohm": "motor.rs_ohm", "ld_h": "motor.ld_h", "lq_h": "motor.lq_h", "psi_f_wb": "motor.psi_f_wb",
    "j_kgm2": "motor.j_kgm2", "b_nms": "motor.b_nms", "udc_v": "inverter.udc_v", "c_f": "inverter.c_f",
    "adc_full_scale_a": "inverter.i_trip_a",
}


@dataclass(frozen=True)
class Plant:
    """The simulated plant where it differs from the controller's model, and its non-idealities.

    Every field defaults to "as the controller's model" / "off": a config
    without ``[plant]`` simulates the ideal plant it always did.  None of it
    reaches the generated C.
    """

    #: decision from the samples of period k applied during [k+d, k+d+1) (None: 1 with
    #: controller.delay_compensation, else 0)
    actuation_delay_periods: int | None = None
    # parameter overrides (None: the controller's value), for mismatch studies
    rs_ohm: float | None = None
    ld_h: float | None = None
    lq_h: float | None = None
    psi_f_wb: float | None = None
    j_kgm2: float | None = None
    b_nms: float | None = None
    udc_v: float | None = None
    c_f: float | None = None
    # non-ideal inverter
    dead_time_s: float = 0.0
    device_drop_v: float = 0.0
    # non-ideal sensors
    current_gain_error: float = 0.0
    current_offset_a: float = 0.0
    adc_bits: int = 0
    adc_full_scale_a: float | None = None
    noise_a: float = 0.0
    noise_seed: int = 1
    encoder_bits: int = 0
    measurement_delay_s: float = 0.0
    #: how the simulator integrates the plant (docs/simulation.md "Integration"): "rk4" RK4 sub-steps of
    #: at most 1 us, "exact" the Taylor series of each constant-voltage piece summed to double rounding
    integrator: Literal["rk4", "exact"] = "exact"

    #: the values of ``integrator``, in the simulator's order (``sim_params_t.integrator``)
    INTEGRATORS = ("rk4", "exact")

    def value(self, name: str, model: Model) -> float:
        """The plant's value of the parameter ``name`` (a field of this class): the override, else the
        controller's model's (:data:`PLANT_DEFAULTS`)."""
        own = getattr(self, name)
        if own is not None:
            return float(own)
        section, attr = PLANT_DEFAULTS[name].split(".")
        return float(getattr(getattr(model, section), attr))

    def delay_periods(self, delay_compensation: bool) -> int:
        """The actuation delay d in periods (the default follows the controller's assumption)."""
        if self.actuation_delay_periods is not None:
            return self.actuation_delay_periods
        return 1 if delay_compensation else 0


@dataclass(frozen=True)
class Model:
    """The whole validated configuration."""

    name: str
    prefix: str
    source: str  # path of the file it came from (for messages only)
    motor: Motor
    inverter: Inverter
    controller: Controller
    speed_loop: SpeedLoop
    scenario: Scenario
    target: Target = "host"
    #: memory placement of the step and its tables (stm32h743: "tcm" = ITCM/DTCM sections)
    placement: Placement = "tcm"
    #: the simulated plant's differences from the controller's model (not part of the config hash:
    #: it never reaches the generated C)
    plant: Plant = field(default_factory=Plant)
    #: one-line warnings of the operating-point checks (not part of the config hash)
    warnings: tuple[str, ...] = field(default=(), compare=False)

    def replace(self, **sections: object) -> Model:
        """Return a copy with whole sections or top-level fields replaced."""
        return dataclasses.replace(self, **sections)  # type: ignore[arg-type]

    def with_controller(self, **fields: object) -> Model:
        """Return a copy with some controller fields replaced."""
        return dataclasses.replace(
            self, controller=dataclasses.replace(self.controller, **fields)  # type: ignore[arg-type]
        )

    def as_dict(self) -> dict[str, Any]:
        """Plain-dict view (for JSON reports); ``source`` and ``warnings`` are left out, trained tables
        stand as their file's SHA-256."""
        d = dataclasses.asdict(self)
        d.pop("source", None)
        d.pop("warnings", None)
        trained = d["controller"].pop("trained_tables")
        if trained is not None:  # the file's SHA-256 stands for them (a model without them hashes as before)
            d["controller"]["trained_tables_sha256"] = trained[0]
        for name, default in MPCC_DEFAULTS.items():  # at their defaults: a model hashes as it did before them
            if d["controller"][name] == default:
                d["controller"].pop(name)
        return d

    def config_hash(self) -> str:
        """SHA-256 (hex, 16 chars) of the canonical JSON of the model without its ``[plant]`` section
        (the plant shapes simulations, never the generated code: a plant override keeps the C's bytes)."""
        d = self.as_dict()
        d.pop("plant", None)
        blob = json.dumps(d, sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(blob.encode()).hexdigest()[:16]
