"""Config refusals of the long-horizon family (docs/mpcc.md "Configuration"): one line naming the file,
the field, the value and what is allowed, exit code 2."""
from __future__ import annotations

import pytest

from codegen.cli import main
from codegen.config import family_strategies, load_config
from codegen.errors import ConfigError

from .helpers import CONFIGS, mpcc_model
from conftest import SPMSM, TTYPE


@pytest.mark.parametrize("config, overrides, field, allowed", [
    ("spmsm", {"motor.lq_h": 9e-3}, "motor.lq_h", "needs a surface PMSM"),
    ("tlevel", {"motor.lq_h": 2e-3}, "motor.lq_h", "needs a surface PMSM"),
    ("spmsm", {"controller.horizon": 0}, "controller.horizon", "[1, 6]"),
    ("tlevel", {"controller.horizon": 7}, "controller.horizon", "[1, 6]"),
    ("spmsm", {"controller.horizon": 2.5}, "controller.horizon", "integer"),
    ("spmsm", {"controller.lambda_u": 0.0}, "controller.lambda_u", "must be positive"),
    ("spmsm", {"controller.node_budget": 0}, "controller.node_budget", "[1, 65535]"),
    ("spmsm", {"controller.node_budget": 70000}, "controller.node_budget", "[1, 65535]"),
    ("spmsm", {"controller.predictor": "dq-euler"}, "controller.predictor", "ignored by controller.strategy = 'mpcc'"),
    ("spmsm", {"controller.psi_ref_wb": 0.3}, "controller.psi_ref_wb", "ignored by controller.strategy = 'mpcc'"),
    ("spmsm", {"controller.eps_t_nm": 0.6}, "controller.eps_t_nm", "ignored by"),
    ("tlevel", {"controller.lambda_psi_nm_per_wb": 10.0}, "controller.lambda_psi_nm_per_wb", "ignored by"),
    ("tlevel", {"controller.t_n_min_s": 1e-6}, "controller.t_n_min_s", "ignored by"),
    ("spmsm", {"controller.number_format": "fixed"}, "controller.number_format", "float32 only"),
    ("tlevel", {"controller.number_format": "fixed"}, "controller.number_format", "float32 only"),
    ("tlevel", {"controller.lambda_vo_a2_per_v2": -1.0}, "controller.lambda_vo_a2_per_v2", "[0, 1e+06]"),
    ("tlevel", {"controller.lambda_vo_a2_per_v2": 2e6}, "controller.lambda_vo_a2_per_v2", "[0, 1e+06]"),
    ("spmsm", {"controller.lambda_vo_a2_per_v2": 10.0}, "controller.lambda_vo_a2_per_v2",
     "a 'two-level' config has no such field"),
])
def test_refusals(config: str, overrides: dict[str, object], field: str, allowed: str):
    with pytest.raises(ConfigError) as err:
        load_config(CONFIGS[config], overrides)
    assert err.value.field == field
    text = str(err.value)
    assert allowed in text and "\n" not in text and str(CONFIGS[config]) in text


@pytest.mark.parametrize("path, field", [(SPMSM, "controller.horizon"), (SPMSM, "controller.lambda_u"),
                                         (TTYPE, "controller.node_budget"), (TTYPE, "controller.lambda_vo_a2_per_v2")])
def test_the_other_families_refuse_the_long_horizon_fields(path, field):
    value = 3 if field != "controller.lambda_u" else 1.0
    with pytest.raises(ConfigError) as err:
        load_config(path, {field: value})
    assert err.value.field == field and "ignored by controller.strategy" in str(err.value)


def test_required_fields_and_defaults(tmp_path):
    text = CONFIGS["spmsm"].read_text().replace("horizon = 3", "")
    path = tmp_path / "no_horizon.toml"
    path.write_text(text)
    with pytest.raises(ConfigError) as err:
        load_config(path)
    assert err.value.field == "controller.horizon" and "required" in str(err.value)
    m = mpcc_model("spmsm")
    assert m.controller.node_budget is None and m.controller.horizon == 3
    # an MPTC config keeps its hash: the long-horizon fields at their defaults are not in it
    assert "horizon" not in load_config(SPMSM).as_dict()["controller"]


def test_neutral_point_weight_default_and_use(tmp_path):
    """Left out, the T-type family's neutral-point weight is the model's default (and the config hashes
    as with the default written out); given, it is the constant LAMBDA_VO of the generated step."""
    from codegen.model import Controller
    from codegen.topology import topology_of

    text = CONFIGS["tlevel"].read_text()
    line = next(x for x in text.splitlines() if x.startswith("lambda_vo_a2_per_v2"))
    path = tmp_path / "no_lambda_vo.toml"
    path.write_text(text.replace(line, ""))
    default = load_config(path)
    assert default.controller.lambda_vo_a2_per_v2 == Controller.lambda_vo_a2_per_v2
    assert default.config_hash() == load_config(CONFIGS["tlevel"], {"controller.lambda_vo_a2_per_v2":
                                                                    Controller.lambda_vo_a2_per_v2}).config_hash()
    m = mpcc_model("tlevel", lambda_vo_a2_per_v2=123.5)
    assert m.config_hash() != default.config_hash()
    t = topology_of(m).derive(m)
    assert float(t.const("LAMBDA_VO")) == 123.5 and t.neutral_point
    two = mpcc_model("spmsm")
    assert not topology_of(two).derive(two).neutral_point


def test_families_of_each_topology():
    assert family_strategies("two-level", "mpcc") == ("mpcc",)
    assert family_strategies("two-level", "s2") == ("conventional", "s1", "s2", "s3")
    assert family_strategies("t-type", "mpdtc63") == ("mpdtc27", "mpdtc63")
    assert family_strategies("t-type", "mpcc") == ("mpcc",)


def test_command_line_exit_code(capsys):
    code = main(["verify", str(CONFIGS["spmsm"]), "--set", "motor.lq_h=9e-3", "--states", "1000"])
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "motor.lq_h" in err[0] and "surface PMSM" in err[0]


def test_strategies_outside_the_family_are_refused(capsys):
    code = main(["verify", str(CONFIGS["spmsm"]), "--strategies", "s1", "--states", "1000"])
    assert code == 2
    assert "family of controller.strategy = 'mpcc'" in capsys.readouterr().err
