"""Load a TOML configuration file and validate it into a frozen :class:`Model`.

This is the only module that reads configuration files.  The flow is::

    file --tomllib--> nested dict --overrides--> nested dict
         --inverter.topology--> the topology's schema (schema_for)
         --structure check--> flat {"section.field": raw value}
         --per-field checks (the schema, in order)--> flat {"section.field": value}
         --the topology's consistency checks--> Model --its artefacts read in (resolve)--> Model

Every failure raises :class:`~codegen.errors.ConfigError` naming the file, the
dotted field, the offending value and what is allowed.  Field checks are
table driven: :data:`COMMON_SCHEMA` maps each field every topology has to its
kind and allowed interval or choices; each topology's ``section`` module
(found through :mod:`codegen.registry`) adds its own fields and narrows
common ones (:func:`schema_for`).  A field of another topology is refused,
naming the topology it belongs to.  An interval bound may refer to another
field (:class:`Ref`), which must come earlier in the schema; defaults come
from the dataclasses in :mod:`codegen.model`, so they are written down only
once.
"""
from __future__ import annotations

import dataclasses
import difflib
import functools
import math
import re
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NoReturn, Protocol, get_args

from codegen.errors import FILE_FIELD, MISSING, ConfigError, Marker
from codegen.model import (
    FAULT_ACTIONS,
    PLACEMENTS,
    TARGETS,
    Controller,
    Derivation,
    Inverter,
    Model,
    Motor,
    Plant,
    Scenario,
    SpeedLoop,
    SpeedMode,
)
from codegen.numfmt import CONFIG_FORMATS
from codegen.operating import Finding, operating_findings
from codegen.registry import topology_module, topology_names

__all__ = ["load_config", "parse_override", "COMMON_SCHEMA", "schema_for", "all_fields", "owners", "strategies_of",
           "family_of", "family_strategies",
           "topology_section", "TopologySection", "Spec", "Interval", "Ref"]

#: ``ConfigError.file`` for errors in command-line ``--set`` strings.
COMMAND_LINE = "(command line)"

# C keywords (C89..C23) plus the common ``asm`` extension: a prefix equal to
# one of these would still be a valid symbol prefix ("int_step"), but it is
# almost certainly a mistake and is rejected.
C_KEYWORDS: frozenset[str] = frozenset(
    """
    alignas alignof asm auto bool break case char const constexpr continue
    default do double else enum extern false float for goto if inline int long
    nullptr register restrict return short signed sizeof static static_assert
    struct switch thread_local true typedef typeof typeof_unqual union unsigned
    void volatile while
    """.split()
)
PREFIX_PATTERN = r"^[a-z][a-z0-9_]{0,23}$"
_PREFIX_RE = re.compile(PREFIX_PATTERN.strip("^$"))
_OVERRIDE_KEY_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_-]*(\.[A-Za-z_][A-Za-z0-9_-]*)+")


# --------------------------------------------------------------------------
# schema


def _num(x: float) -> str:
    """Compact number text for messages (``5e-05``, ``312``, ``0.9``)."""
    return f"{x:g}"


@dataclass(frozen=True)
class Ref:
    """An interval bound taken from another, already validated field.

    ``scale`` multiplies the other field; ``label`` names the result in
    messages (default: the field path).
    """

    path: str
    scale: float = 1.0
    label: str | None = None

    def resolve(self, values: Mapping[str, object]) -> float:
        """The bound's numeric value."""
        return float(values[self.path]) * self.scale  # type: ignore[arg-type]

    def describe(self, values: Mapping[str, object]) -> str:
        """``label = number`` for messages."""
        return f"{self.label or self.path} = {_num(self.resolve(values))}"


Bound = float | Ref


@dataclass(frozen=True)
class Interval:
    """A real interval; each end closed or open, each bound fixed or a :class:`Ref`."""

    lo: Bound
    hi: Bound
    lo_open: bool = False
    hi_open: bool = False

    @staticmethod
    def _value(bound: Bound, values: Mapping[str, object]) -> float:
        return bound.resolve(values) if isinstance(bound, Ref) else float(bound)

    @staticmethod
    def _text(bound: Bound, values: Mapping[str, object]) -> str:
        return bound.describe(values) if isinstance(bound, Ref) else _num(bound)

    def below(self, x: float, values: Mapping[str, object]) -> bool:
        """True if ``x`` lies below the interval."""
        lo = self._value(self.lo, values)
        return x <= lo if self.lo_open else x < lo

    def above(self, x: float, values: Mapping[str, object]) -> bool:
        """True if ``x`` lies above the interval."""
        hi = self._value(self.hi, values)
        return x >= hi if self.hi_open else x > hi

    def describe(self, values: Mapping[str, object]) -> str:
        """E.g. ``(0, 100]`` or ``[0, Ts/3 = 1.66667e-05] (controller.dt_s = 5e-05)``."""
        text = (
            ("(" if self.lo_open else "[")
            + f"{self._text(self.lo, values)}, {self._text(self.hi, values)}"
            + (")" if self.hi_open else "]")
        )
        scaled = [b.path for b in (self.lo, self.hi) if isinstance(b, Ref) and b.scale != 1.0]
        notes = [f"{p} = {_num(float(values[p]))}" for p in dict.fromkeys(scaled)]  # type: ignore[arg-type]
        return text + (f" ({', '.join(notes)})" if notes else "")


