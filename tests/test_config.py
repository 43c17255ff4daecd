"""Tests of codegen.config: loading, overrides, the frozen model and every
kind of invalid configuration (each message names file, field, value and
what is allowed)."""
from __future__ import annotations

import dataclasses
import json
import math
import tomllib
from pathlib import Path

import pytest

from codegen import model as model_module
from codegen.config import all_fields, load_config, parse_override
from codegen.errors import ConfigError, MpcgenError

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
SPMSM = EXAMPLES / "seed001_spmsm.toml"
IPMSM = EXAMPLES / "seed001_ipmsm.toml"
TLEVEL = EXAMPLES / "seed000_tlevel.toml"
DELETE = object()  # edit value meaning "remove this field or section"


# --------------------------------------------------------------------------
# helpers


def _toml_value(v: object) -> str:
    """One value in TOML syntax (enough for the config layout)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, float) and not math.isfinite(v):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf")
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {v!r} as TOML")


def dump_toml(table: dict, name: str = "") -> str:
    """Serialise nested dicts as TOML: scalars first, then sub-tables."""
    lines = [f"[{name}]"] if name else []
    lines += [f"{k} = {_toml_value(v)}" for k, v in table.items() if not isinstance(v, dict)]
    for k, v in table.items():
        if isinstance(v, dict):
            lines += ["", dump_toml(v, f"{name}.{k}" if name else k)]
    return "\n".join(lines) + "\n"


def edited(base: Path, edits: dict[str, object]) -> dict:
    """The example's parsed dict with dotted-path edits (DELETE removes)."""
    data = tomllib.loads(base.read_text())
    for path, value in edits.items():
        *parents, key = path.split(".")
        node = data
        for part in parents:
            node = node.setdefault(part, {})
        if value is DELETE:
            del node[key]
        else:
            node[key] = value
    return data


def write_config(tmp_path: Path, edits: dict[str, object], base: Path = SPMSM) -> Path:
    """Write the example with ``edits`` applied to tmp_path/config.toml."""
    path = tmp_path / "config.toml"
    path.write_text(dump_toml(edited(base, edits)))
    return path


def assert_message(err: ConfigError, file: Path | str, field: str, value: str, allowed: str) -> None:
    """The one-line message names file, field, value and what is allowed."""
    msg = str(err)
    assert "\n" not in msg
    assert msg.startswith(f"{file}: {field}"), msg
    for fragment in (str(file), field, value, allowed):
        assert fragment in msg, f"{fragment!r} not in {msg!r}"


# --------------------------------------------------------------------------
# valid configs


def test_load_spmsm_example() -> None:
    m = load_config(SPMSM)
    assert m.name == "seed001_spmsm" and m.prefix == "spmsm"
    assert m.motor.ld_h == 8.5e-3 == m.motor.lq_h
    assert m.motor.pole_pairs == 4 and isinstance(m.motor.pole_pairs, int)
    assert m.inverter.topology == "two-level"
    assert m.controller.predictor == "flux-geometry"
    assert m.controller.delay_compensation is False
    assert m.controller.dt_s == 50e-6
    assert m.controller.derivation.coverage == 0.90
    assert m.controller.derivation.max_active == 3
    assert m.scenario.speed_ref_rpm == ((0.0, 500.0), (2.0, -500.0))
    assert m.scenario.load_nm == ((0.0, 10.0), (1.0, -10.0), (3.0, 10.0))
    assert m.target == "host"
    assert m.source == str(SPMSM)


def test_load_ipmsm_example() -> None:
    m = load_config(IPMSM)
    assert m.controller.predictor == "dq-euler"
    assert (m.motor.ld_h, m.motor.lq_h) == (3.3e-3, 7.3e-3)
    assert m.scenario.duration_s == 2.0


