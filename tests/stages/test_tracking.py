"""The simulator's verdict on its own run: a drive that never reaches its speed is not a normal run.

The second user trial's cases: the 400 W servo with ``motor.j_kgm2 = 0.26`` (kg*cm^2 entered as kg*m^2)
ended at 41 r/min against 3000, and with ``motor.b_nms = 1.0``; both were reported like a good run.
"""
from __future__ import annotations

import json

import pytest

from codegen.cli import main

from conftest import EXAMPLES

SERVO = EXAMPLES / "servo400w.toml"


@pytest.mark.parametrize("slip", ["motor.j_kgm2=0.26", "motor.b_nms=1.0"])
def test_a_drive_that_misses_its_speed_fails_its_verdict(tmp_path, capsys, slip):
    out = tmp_path / "sim.json"
    argv = ["simulate", str(SERVO), "--strategies", "conventional", "--set", slip, "--json", str(out), "-q"]
    assert main(argv) == 0  # the results are written either way
    err = capsys.readouterr()
    assert "tracking FAILED: conventional: speed" in err.out  # in the table
    assert "warning: tracking failed: conventional: speed" in err.err  # on stderr
    assert f"mpcgen: warning: {SERVO}: {slip.split('=')[0]} = " in err.err  # and at load
    data = json.loads(out.read_text())
    verdict = data["strategies"]["conventional"]
    assert verdict["tracking"] == "failed" and data["tracking_failed"] == ["conventional"]
    assert any("against a reference of 3000.0 r/min" in r for r in verdict["tracking_reasons"])
    assert main([*argv, "--strict"]) == 1


def test_a_good_run_passes_its_verdict_and_strict_exits_0(tmp_path, capsys):
    out = tmp_path / "sim.json"
    assert main(["simulate", str(SERVO), "--strategies", "conventional,s1", "--json", str(out), "--strict",
                 "-q"]) == 0
    assert "tracking: ok" in capsys.readouterr().out
    data = json.loads(out.read_text())
    assert data["tracking_failed"] == []
    assert {s["tracking"] for s in data["strategies"].values()} == {"ok"}