# field kinds
REAL = "real"      # int or float (not bool), finite, in ``interval``
INT = "int"        # int (not bool, not float), in ``interval``
BOOL = "bool"      # true / false
CHOICE = "choice"  # string, one of ``choices``
PREFIX = "prefix"  # C identifier prefix
STEPS = "steps"    # [[time_s, value], ...] with values in ``interval``
PATH = "path"      # optional file path, relative to the config file's folder; must exist
NAME = "name"      # a name printed into generated C comments and Makefiles: printable ASCII, no comment delimiters


@dataclass(frozen=True)
class Spec:
    """How one field is checked.

    ``hint_low`` / ``hint_high`` start the message when a number is below /
    above the interval; ``hint`` replaces "must be one of" for a choice (a
    boolean with ``choices`` allows only those values).  ``required``: the
    file must give the field, whatever the model's default (a field that
    only one topology has keeps a default in the model for the others).
    ``families``: the strategy families (``TopologySection.families``) whose
    strategies read the field; empty: every strategy.  Under a strategy of
    another family the field is refused when given and keeps the model's
    default, and ``required`` applies only inside the families.
    """

    kind: str
    interval: Interval | None = None
    choices: tuple[object, ...] = ()
    hint: str = ""
    hint_low: str = ""
    hint_high: str = ""
    required: bool = False
    families: tuple[str, ...] = ()


def open_closed(lo: Bound, hi: Bound) -> Interval:
    """(lo, hi]"""
    return Interval(lo, hi, lo_open=True)


def closed(lo: Bound, hi: Bound) -> Interval:
    """[lo, hi]"""
    return Interval(lo, hi)


def closed_open(lo: Bound, hi: Bound) -> Interval:
    """[lo, hi)"""
    return Interval(lo, hi, hi_open=True)


def open_interval(lo: Bound, hi: Bound) -> Interval:
    """(lo, hi)"""
    return Interval(lo, hi, lo_open=True, hi_open=True)


def real_spec(interval: Interval, hint_low: str = "", hint_high: str = "", required: bool = False) -> Spec:
    """A real field in ``interval``."""
    return Spec(REAL, interval, hint_low=hint_low, hint_high=hint_high, required=required)


def choice_spec(choices: tuple[str, ...], hint: str = "", required: bool = False) -> Spec:
    """A string field, one of ``choices``."""
    return Spec(CHOICE, choices=tuple(choices), hint=hint, required=required)


_RATED_RPM = "motor.rated_speed_rpm"