def test_source_is_the_path_as_given(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    write_config(tmp_path, {})
    monkeypatch.chdir(tmp_path)
    assert load_config("config.toml").source == "config.toml"


def test_optional_fields_and_sections_take_model_defaults(tmp_path: Path) -> None:
    path = write_config(tmp_path, {
        "motor.b_nms": DELETE, "controller.number_format": DELETE,
        "controller.derivation": DELETE, "target": DELETE, "scenario.speed_mode": DELETE,
    })
    m = load_config(path)
    assert m.motor.b_nms == 0.0
    assert m.inverter.c_f == 1000e-6
    assert m.controller.number_format == "float32"
    assert m.controller.derivation == model_module.Derivation()
    assert m.controller.t_n_min_s is None
    assert m.scenario.speed_mode == "mechanical"
    assert m.target == "host"


def test_valid_ttype_config(tmp_path: Path) -> None:
    path = write_config(tmp_path, {
        "controller.strategy": "mpdtc63", "controller.t_n_min_s": 50e-6 / 6, "inverter.c_f": 2.2e-3,
    }, base=TLEVEL)
    m = load_config(path)
    assert m.controller.strategy == "mpdtc63"
    assert m.controller.t_n_min_s == pytest.approx(50e-6 / 6)
    assert m.inverter.c_f == 2.2e-3


def test_ints_accepted_for_floats_and_normalised(tmp_path: Path) -> None:
    m = load_config(write_config(tmp_path, {"inverter.udc_v": 312, "speed_loop.kp": 5}))
    assert isinstance(m.inverter.udc_v, float) and isinstance(m.speed_loop.kp, float)
    assert m.config_hash() == load_config(SPMSM).config_hash()


def test_schema_covers_every_model_field() -> None:
    """No Model field is silently left at its default by the loader."""
    leaves = {"meta.name", "meta.prefix", "target.name", "target.placement"}
    sections = {"motor": model_module.Motor, "inverter": model_module.Inverter,
                "controller": model_module.Controller, "speed_loop": model_module.SpeedLoop,
                "scenario": model_module.Scenario, "controller.derivation": model_module.Derivation,
                "plant": model_module.Plant}
    for section, cls in sections.items():
        loaded = ("derivation", "trained_tables")  # a sub-section; the artefact read at load (not a field)
        leaves |= {f"{section}.{f.name}" for f in dataclasses.fields(cls) if f.name not in loaded}
    assert set(all_fields()) == leaves


# --------------------------------------------------------------------------
# overrides


def test_overrides_are_applied() -> None:
    m = load_config(SPMSM, {"controller.strategy": "s2", "target.name": "stm32h743",
                            "controller.delay_compensation": True,
                            "controller.derivation.max_active": 2})
    assert m.controller.strategy == "s2"
    assert m.target == "stm32h743"
    assert m.controller.delay_compensation is True
    assert m.controller.derivation.max_active == 2


@pytest.mark.parametrize(("overrides", "field", "value", "allowed"), [
    ({"controller.strategy": "s9"}, "controller.strategy", "'s9'", "must be one of conventional, s1"),
    ({"controller.delay_compensation": "true"}, "controller.delay_compensation", "'true'", "true or false"),
    ({"target.name": "stm32f4"}, "target.name", "'stm32f4'", "host, stm32h743, tms320f28377"),
    ({"motor.rs_ohmm": 0.1}, "motor.rs_ohmm", "0.1", "did you mean 'rs_ohm'"),
    ({"controller.dt_s": 0.0}, "controller.dt_s", "0.0", "[1e-06, 0.001]"),
])
def test_overrides_are_validated(overrides: dict, field: str, value: str, allowed: str) -> None:
    with pytest.raises(ConfigError) as exc:
        load_config(SPMSM, overrides)
    assert_message(exc.value, SPMSM, field, value, allowed)
    assert "set by override" in str(exc.value)


@pytest.mark.parametrize(("text", "expected"), [
    ("controller.strategy=s2", ("controller.strategy", "s2")),
    ("controller.strategy = \"s3\"", ("controller.strategy", "s3")),
    ("controller.delay_compensation=true", ("controller.delay_compensation", True)),
    ("controller.dt_s=5e-5", ("controller.dt_s", 5e-5)),
    ("motor.pole_pairs=4", ("motor.pole_pairs", 4)),
    ("scenario.load_nm=[[0, 1.5]]", ("scenario.load_nm", [[0, 1.5]])),
    ("target.name=stm32h743", ("target.name", "stm32h743")),
    ("meta.name=a = b", ("meta.name", "a = b")),
])
def test_parse_override(text: str, expected: tuple[str, object]) -> None:
    assert parse_override(text) == expected


@pytest.mark.parametrize("text", ["controller.strategy", "strategy=s2", "=s2", ".x=1", "a..b=1"])
def test_parse_override_rejects_malformed(text: str) -> None:
    with pytest.raises(ConfigError) as exc:
        parse_override(text)
    assert_message(exc.value, "(command line)", "--set", repr(text), "section.field=value")


def test_parse_override_feeds_load_config() -> None:
    m = load_config(SPMSM, dict(map(parse_override, ["controller.strategy=s1", "controller.dt_s=1e-4"])))
    assert (m.controller.strategy, m.controller.dt_s) == ("s1", 1e-4)


# --------------------------------------------------------------------------
# the model is frozen and hashable in content


def test_model_is_frozen() -> None:
    m = load_config(SPMSM)
    with pytest.raises(dataclasses.FrozenInstanceError):
        m.name = "x"  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        m.motor.ld_h = 1.0  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        m.controller.derivation.coverage = 0.5  # type: ignore[misc]


def test_config_hash_is_stable_and_content_based(tmp_path: Path) -> None:
    h = load_config(SPMSM).config_hash()
    assert h == load_config(SPMSM).config_hash()
    assert len(h) == 16 and int(h, 16) >= 0
    copy = tmp_path / "copy.toml"
    copy.write_text(SPMSM.read_text())
    assert load_config(copy).config_hash() == h  # source path does not matter
    assert load_config(SPMSM, {"motor.ld_h": 8.6e-3, "motor.lq_h": 8.6e-3}).config_hash() != h
    assert load_config(SPMSM, {"controller.strategy": "s1"}).config_hash() != h


# --------------------------------------------------------------------------
# invalid configs: (id, base example, edits, field, value repr, allowed fragment)

LONG_PREFIX = "p" * 25

INVALID = [
    ("missing-field", SPMSM, {"motor.rs_ohm": DELETE}, "motor.rs_ohm", "<missing>", "required field missing"),
    ("missing-section", SPMSM, {"speed_loop": DELETE}, "speed_loop", "<missing>", "required section [speed_loop]"),
    ("missing-meta-name", SPMSM, {"meta.name": DELETE}, "meta.name", "<missing>", "fields: name, prefix"),
    ("unknown-field", SPMSM, {"motor.rs_ohmm": 0.2}, "motor.rs_ohmm", "0.2", "allowed fields: rs_ohm, ld_h"),
    ("unknown-derivation-field", SPMSM, {"controller.derivation.cover": 0.9},
     "controller.derivation.cover", "0.9", "did you mean 'coverage'"),
    ("unknown-section", SPMSM, {"motors": {"x": 1}}, "motors", "{'x': 1}", "allowed sections: meta, motor"),
    ("section-not-table", SPMSM, {"speed_loop": 5}, "speed_loop", "5", "must be a table"),
    ("string-for-number", SPMSM, {"motor.rs_ohm": "0.2"}, "motor.rs_ohm", "'0.2'", "must be a number in (0, 100]"),
    ("bool-as-number", SPMSM, {"motor.j_kgm2": True}, "motor.j_kgm2", "True", "not a boolean"),
    ("bool-as-integer", SPMSM, {"motor.pole_pairs": True}, "motor.pole_pairs", "True", "integer in [1, 64]"),
    ("float-for-integer", SPMSM, {"motor.pole_pairs": 4.0}, "motor.pole_pairs", "4.0", "integer in [1, 64]"),
    ("string-for-bool", SPMSM, {"controller.delay_compensation": "no"},
     "controller.delay_compensation", "'no'", "true or false"),
    ("number-for-string", SPMSM, {"controller.strategy": 3}, "controller.strategy", "3", "must be a string"),
    ("non-finite", SPMSM, {"motor.psi_f_wb": math.inf}, "motor.psi_f_wb", "inf", "finite number in (0, 10]"),
    ("nan", SPMSM, {"speed_loop.kp": math.nan}, "speed_loop.kp", "nan", "finite number in [0, 1e+06]"),
    ("rs-zero", SPMSM, {"motor.rs_ohm": 0.0}, "motor.rs_ohm", "0.0", "(0, 100]"),
    ("rs-too-large", SPMSM, {"motor.rs_ohm": 150.0}, "motor.rs_ohm", "150.0", "(0, 100]"),
    ("ld-negative", SPMSM, {"motor.ld_h": -8.5e-3, "motor.lq_h": -8.5e-3}, "motor.ld_h", "-0.0085", "(0, 1]"),
    ("pole-pairs-zero", SPMSM, {"motor.pole_pairs": 0}, "motor.pole_pairs", "0", "[1, 64]"),
    ("pole-pairs-large", SPMSM, {"motor.pole_pairs": 65}, "motor.pole_pairs", "65", "[1, 64]"),
    ("b-negative", SPMSM, {"motor.b_nms": -0.1}, "motor.b_nms", "-0.1", "[0, 1000]"),
    ("dt-too-long", SPMSM, {"controller.dt_s": 5e-3}, "controller.dt_s", "0.005", "[1e-06, 0.001]"),
    ("dt-too-short", SPMSM, {"controller.dt_s": 1e-7}, "controller.dt_s", "1e-07", "[1e-06, 0.001]"),
    ("eps-at-rated", SPMSM, {"controller.eps_t_nm": 12.0},
     "controller.eps_t_nm", "12.0", "[0, motor.rated_torque_nm = 12)"),
    ("coverage-above-1", SPMSM, {"controller.derivation.coverage": 1.5},
     "controller.derivation.coverage", "1.5", "(0, 1]"),
    ("max-active-7", SPMSM, {"controller.derivation.max_active": 7},
     "controller.derivation.max_active", "7", "[1, 6]"),
    ("lambda-vo-negative", TLEVEL, {"controller.lambda_vo_nm_per_v": -1.0},
     "controller.lambda_vo_nm_per_v", "-1.0", "[0, 1000]"),
    ("limit-negative", SPMSM, {"speed_loop.limit_nm": -1.0}, "speed_loop.limit_nm", "-1.0", "(0, 1e+06]"),
    ("duration-zero", SPMSM, {"scenario.duration_s": 0.0}, "scenario.duration_s", "0.0",
     "a run shorter than 10 control periods has no metrics: must be in [10*dt_s = 0.0005, 100]"),
    ("duration-below-ten-periods", SPMSM, {"scenario.duration_s": 1e-5}, "scenario.duration_s", "1e-05",
     "[10*dt_s = 0.0005, 100] (controller.dt_s = 5e-05)"),
    ("udc-min-above-udc", SPMSM, {"inverter.udc_min_v": 400.0},
     "inverter.udc_min_v", "400.0", "(0, inverter.udc_v = 312)"),
    ("udc-max-below-udc", SPMSM, {"inverter.udc_max_v": 300.0},
     "inverter.udc_max_v", "300.0", "(inverter.udc_v = 312, 20000]"),
    ("capacitance-zero", TLEVEL, {"inverter.c_f": 0.0}, "inverter.c_f", "0.0", "capacitance <= 0"),
    ("capacitance-negative", TLEVEL, {"inverter.c_f": -1e-3}, "inverter.c_f", "-0.001", "capacitance <= 0"),
    ("flux-geometry-ld-ne-lq", SPMSM, {"motor.lq_h": 9.5e-3}, "controller.predictor", "'flux-geometry'",
     'needs Ld == Lq (surface PMSM); use predictor = "dq-euler"'),
    ("flux-geometry-on-ipmsm", IPMSM, {"controller.predictor": "flux-geometry"},
     "controller.predictor", "'flux-geometry'", "motor.ld_h = 0.0033, motor.lq_h = 0.0073"),
    ("unknown-strategy", SPMSM, {"controller.strategy": "foo"}, "controller.strategy", "'foo'",
     "must be one of conventional, s1, s2, s3"),
    ("two-level-strategy-on-t-type", TLEVEL, {"controller.strategy": "conventional"}, "controller.strategy",
     "'conventional'", "belongs to inverter.topology = 'two-level', but inverter.topology = 't-type'; "
     "allowed for 't-type': mpdtc27, mpdtc63"),
    ("t-type-strategy-on-two-level", SPMSM, {"controller.strategy": "mpdtc27"}, "controller.strategy",
     "'mpdtc27'", "belongs to inverter.topology = 't-type', but inverter.topology = 'two-level'"),
    ("two-level-fields-on-t-type", SPMSM, {"inverter.topology": "t-type"}, "controller.predictor",
     "'flux-geometry'", "belongs to inverter.topology = 'two-level'; a 't-type' config has no such field"),
    ("t-type-on-ipmsm", TLEVEL, {"motor.lq_h": 7.3e-3}, "controller.strategy", "'mpdtc63'", "needs Ld == Lq"),
    ("c-f-on-two-level", SPMSM, {"inverter.c_f": 1e-3}, "inverter.c_f", "0.001",
     "belongs to inverter.topology = 't-type'; a 'two-level' config has no such field: remove it"),
    ("plant-c-f-on-two-level", SPMSM, {"plant.c_f": 1e-3}, "plant.c_f", "0.001",
     "belongs to inverter.topology = 't-type'"),
    ("lambda-on-two-level", SPMSM, {"controller.lambda_psi_nm_per_wb": 10.0}, "controller.lambda_psi_nm_per_wb",
     "10.0", "belongs to inverter.topology = 't-type'"),
    ("eps-t-on-t-type", TLEVEL, {"controller.eps_t_nm": 0.5}, "controller.eps_t_nm", "0.5",
     "belongs to inverter.topology = 'two-level'; a 't-type' config has no such field"),
    ("tables-on-t-type", TLEVEL, {"controller.tables": "published"}, "controller.tables", "'published'",
     "belongs to inverter.topology = 'two-level'"),
    ("derivation-on-t-type", TLEVEL, {"controller.derivation.coverage": 0.5}, "controller.derivation",
     "{'coverage': 0.5}", "belongs to inverter.topology = 'two-level'"),
    ("no-delay-compensation-on-t-type", TLEVEL, {"controller.delay_compensation": False},
     "controller.delay_compensation", "False", "set plant.actuation_delay_periods); allowed: true"),
    ("table5-set-on-two-level", SPMSM, {"scenario.set": "mpdtc-table5"}, "scenario.set", "'mpdtc-table5'",
     "belongs to inverter.topology = 't-type', but inverter.topology = 'two-level'; allowed for 'two-level': config"),
    ("eps-t-missing-on-two-level", SPMSM, {"controller.eps_t_nm": DELETE}, "controller.eps_t_nm", "<missing>",
     "required field missing in [controller]"),
    ("unknown-topology", SPMSM, {"inverter.topology": "three-level"},
     "inverter.topology", "'three-level'", "two-level, t-type"),
    ("unknown-predictor", SPMSM, {"controller.predictor": "rk4"}, "controller.predictor", "'rk4'",
     "flux-geometry, dq-euler"),
    ("unknown-tables", SPMSM, {"controller.tables": "paper"}, "controller.tables", "'paper'", "derived, published"),
    ("unknown-speed-mode", SPMSM, {"scenario.speed_mode": "held"}, "scenario.speed_mode", "'held'",
     "mechanical, imposed"),
    ("unknown-target", SPMSM, {"target.name": "stm32f407"}, "target.name", "'stm32f407'",
     "host, stm32h743, tms320f28377"),
    ("t-n-min-above-ts-3", TLEVEL, {"controller.t_n_min_s": 2e-5}, "controller.t_n_min_s", "2e-05",
     "clamp minimum above Ts/3: must be in [0, Ts/3 = 1.66667e-05] (controller.dt_s = 5e-05)"),
    ("unknown-number-format", SPMSM, {"controller.number_format": "fixed-q15"}, "controller.number_format",
     "'fixed-q15'", "must be one of float32, fixed"),
    ("psi-ref-on-t-type", TLEVEL, {"controller.psi_ref": "mtpa"}, "controller.psi_ref", "'mtpa'",
     "belongs to inverter.topology = 'two-level'"),
    ("cost-on-t-type", TLEVEL, {"controller.cost": "reference"}, "controller.cost", "'reference'",
     "belongs to inverter.topology = 'two-level'"),
    ("fixed-q-too-small", SPMSM, {"controller.fixed_q": 4}, "controller.fixed_q", "4", "must be an integer in [8, 30]"),
    ("prefix-uppercase", SPMSM, {"meta.prefix": "Spmsm"}, "meta.prefix", "'Spmsm'", "^[a-z][a-z0-9_]{0,23}$"),
    ("prefix-digit-first", SPMSM, {"meta.prefix": "1spmsm"}, "meta.prefix", "'1spmsm'", "C identifier"),
    ("prefix-too-long", SPMSM, {"meta.prefix": LONG_PREFIX}, "meta.prefix", repr(LONG_PREFIX), "{0,23}"),
    ("prefix-keyword", SPMSM, {"meta.prefix": "int"}, "meta.prefix", "'int'", "is a C keyword"),
    ("prefix-hyphen", SPMSM, {"meta.prefix": "my-motor"}, "meta.prefix", "'my-motor'", "C identifier"),
    ("empty-name", SPMSM, {"meta.name": ""}, "meta.name", "''", "non-empty string"),
    ("times-not-increasing", SPMSM, {"scenario.load_nm": [[0.0, 10.0], [3.0, -10.0], [1.0, 10.0]]},
     "scenario.load_nm[2]", "[1.0, 10.0]", "strictly increasing: 1 <= previous time 3"),
    ("times-repeated", SPMSM, {"scenario.speed_ref_rpm": [[0.0, 500.0], [0.0, 100.0]]},
     "scenario.speed_ref_rpm[1]", "[0.0, 100.0]", "strictly increasing"),
    ("first-time-not-zero", SPMSM, {"scenario.speed_ref_rpm": [[0.5, 500.0]]},
     "scenario.speed_ref_rpm[0]", "[0.5, 500.0]", "first time must be exactly 0"),
    ("time-after-duration", SPMSM, {"scenario.load_nm": [[0.0, 10.0], [4.0, 0.0]]},
     "scenario.load_nm[1]", "[4.0, 0.0]", "< scenario.duration_s = 4"),
    ("steps-empty", SPMSM, {"scenario.load_nm": []}, "scenario.load_nm", "[]", "non-empty list of [time_s, value]"),
    ("steps-not-pairs", SPMSM, {"scenario.load_nm": [[0.0, 1.0, 2.0]]},
     "scenario.load_nm[0]", "[0.0, 1.0, 2.0]", "[time_s, value] pair"),
    ("steps-bool-value", SPMSM, {"scenario.load_nm": [[0.0, True]]},
     "scenario.load_nm[0]", "[0.0, True]", "pair of numbers"),
    ("steps-not-finite", SPMSM, {"scenario.load_nm": [[0.0, math.inf]]},
     "scenario.load_nm[0]", "[0.0, inf]", "finite"),
    ("speed-above-10x-rated", SPMSM, {"scenario.speed_ref_rpm": [[0.0, 9000.0]]},
     "scenario.speed_ref_rpm[0]", "[0.0, 9000.0]", "[-10*rated = -7500, 10*rated = 7500]"),
]


@pytest.mark.parametrize(("base", "edits", "field", "value", "allowed"),
                         [case[1:] for case in INVALID], ids=[case[0] for case in INVALID])
def test_invalid_config(tmp_path: Path, base: Path, edits: dict, field: str, value: str, allowed: str) -> None:
    path = write_config(tmp_path, edits, base)
    with pytest.raises(ConfigError) as exc:
        load_config(path)
    assert_message(exc.value, path, field, value, allowed)
    assert (exc.value.file, exc.value.field) == (str(path), field)


def _not_toml(tmp_path: Path) -> Path:
    path = tmp_path / "broken.toml"
    path.write_text('[meta]\nname = "x"\nprefix = = "x"\n')
    return path


def _binary(tmp_path: Path) -> Path:
    path = tmp_path / "binary.toml"
    path.write_bytes(b"\xff\xfe\x00garbage")
    return path


def _missing(tmp_path: Path) -> Path:
    return tmp_path / "nonexistent.toml"


def _directory(tmp_path: Path) -> Path:
    path = tmp_path / "adir.toml"
    path.mkdir()
    return path


def _bom(tmp_path: Path) -> Path:
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + SPMSM.read_bytes())
    return path


