"""A user's own motor, safely: operating-point checks at load time, names that reach C, CLI values.

The motor is a 400 W servo (Rs 0.9 ohm, Ld = Lq 3.2 mH, psi_f 0.036 Wb,
4 pole pairs, 3000 r/min, 1.27 N*m, Udc 310 V, dt 25 us): each case breaks one
thing and must be refused (exit 2, one line naming file, field and value)
or warned about, before any long run.
"""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from codegen.cli import main
from codegen.config import load_config
from codegen.errors import ConfigError

from conftest import SPMSM

SERVO = {
    "meta.name": "servo 400 W", "meta.prefix": "servo",
    "motor.rs_ohm": 0.9, "motor.ld_h": 3.2e-3, "motor.lq_h": 3.2e-3, "motor.psi_f_wb": 0.036,
    "motor.pole_pairs": 4, "motor.rated_speed_rpm": 3000.0, "motor.rated_torque_nm": 1.27,
    "motor.j_kgm2": 5e-5, "inverter.udc_v": 310.0, "inverter.udc_min_v": 200.0, "inverter.udc_max_v": 400.0,
    "inverter.i_trip_a": 20.0, "controller.dt_s": 25e-6, "controller.psi_ref_wb": 0.036,
    "controller.eps_t_nm": 0.1, "controller.tables": "published", "speed_loop.kp": 0.05, "speed_loop.ki": 2.0,
    "speed_loop.limit_nm": 3.0, "scenario.speed_ref_rpm": [[0.0, 1000.0]], "scenario.load_nm": [[0.0, 0.5]],
    "scenario.duration_s": 0.5,
}


def servo(**changes: object):
    return load_config(SPMSM, {**SERVO, **{k.replace("__", "."): v for k, v in changes.items()}})


def test_servo_loads_clean():
    assert servo().warnings == ()


@pytest.mark.parametrize("change,field", [
    ({"inverter__i_trip_a": 3.0}, "inverter.i_trip_a"),              # below the rated current 5.9 A
    ({"inverter__udc_v": 48.0, "inverter__udc_min_v": 40.0, "inverter__udc_max_v": 60.0}, "inverter.udc_v"),
    ({"controller__psi_ref_wb": 0.5}, "controller.psi_ref_wb"),       # 628 V at rated speed
])
def test_operating_point_errors(change, field):
    with pytest.raises(ConfigError) as err:
        servo(**change)
    assert err.value.field == field and "\n" not in str(err.value)


def test_operating_point_warnings(capsys, tmp_path):
    m = servo(speed_loop__limit_nm=5.0)  # 23 A > i_trip 20 A
    assert len(m.warnings) == 1 and "speed_loop.limit_nm" in m.warnings[0] and "trip" in m.warnings[0]
    m = servo(inverter__udc_v=180.0, inverter__udc_min_v=100.0)  # 45 V back-EMF: 104 V linear, 115 V six-step
    assert m.warnings == () or "inverter.udc_v" in m.warnings[0]
    sets = [f"--set={k}={json.dumps(v)}" for k, v in SERVO.items()] + ["--set=speed_loop.limit_nm=5.0"]
    assert main(["generate", str(SPMSM), *sets, "-o", str(tmp_path / "c"), "-q"]) == 0
    assert "mpcgen: warning:" in capsys.readouterr().err


@pytest.mark.parametrize("name", ["servo */ 400w", "a /* b", "back\\slash", "two\nlines", "x" * 81, "ümlaut"])
def test_names_that_would_break_generated_c_are_refused(name):
    with pytest.raises(ConfigError) as err:
        servo(meta__name=name)
    assert err.value.field == "meta.name"


def _one_line_exit_2(capsys, args: list[str], *words: str) -> None:
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "Traceback" not in err[0], err
    for w in words:
        assert w in err[0], (w, err[0])