#: The fields every topology has, in check order (a :class:`Ref` must point upwards); each topology
#: adds its own after them and may narrow some (its ``section`` module, :func:`schema_for`).
#: The section of ``a.b.c`` is ``a.b``; the TOML layout follows from it.
COMMON_SCHEMA: dict[str, Spec] = {
    "meta.name": Spec(NAME),
    "meta.prefix": Spec(PREFIX),
    "motor.rs_ohm": real_spec(open_closed(0, 100)),
    "motor.ld_h": real_spec(open_closed(0, 1)),
    "motor.lq_h": real_spec(open_closed(0, 1)),
    "motor.psi_f_wb": real_spec(open_closed(0, 10)),
    "motor.pole_pairs": Spec(INT, closed(1, 64)),
    "motor.rated_speed_rpm": real_spec(open_closed(0, 1e5)),
    "motor.rated_torque_nm": real_spec(open_closed(0, 1e5)),
    "motor.j_kgm2": real_spec(open_closed(0, 1e3)),
    "motor.b_nms": real_spec(closed(0, 1e3)),
    "inverter.topology": choice_spec(topology_names()),
    "inverter.udc_v": real_spec(open_closed(0, 1e4)),
    "inverter.udc_min_v": real_spec(
        open_interval(0, Ref("inverter.udc_v")),
        hint_high="DC-link undervoltage guard not below the nominal DC-link voltage",
    ),
    "inverter.udc_max_v": real_spec(
        open_closed(Ref("inverter.udc_v"), 2e4),
        hint_low="DC-link overvoltage guard not above the nominal DC-link voltage",
    ),
    "inverter.i_trip_a": real_spec(open_closed(0, 1e5)),
    # its choices: the strategies of the config's topology (schema_for)
    "controller.strategy": Spec(CHOICE),
    "controller.delay_compensation": Spec(BOOL),
    "controller.dt_s": real_spec(closed(1e-6, 1e-3)),
    "controller.number_format": choice_spec(CONFIG_FORMATS),
    "controller.fixed_q": Spec(INT, closed(8, 30)),
    "controller.fault_action": choice_spec(FAULT_ACTIONS),
    "controller.asc_min_speed_rpm": real_spec(closed(0, Ref(_RATED_RPM, 10.0, "10*rated"))),
    "speed_loop.kp": real_spec(closed(0, 1e6)),
    "speed_loop.ki": real_spec(closed(0, 1e6)),
    "speed_loop.limit_nm": real_spec(open_closed(0, 1e6)),
    "scenario.duration_s": real_spec(closed(Ref("controller.dt_s", 10.0, "10*dt_s"), 100),
                                     hint_low="a run shorter than 10 control periods has no metrics"),
    "scenario.speed_mode": choice_spec(get_args(SpeedMode)),
    "scenario.set": choice_spec(("config",), hint="this topology runs the config's own scenario"),
    "scenario.window_s": real_spec(open_closed(0, 100)),
    "scenario.speed_ref_rpm": Spec(
        STEPS, closed(Ref(_RATED_RPM, -10.0, "-10*rated"), Ref(_RATED_RPM, 10.0, "10*rated"))
    ),
    "scenario.load_nm": Spec(STEPS),
    "plant.actuation_delay_periods": Spec(INT, closed(0, 2)),
    "plant.rs_ohm": real_spec(open_closed(0, 100)),
    "plant.ld_h": real_spec(open_closed(0, 1)),
    "plant.lq_h": real_spec(open_closed(0, 1)),
    "plant.psi_f_wb": real_spec(open_closed(0, 10)),
    "plant.j_kgm2": real_spec(open_closed(0, 1e3)),
    "plant.b_nms": real_spec(closed(0, 1e3)),
    "plant.udc_v": real_spec(open_closed(0, 1e4)),
    "plant.dead_time_s": real_spec(closed(0, Ref("controller.dt_s", 0.1, "dt_s/10"))),
    "plant.device_drop_v": real_spec(closed(0, 50)),
    "plant.current_gain_error": real_spec(closed(-0.5, 0.5)),
    "plant.current_offset_a": real_spec(closed(Ref("inverter.i_trip_a", -1.0, "-i_trip_a"), Ref("inverter.i_trip_a"))),
    "plant.adc_bits": Spec(INT, closed(0, 24)),
    "plant.adc_full_scale_a": real_spec(open_closed(0, 1e5)),
    "plant.noise_a": real_spec(closed(0, Ref("inverter.i_trip_a"))),
    "plant.noise_seed": Spec(INT, closed(0, 2**31 - 1)),
    "plant.encoder_bits": Spec(INT, closed(0, 24)),
    "plant.measurement_delay_s": real_spec(closed(0, Ref("controller.dt_s"))),
    "plant.integrator": choice_spec(Plant.INTEGRATORS),
    "target.name": choice_spec(TARGETS),
    "target.placement": choice_spec(PLACEMENTS),
}

# Which dataclass holds each section's fields (for defaults and building the
# Model), and the fields whose attribute name differs from the TOML key.
_SECTION_CLASS: dict[str, type] = {
    "meta": Model,
    "motor": Motor,
    "inverter": Inverter,
    "controller": Controller,
    "controller.derivation": Derivation,
    "speed_loop": SpeedLoop,
    "scenario": Scenario,
    "plant": Plant,
    "target": Model,
}
_ATTR_NAME: dict[str, str] = {"target.name": "target"}


def _section_of(path: str) -> str:
    return path.rpartition(".")[0]


def _key_of(path: str) -> str:
    return path.rpartition(".")[2]


def _attr_of(path: str) -> str:
    return _ATTR_NAME.get(path, _key_of(path))


