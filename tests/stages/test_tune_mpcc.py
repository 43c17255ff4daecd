"""`mpcgen tune --weight controller.lambda_u`: the long-horizon switching weight of both topologies.

Its default range is the weights' (the config's value / 10^1.5 .. x 10^1.5, log scale), the default
objectives add the switching frequency (a switching weight trades ripple for switching), a config whose
strategy does not read it is refused in one line, and a short tune of each example recommends an
admissible value with the same outputs as any tune.
"""
from __future__ import annotations

import json

import pytest

from codegen.cli import main
from codegen.config import load_config
from codegen.errors import UsageError
from codegen.stages import tune

from conftest import EXAMPLES, SPMSM, TTYPE

MPCC_SPMSM, MPCC_TTYPE = EXAMPLES / "mpcc_spmsm.toml", EXAMPLES / "mpcc_tlevel.toml"


@pytest.mark.parametrize("config", [MPCC_SPMSM, MPCC_TTYPE], ids=["two-level", "t-type"])
def test_lambda_u_range_and_objectives(config):
    model = load_config(config)
    a = tune.parse_axis("--weight", "controller.lambda_u", model)
    lam = model.controller.lambda_u
    assert (a.role, a.log, a.nominal) == ("weight", True, lam)
    assert a.lo == pytest.approx(lam / 10 ** 1.5, rel=1e-5) and a.hi == pytest.approx(lam * 10 ** 1.5, rel=1e-5)
    keys = [f.key for f in tune.parse_objectives(None, [a.field])]
    assert keys == [*tune.DEFAULT_OBJECTIVES, "f_ave_hz"]
    assert [f.key for f in tune.parse_objectives(None, ["controller.lambda_psi_nm_per_wb"])] == \
        list(tune.DEFAULT_OBJECTIVES)
    with pytest.raises(UsageError, match="outside the allowed range"):
        tune.parse_axis("--weight", "controller.lambda_u=0:1", model)


@pytest.mark.parametrize("config", [SPMSM, TTYPE], ids=["two-level", "t-type"])
def test_lambda_u_of_a_strategy_that_does_not_read_it(config, capsys):
    with pytest.raises(UsageError, match="not read by controller.strategy = ") as exc:
        tune.parse_axis("--weight", "controller.lambda_u=0.1:1", load_config(config))
    assert "\n" not in str(exc.value)
    assert main(["tune", str(config), "-q", "--weight", "controller.lambda_u=0.1:1"]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


CASES = {
    "two-level": (MPCC_SPMSM, ["--set", "scenario.duration_s=0.5", "--set", "scenario.speed_ref_rpm=[[0.0, 500.0]]",
                               "--set", "scenario.load_nm=[[0.0, 10.0]]"]),
    "t-type": (MPCC_TTYPE, ["--set", "scenario.set=config", "--set", "scenario.duration_s=0.1"]),
}


@pytest.mark.parametrize("config,short", list(CASES.values()), ids=list(CASES))
def test_short_lambda_u_tune_recommends_an_admissible_value(tmp_path, capsys, config, short):
    out = tmp_path / "tune"
    assert main(["tune", str(config), "-q", "--serial", "--weight", "controller.lambda_u", "--grid", "3",
                 "--rounds", "1", *short, "-o", str(out)]) == 0
    assert "mpcc: recommended controller.lambda_u = " in capsys.readouterr().out
    data = json.loads((out / "tune.json").read_text())
    assert data["objectives"] == [*tune.DEFAULT_OBJECTIVES, "f_ave_hz"]
    assert data["fields"][0]["scale"] == "log" and data["fields"][0]["field"] == "controller.lambda_u"
    d = data["strategies"]["mpcc"]
    lams = [p["params"]["controller.lambda_u"] for p in d["points"]]
    lam = load_config(config).controller.lambda_u
    assert lams[:3] == [float(f"{lam / 10 ** 1.5:.6g}"), lam, float(f"{lam * 10 ** 1.5:.6g}")] and len(lams) > 3
    fave = [p["figures"]["f_ave_hz"] for p in d["points"][:3]]
    assert fave[0] > fave[2]  # a larger switching weight switches less
    rec = d["recommended"]
    assert rec is not None and rec["index"] in d["admissible_front"] and len(rec["c_hash"]) == 64
    assert rec["set_line"] == f"--set controller.lambda_u={rec['params']['controller.lambda_u']!r}"
    assert (out / "front_THD_all_f_ave.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