def _unicode_minus(tmp_path: Path) -> Path:
    path = tmp_path / "minus.toml"
    path.write_text('[meta]\nname = "x"\n[motor]\nb_nms = \u22121.0\n', encoding="utf-8")
    return path


@pytest.mark.parametrize(("make", "value", "allowed"), [
    (_not_toml, "'prefix = = \"x\"'", "not TOML: Invalid value (at line 3, column 10)"),
    (_binary, "<binary data>", "not UTF-8"),
    (_missing, "nonexistent.toml", "file not found"),
    (_directory, "adir.toml", "is a directory"),
    (_bom, "<byte-order mark>", "starts with a UTF-8 byte-order mark (BOM)"),
    (_unicode_minus, "'b_nms = \u22121.0'", "line 4 column 9 is U+2212 MINUS SIGN, not the ASCII '-' it looks like"),
], ids=["not-toml", "binary", "missing-file", "directory", "bom", "unicode-minus"])
def test_invalid_file(tmp_path: Path, make, value: str, allowed: str) -> None:
    path = make(tmp_path)
    with pytest.raises(ConfigError) as exc:
        load_config(path)
    assert_message(exc.value, path, "(file)", value, allowed)


def test_config_error_is_user_facing_error() -> None:
    err = ConfigError("x.toml", "controller.strategy", "foo", "must be one of conventional, s1, s2, s3")
    assert isinstance(err, MpcgenError)
    assert str(err) == "x.toml: controller.strategy = 'foo': must be one of conventional, s1, s2, s3"
    assert (err.file, err.field, err.value, err.allowed) == (
        "x.toml", "controller.strategy", "foo", "must be one of conventional, s1, s2, s3")