class TopologySection(Protocol):
    """A topology's part of the configuration: the module ``<package>.section`` of its plugin package
    (:mod:`codegen.registry`), read while a file is loaded."""

    #: every strategy, in report order; the first is the baseline the others are compared to
    strategies: tuple[str, ...]
    #: strategy family -> its strategies (each strategy in one family, in report order): a command that
    #: runs several strategies runs the family of the config's strategy, and a field whose spec names
    #: families is read only by their strategies
    families: Mapping[str, tuple[str, ...]]
    #: the fields only this topology has, in check order (checked after :data:`COMMON_SCHEMA`)
    fields: Mapping[str, Spec]
    #: common fields whose allowed values this topology narrows (or widens)
    narrowed: Mapping[str, Spec]

    def check(self, values: Mapping[str, object], fail: Callable[[str, object, str], NoReturn]) -> None:
        """Consistency between fields, once every field passed its own check (``fail(field, value,
        allowed)`` raises the one-line error)."""
        ...

    def operating_findings(self, model: Model) -> list[Finding]:
        """The topology's own operating-point findings (after the common ones)."""
        ...

    def resolve(self, model: Model) -> Model:
        """The model with the artefacts its config names read in (pure of compilers and runs)."""
        ...


@functools.cache
def topology_section(name: str) -> TopologySection:
    """The config section module of topology ``name`` (a registry value)."""
    section: TopologySection = topology_module(name, "section")  # type: ignore[assignment]
    return section


def strategies_of(topology: str) -> tuple[str, ...]:
    """The strategies of ``topology``, in report order."""
    return topology_section(topology).strategies


def family_of(topology: str, strategy: str) -> str:
    """The strategy family of ``strategy`` of ``topology`` (a key of its section's ``families``)."""
    for name, members in topology_section(topology).families.items():
        if strategy in members:
            return name
    raise ValueError(f"strategy {strategy!r} of {topology!r} is in no family")


def family_strategies(topology: str, strategy: str) -> tuple[str, ...]:
    """The strategies of the family ``strategy`` belongs to, in report order (what a command runs by
    default: the config's strategy and its siblings, never another family's)."""
    return topology_section(topology).families[family_of(topology, strategy)]


@functools.cache
def schema_for(topology: str) -> dict[str, Spec]:
    """Every field of a config of ``topology``, in check order: the common ones (narrowed where the
    topology narrows them, ``controller.strategy`` one of its strategies), then its own."""
    section = topology_section(topology)
    common = {**COMMON_SCHEMA, **section.narrowed,
              "controller.strategy": choice_spec(section.strategies)}
    return {**{p: common[p] for p in COMMON_SCHEMA}, **section.fields}


@functools.cache
def all_fields() -> dict[str, Spec]:
    """Every field any topology has (the first topology's spec where two narrow one differently)."""
    out: dict[str, Spec] = {}
    for name in topology_names():
        for path, spec in schema_for(name).items():
            out.setdefault(path, spec)
    return out


def owners(path: str) -> tuple[str, ...]:
    """The topologies whose configs have field ``path`` (every one for a common field)."""
    return tuple(t for t in topology_names() if path in schema_for(t))


def _sections(schema: Mapping[str, Spec]) -> tuple[str, ...]:
    """The dotted sections of ``schema``'s fields, in order."""
    return tuple(dict.fromkeys(_section_of(p) for p in schema))


def _fields_of(schema: Mapping[str, Spec], section: str) -> list[str]:
    """TOML keys of the fields directly in ``section``."""
    return [_key_of(p) for p in schema if _section_of(p) == section]


def _subsections_of(schema: Mapping[str, Spec], section: str) -> list[str]:
    """Names of the tables directly inside ``section`` ("" is the top level)."""
    return [_key_of(s) for s in _sections(schema) if _section_of(s) == section]


def _default(path: str) -> object:
    """The model's default for a field, or :data:`MISSING` if it is required."""
    attr = _attr_of(path)
    for f in dataclasses.fields(_SECTION_CLASS[_section_of(path)]):
        if f.name == attr:
            if f.default is not dataclasses.MISSING:
                return f.default
            if f.default_factory is not dataclasses.MISSING:
                return f.default_factory()
            return MISSING
    raise LookupError(f"schema field {path} has no model attribute {attr}")


def _is_required(schema: Mapping[str, Spec], path: str) -> bool:
    """The file must give ``path``: the spec says so, or the model has no default."""
    return schema[path].required or _default(path) is MISSING


def _required(schema: Mapping[str, Spec], section: str, family: str | None = None) -> bool:
    """A section is required if it has a required field (that the strategy's ``family`` reads)."""
    return any(_is_required(schema, f"{section}.{k}") and not _outside_family(schema[f"{section}.{k}"], family)
               and not _family_unknown(schema[f"{section}.{k}"], family) for k in _fields_of(schema, section))


# --------------------------------------------------------------------------
# checking


class _Checker:
    """Holds the file name, overridden fields and the values checked so far."""

    def __init__(self, file: str, overridden: frozenset[str]) -> None:
        self.file = file
        self.overridden = overridden
        self.values: dict[str, object] = {}

    def fail(self, path: str, value: object, allowed: str) -> NoReturn:
        """Raise a ConfigError; mention it if the value came from an override."""
        base = path.split("[", 1)[0]
        if any(o == base or o.startswith(base + ".") for o in self.overridden):
            allowed += " (value set by override)"
        raise ConfigError(self.file, path, value, allowed)