@pytest.mark.parametrize("args,words", [
    (["verify", "{cfg}", "--strategies", ""], ["--strategies"]),
    (["verify", "{cfg}", "--strategies", " , "], ["--strategies"]),
    (["bench", "{cfg}", "--repeats", "0"], ["--repeats"]),
    (["bench", "{cfg}", "--repeats", "-3"], ["--repeats"]),
    (["simulate", "{cfg}", "--sweep-eps", "0.1:0.5:0"], ["--sweep-eps", "STEP > 0"]),
    (["simulate", "{cfg}", "--sweep-eps", "0.5:0.1:0.1"], ["--sweep-eps"]),
    (["simulate", "{cfg}", "--sweep-eps", "0.5,12"], ["--sweep-eps", "rated_torque_nm"]),
    (["simulate", "{cfg}", "--sweep-eps", "0.1:1000:0.0001"], ["--sweep-eps", "at most"]),
    (["generate", "{cfg}", "-o", "{file}"], ["-o", "not a folder"]),
    (["generate", "{cfg}", "-o", "/proc/x"], ["-o", "/proc/x"]),
    (["firmware", "{cfg}", "--board", "host", "-o", "/proc/fw"], ["-o", "/proc/fw"]),
    (["simulate", "{cfg}", "--plots", "{file}"], ["--plots"]),
    (["verify", "{cfg}", "--json", "{dir}"], ["--json", "folder"]),
    (["bench", "{cfg}", "--json", "/proc/x.json"], ["--json"]),
    (["tables", "{cfg}", "--derive", "-o", "{dir}"], ["-o", "folder"]),
])
def test_bad_command_line_values(capsys, tmp_path: Path, args, words):
    f = tmp_path / "a_file"
    f.write_text("x")
    subs = {"{cfg}": str(SPMSM), "{file}": str(f), "{dir}": str(tmp_path)}
    _one_line_exit_2(capsys, [subs.get(a, a) for a in args] + ["-q"], *words)


def test_verify_runs_exactly_the_states_asked_for(tmp_path):
    out = tmp_path / "v.json"
    assert main(["verify", str(SPMSM), "--states", "1", "--strategies", "s1", "--json", str(out), "-q"]) == 0
    r = json.loads(out.read_text())["strategies"]["s1"]
    assert r["states"] == 1 and r["mismatches"] == 0
    assert main(["verify", str(SPMSM), "--states", "5000", "--strategies", "conventional", "--json", str(out),
                 "-q"]) == 0
    r = json.loads(out.read_text())["strategies"]["conventional"]
    assert r["states"] == 5000 and sum(r["sources"].values()) == 5000 and r["sources"]["closed_loop"] == 400


SERVO_EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "servo400w.toml"


@pytest.mark.parametrize("field,value,fragments", [
    ("motor.j_kgm2", 0.26, ("mechanical time constant", "64.32 s", "kg*cm^2 entered as kg*m^2?")),
    ("motor.b_nms", 1.0, ("of the rated torque at rated speed", "N*m*s/rad")),
    ("motor.rated_speed_rpm", 314.16, ("back-EMF at rated speed of only", "rad/s entered as r/min?")),
    ("scenario.speed_ref_rpm", [[0.0, 20000.0]], ("above the step's speed guard", "5 x rated = 1.5e+04 r/min")),
    ("motor.ld_h", 2e-5, ("electrical time constant", "less than 2 control periods")),
])
def test_unit_slips_warn_at_load_naming_the_field(field, value, fragments):
    """The unit slips of the second user trial: each a warning at load naming the field and the likely slip."""
    overrides: dict[str, object] = {field: value}
    if field == "motor.ld_h":
        overrides["motor.lq_h"] = value
    warnings = load_config(SERVO_EXAMPLE, overrides).warnings
    mine = [w for w in warnings if f": {field} = " in w]
    assert len(mine) == 1, warnings
    for f in fragments:
        assert f in mine[0], mine[0]


def test_examples_have_no_plausibility_warning():
    for name in ("seed001_spmsm", "seed001_ipmsm", "servo400w", "seed000_tlevel"):
        assert load_config(SERVO_EXAMPLE.parent / f"{name}.toml").warnings == (), name