def _is_number(value: object) -> bool:
    """int or float, but not bool (bool is an int subclass in Python)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _check_real(ck: _Checker, path: str, value: object, spec: Spec) -> float | None:
    assert spec.interval is not None
    if value is None and _default(path) is None:
        return None  # optional field left at "derive it" (e.g. t_n_min_s)
    rng = spec.interval.describe(ck.values)
    if isinstance(value, bool):
        ck.fail(path, value, f"must be a number in {rng}, not a boolean")
    if not _is_number(value):
        ck.fail(path, value, f"must be a number in {rng}")
    x = float(value)  # type: ignore[arg-type]
    if not math.isfinite(x):
        ck.fail(path, value, f"must be a finite number in {rng}")
    _check_interval(ck, path, value, x, spec, f"must be in {rng}")
    return x


def _check_interval(ck: _Checker, path: str, value: object, x: float, spec: Spec, allowed: str) -> None:
    """Fail if ``x`` is outside ``spec.interval``, prefixing the matching hint."""
    assert spec.interval is not None
    if spec.interval.below(x, ck.values):
        ck.fail(path, value, f"{spec.hint_low}: {allowed}" if spec.hint_low else allowed)
    if spec.interval.above(x, ck.values):
        ck.fail(path, value, f"{spec.hint_high}: {allowed}" if spec.hint_high else allowed)


def _check_int(ck: _Checker, path: str, value: object, spec: Spec) -> int | None:
    assert spec.interval is not None
    if value is None and _default(path) is None:
        return None  # optional field left at "derive it" (e.g. fixed_q)
    allowed = f"must be an integer in {spec.interval.describe(ck.values)}"
    if isinstance(value, bool) or not isinstance(value, int):
        ck.fail(path, value, allowed)
    _check_interval(ck, path, value, float(value), spec, allowed)
    return value


def _check_bool(ck: _Checker, path: str, value: object, spec: Spec) -> bool:
    if not isinstance(value, bool):
        ck.fail(path, value, "must be true or false")
    if spec.choices and value not in spec.choices:
        only = " or ".join(str(c).lower() for c in spec.choices)
        ck.fail(path, value, f"{spec.hint}; allowed: {only}" if spec.hint else f"must be {only}")
    return value


def _check_path(ck: _Checker, path: str, value: object, spec: Spec) -> str | None:
    if value is None:
        return None
    if not isinstance(value, str) or not value.strip():
        ck.fail(path, value, "must be a non-empty file path (relative to the config file's folder)")
    where = resolve_path(ck.file, value)
    if not where.is_file():
        ck.fail(path, value, f"file not found: {where} (a path is relative to the config file's folder; "
                "write the file with `mpcgen tables CONFIG --derive -o FILE`)")
    return value


def resolve_path(config_file: str, value: str) -> Path:
    """A path from a config field: absolute, or relative to the config file's folder."""
    p = Path(value)
    return p if p.is_absolute() else Path(config_file).parent / p


_NAME_RE = re.compile(r"[ -~]{1,80}")


def _check_name(ck: _Checker, path: str, value: object, spec: Spec) -> str:
    allowed = ("must be a non-empty string of at most 80 printable ASCII characters without '/*', '*/' or a backslash "
               "(it is printed into generated C comments and Makefiles)")
    if not isinstance(value, str) or not value.strip() or not _NAME_RE.fullmatch(value):
        ck.fail(path, value, allowed)
    if "/*" in value or "*/" in value or "\\" in value:
        ck.fail(path, value, allowed)
    return value


def _check_choice(ck: _Checker, path: str, value: object, spec: Spec) -> str:
    options = ", ".join(map(str, spec.choices))
    allowed = f"{spec.hint}, allowed: {options}" if spec.hint else f"must be one of {options}"
    if not isinstance(value, str):
        ck.fail(path, value, f"must be a string; {allowed}")
    if value not in spec.choices:
        ck.fail(path, value, allowed)
    return value


def _check_prefix(ck: _Checker, path: str, value: object, spec: Spec) -> str:
    allowed = f"must be a C identifier matching {PREFIX_PATTERN} and not a C keyword"
    if not isinstance(value, str) or not _PREFIX_RE.fullmatch(value):
        ck.fail(path, value, allowed)
    if value in C_KEYWORDS:
        ck.fail(path, value, f"is a C keyword; {allowed}")
    return value


def _check_steps(ck: _Checker, path: str, value: object, spec: Spec) -> tuple[tuple[float, float], ...]:
    """A piecewise-constant profile: [[0, v0], [t1, v1], ...] within the scenario."""
    shape = "must be a non-empty list of [time_s, value] pairs"
    if not isinstance(value, (list, tuple)) or not value:
        ck.fail(path, value, shape)
    duration = float(ck.values["scenario.duration_s"])  # type: ignore[arg-type]
    steps: list[tuple[float, float]] = []
    for i, item in enumerate(value):
        where = f"{path}[{i}]"
        if not (isinstance(item, (list, tuple)) and len(item) == 2 and all(map(_is_number, item))):
            ck.fail(where, item, f"must be a [time_s, value] pair of numbers ({path} {shape})")
        t, v = float(item[0]), float(item[1])
        if not (math.isfinite(t) and math.isfinite(v)):
            ck.fail(where, item, "time and value must be finite numbers")
        if i == 0 and t != 0.0:
            ck.fail(where, item, "the first time must be exactly 0")
        if steps and t <= steps[-1][0]:
            ck.fail(where, item, f"times must be strictly increasing: {_num(t)} <= previous time {_num(steps[-1][0])}")
        if t >= duration:
            ck.fail(where, item, f"time must be < scenario.duration_s = {_num(duration)}")
        if spec.interval is not None:
            _check_interval(ck, where, item, v, spec, f"value must be in {spec.interval.describe(ck.values)}")
        steps.append((t, v))
    return tuple(steps)


_CHECKS: dict[str, Callable[[_Checker, str, object, Spec], object]] = {
    REAL: _check_real,
    INT: _check_int,
    BOOL: _check_bool,
    CHOICE: _check_choice,
    PREFIX: _check_prefix,
    STEPS: _check_steps,
    PATH: _check_path,
    NAME: _check_name,
}


# --------------------------------------------------------------------------
# consistency between fields


def _check_foreign_value(ck: _Checker, schema: Mapping[str, Spec], path: str, value: object) -> None:
    """A choice another topology allows but this one does not: say whose it is (before the field check)."""
    spec = schema[path]
    if spec.kind != CHOICE or value in spec.choices or not isinstance(value, str):
        return
    topology = ck.values["inverter.topology"]
    theirs = [t for t in topology_names()
              if t != topology and path in schema_for(t) and value in schema_for(t)[path].choices]
    if theirs:
        ck.fail(path, value, f"belongs to inverter.topology = '{theirs[0]}', but inverter.topology = "
                             f"'{topology}'; allowed for '{topology}': {', '.join(map(str, spec.choices))}")


# --------------------------------------------------------------------------
# reading, structure, overrides


def _read_toml(file: str) -> dict[str, Any]:
    """Parse the file; any failure is a ConfigError on field ``(file)``."""
    try:
        blob = Path(file).read_bytes()
    except FileNotFoundError as exc:
        raise ConfigError(file, FILE_FIELD, file, "file not found; expected a TOML config file") from exc
    except IsADirectoryError as exc:
        raise ConfigError(file, FILE_FIELD, file, "is a directory; expected a TOML config file") from exc
    except OSError as exc:
        raise ConfigError(file, FILE_FIELD, file, f"cannot read file: {exc.strerror or exc}") from exc
    try:
        text = blob.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(
            file, FILE_FIELD, Marker("<binary data>"),
            f"not TOML: not UTF-8 text (byte {blob[exc.start]:#04x} at offset {exc.start})",
        ) from exc
    if text.startswith("\ufeff"):
        raise ConfigError(file, FILE_FIELD, Marker("<byte-order mark>"),
                          "not TOML: the file starts with a UTF-8 byte-order mark (BOM), which TOML does not "
                          "allow; save it as UTF-8 without BOM")
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(file, FILE_FIELD, _offending_line(text, str(exc)),
                          f"not TOML: {exc}{_lookalike_hint(text, str(exc))}") from exc


#: characters that look like TOML syntax but are not ASCII, with the ASCII they stand for
_LOOKALIKES: dict[str, str] = {
    "\u2212": "-", "\u2013": "-", "\u2014": "-", "\u2010": "-", "\u2011": "-", "\u00a0": " ", "\u2009": " ",
    "\u202f": " ", "\u201c": '"', "\u201d": '"', "\u2018": "'", "\u2019": "'", "\uff1d": "=", "\u00d7": "*",
}


def _lookalike_hint(text: str, message: str) -> str:
    """``; line N column C is U+2212 MINUS SIGN, not '-'`` when the line a TOML error names holds a
    character that only looks like TOML syntax (pasted from a document)."""
    import unicodedata

    m = re.search(r"at line (\d+)", message)
    lines = text.splitlines()
    if not m or not 1 <= int(m.group(1)) <= len(lines):
        return ""
    line = lines[int(m.group(1)) - 1]
    for col, ch in enumerate(line, start=1):
        if ch in _LOOKALIKES:
            return (f"; line {m.group(1)} column {col} is U+{ord(ch):04X} {unicodedata.name(ch, '?')}, "
                    f"not the ASCII {_LOOKALIKES[ch]!r} it looks like")
    return ""