def _warnings_on(model, field: str) -> list[str]:
    return [w for w in model.warnings if f": {field} = " in w]


def test_salient_motor_with_constant_flux_reference_warns():
    """An IPMSM (Ld != Lq) with the constant psi* gets advice to use the MTPA reference; a surface
    motor with the same constant reference (the SPMSM and servo examples) gets none."""
    ipmsm = SERVO_EXAMPLE.parent / "seed001_ipmsm.toml"
    mine = _warnings_on(load_config(ipmsm, {"controller.psi_ref": "constant"}), "controller.psi_ref")
    assert len(mine) == 1, mine
    for fragment in ("'constant'", "salient", "motor.ld_h = 0.0033 H", "motor.lq_h = 0.0073 H",
                     'controller.psi_ref = "mtpa"'):
        assert fragment in mine[0], (fragment, mine[0])
    assert load_config(ipmsm).warnings == ()  # the example itself uses psi_ref = "mtpa"
    assert load_config(SPMSM).controller.psi_ref == "constant"
    assert load_config(SPMSM).warnings == () and load_config(SERVO_EXAMPLE).warnings == ()


def test_salient_motor_warning_reaches_the_command_line(capsys, tmp_path):
    ipmsm = SERVO_EXAMPLE.parent / "seed001_ipmsm.toml"
    assert main(["generate", str(ipmsm), "--set", "controller.psi_ref=constant", "-o", str(tmp_path), "-q"]) == 0
    err = capsys.readouterr().err
    assert "mpcgen: warning:" in err and "controller.psi_ref = 'constant'" in err


def test_scenario_above_rated_speed_warns_naming_the_field():
    """A profile above motor.rated_speed_rpm (below the speed guard) is warned about on
    scenario.speed_ref_rpm; at rated speed it is not; above the guard only the guard's warning."""
    mine = _warnings_on(load_config(SERVO_EXAMPLE, {"scenario.speed_ref_rpm": [[0.0, 3000.0], [0.3, -3600.0]]}),
                        "scenario.speed_ref_rpm")
    assert len(mine) == 1, mine
    for fragment in ("runs the motor at 3600 r/min", "above motor.rated_speed_rpm = 3000 r/min",
                     "back-EMF at 3600 r/min: 54.29 V", "Udc/sqrt(3) = 179 V"):
        assert fragment in mine[0], (fragment, mine[0])
    assert load_config(SERVO_EXAMPLE, {"scenario.speed_ref_rpm": [[0.0, 3000.0]]}).warnings == ()
    guard = _warnings_on(load_config(SERVO_EXAMPLE, {"scenario.speed_ref_rpm": [[0.0, 20000.0]]}),
                         "scenario.speed_ref_rpm")
    assert len(guard) == 1 and "speed guard" in guard[0]


def test_table5_set_above_rated_speed_warns_naming_the_set():
    """The T-type's Table 5 set runs 300/1800/3000 r/min whatever the motor: on a 2000 r/min motor
    the warning names scenario.set; the config's own profile below rated speed gives none."""
    tlevel = SERVO_EXAMPLE.parent / "seed000_tlevel.toml"
    m = load_config(tlevel, {"motor.rated_speed_rpm": 2000.0})
    assert m.scenario.set == "mpdtc-table5"
    mine = _warnings_on(m, "scenario.set")
    assert len(mine) == 1 and len(m.warnings) == 1, m.warnings
    for fragment in ("'mpdtc-table5'", "Table 5 set (steady runs at 300, 1800 and 3000 r/min)",
                     "above motor.rated_speed_rpm = 2000 r/min"):
        assert fragment in mine[0], (fragment, mine[0])
    own = load_config(tlevel, {"motor.rated_speed_rpm": 2000.0, "scenario.set": "config",
                               "scenario.speed_ref_rpm": [[0.0, 1500.0]]})
    assert own.warnings == ()
    assert load_config(tlevel).warnings == ()  # rated 3000 r/min: the set stays within it