def _offending_line(text: str, message: str) -> object:
    """The source line a TOML error message points at (or a marker)."""
    m = re.search(r"at line (\d+)", message)
    lines = text.splitlines()
    if m and 1 <= int(m.group(1)) <= len(lines) and lines[int(m.group(1)) - 1].strip():
        return lines[int(m.group(1)) - 1].strip()
    return Marker("<not TOML>")


def _apply_overrides(ck: _Checker, data: dict[str, Any], overrides: Mapping[str, object]) -> None:
    """Set each dotted ``section.field`` in the parsed document (in place)."""
    for key, value in overrides.items():
        parts = key.split(".")
        if len(parts) < 2 or not all(parts):
            ck.fail(key, value, "an override must name a dotted field such as controller.strategy")
        node = data
        for i, part in enumerate(parts[:-1]):
            node = node.setdefault(part, {})
            if not isinstance(node, dict):
                ck.fail(".".join(parts[: i + 1]), node, f"must be a table to apply override {key}")
        node[parts[-1]] = value


def _lookup_table(ck: _Checker, data: dict[str, Any], section: str) -> dict[str, Any] | None:
    """The table for a dotted section, None if absent, error if not a table."""
    node: object = data
    for part in section.split("."):
        node = node.get(part) if isinstance(node, dict) else None
        if node is None:
            return None
    if not isinstance(node, dict):
        ck.fail(section, node, f"must be a table [{section}]")
    return node


def _foreign(path: str) -> str | None:
    """The topologies that have ``path`` as a field or a section, as text (None: no topology has it)."""
    theirs = [t for t in topology_names()
              if path in schema_for(t) or any(p.startswith(path + ".") for p in schema_for(t))]
    return " or ".join(f"'{t}'" for t in theirs) or None


def _check_keys(ck: _Checker, schema: Mapping[str, Spec], section: str, table: dict[str, Any]) -> None:
    """Reject keys that are neither fields nor sub-sections of ``section``; a key another topology has
    is named as that topology's."""
    fields, subs = _fields_of(schema, section), _subsections_of(schema, section)
    known = fields + subs
    for key, value in table.items():
        if key in known:
            continue
        path = f"{section}.{key}" if section else key
        theirs = _foreign(path)
        if theirs is not None:
            topology = ck.values["inverter.topology"]
            ck.fail(path, value, f"belongs to inverter.topology = {theirs}; a '{topology}' config has no "
                                 f"such field: remove it")
        guess = difflib.get_close_matches(key, known, n=1)
        maybe = f" (did you mean '{guess[0]}'?)" if guess else ""
        if section:
            tables = f"; sections: {', '.join(f'[{section}.{s}]' for s in subs)}" if subs else ""
            ck.fail(path, value,
                    f"unknown field in [{section}]{maybe}; allowed fields: {', '.join(fields)}{tables}")
        ck.fail(key, value, f"unknown section{maybe}; allowed sections: {', '.join(subs)}")


def _topology(ck: _Checker, data: dict[str, Any]) -> str:
    """``inverter.topology``, checked first: it decides which fields the file may have."""
    inverter = _lookup_table(ck, data, "inverter")
    value = (inverter or {}).get("topology", MISSING)
    if value is MISSING:
        ck.fail("inverter.topology", MISSING, f"required field missing in [inverter]; allowed: "
                                              f"{', '.join(topology_names())}")
    name: str = _check_choice(ck, "inverter.topology", value, COMMON_SCHEMA["inverter.topology"])
    ck.values["inverter.topology"] = name
    return name


def _family(ck: _Checker, data: dict[str, Any], topology: str) -> str | None:
    """The strategy family of the file's ``controller.strategy`` (None when it names no strategy of the
    topology: the field's own check reports that)."""
    controller = data.get("controller")
    value = controller.get("strategy") if isinstance(controller, dict) else None
    if not isinstance(value, str) or value not in strategies_of(topology):
        return None
    return family_of(topology, value)


def _outside_family(spec: Spec, family: str | None) -> bool:
    """The field is read by no strategy of ``family`` (None: unknown yet, nothing refused)."""
    return bool(spec.families) and family is not None and family not in spec.families


def _family_unknown(spec: Spec, family: str | None) -> bool:
    """The field belongs to some families and the strategy names none (its own check will say so):
    the field is not required yet."""
    return bool(spec.families) and family is None


def _collect(ck: _Checker, schema: Mapping[str, Spec], data: dict[str, Any],
             family: str | None = None) -> dict[str, object]:
    """Check the document's structure; return raw values by dotted path (defaults filled in).  A field
    that the strategy's ``family`` does not read is refused when given, and defaulted."""
    _check_keys(ck, schema, "", data)
    raw: dict[str, object] = {}
    sections = _sections(schema)
    for section in sections:
        table = _lookup_table(ck, data, section)
        if table is None:
            if _required(schema, section, family):
                ck.fail(section, MISSING, f"required section [{section}] is missing; "
                        f"sections: {', '.join(f'[{s}]' for s in sections)}")
            table = {}
        else:
            _check_keys(ck, schema, section, table)
        for key in _fields_of(schema, section):
            path = f"{section}.{key}"
            spec = schema[path]
            if _outside_family(spec, family):
                if key in table:
                    strategy = data["controller"]["strategy"]
                    ck.fail(path, table[key], f"is ignored by controller.strategy = '{strategy}' (only the "
                            f"{' and '.join(spec.families)} strategies read it): remove it")
                raw[path] = _default(path)
                continue
            if key not in table and _is_required(schema, path) and not _family_unknown(spec, family):
                ck.fail(path, MISSING, f"required field missing in [{section}]; "
                        f"fields: {', '.join(_fields_of(schema, section))}")
            raw[path] = table[key] if key in table else _default(path)
    return raw


def _build(values: Mapping[str, object], source: str) -> Model:
    """Assemble the frozen Model from checked values (a field the topology does not have keeps the
    model's default)."""

    def kw(section: str) -> dict[str, Any]:
        return {_attr_of(p): v for p, v in values.items() if _section_of(p) == section}

    return Model(
        **kw("meta"),
        **kw("target"),
        source=source,
        motor=Motor(**kw("motor")),
        inverter=Inverter(**kw("inverter")),
        controller=Controller(**kw("controller"), derivation=Derivation(**kw("controller.derivation"))),
        speed_loop=SpeedLoop(**kw("speed_loop")),
        scenario=Scenario(**kw("scenario")),
        plant=Plant(**kw("plant")),
    )


# --------------------------------------------------------------------------
# public API


def load_config(path: str | Path, overrides: Mapping[str, object] | None = None) -> Model:
    """Read, override and validate a TOML config file.

    Args:
        path: the config file; kept as given in ``Model.source`` and messages.
        overrides: dotted field paths to values (e.g.
            ``{"controller.strategy": "s2"}``), applied to the parsed file
            before validation, so they are checked exactly like file values.

    Raises:
        ConfigError: for the first problem found (file, structure, type,
            range, consistency).
    """
    source = str(path)
    overrides = overrides or {}
    data = _read_toml(source)
    ck = _Checker(source, frozenset(overrides))
    _apply_overrides(ck, data, overrides)
    topology = _topology(ck, data)
    schema = schema_for(topology)
    section = topology_section(topology)
    family = _family(ck, data, topology)
    raw = _collect(ck, schema, data, family)
    for field_path, spec in schema.items():
        if _outside_family(spec, family):  # the model's default, unread by this strategy
            ck.values[field_path] = raw[field_path]
            continue
        _check_foreign_value(ck, schema, field_path, raw[field_path])
        ck.values[field_path] = _CHECKS[spec.kind](ck, field_path, raw[field_path], spec)
    section.check(ck.values, ck.fail)
    model = section.resolve(_build(ck.values, source))
    findings = operating_findings(model) + section.operating_findings(model)
    findings.sort(key=lambda f: not f.error)
    for f in findings:
        if f.error:
            ck.fail(f.field, f.value, f.text)
    return dataclasses.replace(model, warnings=tuple(
        str(ConfigError(source, f.field, f.value, f.text)) for f in findings))


def parse_override(text: str) -> tuple[str, object]:
    """Parse a command-line ``section.field=value`` string.

    The value is read as a TOML value if possible (``true``, ``5e-5``,
    ``"s2"``, ``[[0, 500]]``), otherwise taken as a bare string (``s2``).

    Raises:
        ConfigError: if ``text`` is not of the form ``section.field=value``.
    """
    key, sep, raw = text.partition("=")
    key, raw = key.strip(), raw.strip()
    if not sep or not _OVERRIDE_KEY_RE.fullmatch(key):
        raise ConfigError(COMMAND_LINE, "--set", text,
                          "must be section.field=value, e.g. controller.strategy=s2")
    try:
        doc = tomllib.loads(f"v = {raw}")
    except tomllib.TOMLDecodeError:
        return key, raw
    return (key, doc["v"]) if list(doc) == ["v"] else (key, raw)
