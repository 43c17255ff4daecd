"""Mode ``closed-loop``: the host's plant, the board's decisions; the same run as ``mpcgen simulate``.

On the virtual board the decision sequence (and the whole trace) over 4 000
periods equals the simulator's bit for bit, for a two-level strategy with the
published tables and a three-level one; the metrics are ``simulate``'s.  A
board that decides differently is caught at the period where it does.
"""
from __future__ import annotations

import json

import numpy as np
import pytest
from hil_support import ROOT, SPMSM, TLEVEL, run_mode

from codegen.config import load_config
from codegen.model import Model
from codegen.results import clean_json
from codegen.stages.training import with_trained_tables
from codegen.topology import topology_of
from hil.cli import main
from hil.closedloop import closed_loop, trace_differences
from hil.messages import BoardInfo
from hil.schema import Schema
from hil.session import RunResult, RunStats

#: 4 000 periods of 50 us, both speed and load steps inside (two-level)
SHORT_2L = {"scenario.duration_s": 0.2, "scenario.speed_ref_rpm": [[0.0, 500.0], [0.1, -500.0]],
            "scenario.load_nm": [[0.0, 10.0], [0.05, -10.0]], "controller.tables": "published"}
SHORT_2L_ARGS = ["--set", "scenario.duration_s=0.2", "--set", "scenario.speed_ref_rpm=[[0.0,500.0],[0.1,-500.0]]",
                 "--set", "scenario.load_nm=[[0.0,10.0],[0.05,-10.0]]", "--set", "controller.tables=published"]
FIXED = {"controller.number_format": "fixed"}
#: the long-horizon examples (their own family: no MPTC table field), the two-level one shortened like SHORT_2L
MPCC_SPMSM, MPCC_TLEVEL = ROOT / "examples" / "mpcc_spmsm.toml", ROOT / "examples" / "mpcc_tlevel.toml"
SHORT_MPCC = {k: v for k, v in SHORT_2L.items() if k != "controller.tables"}
CASES = [(SPMSM, "s2", SHORT_2L), (SPMSM, "s3", SHORT_2L), (TLEVEL, "mpdtc63", {}), (TLEVEL, "mpdtc27", {}),
         (SPMSM, "s2", {**SHORT_2L, **FIXED}), (TLEVEL, "mpdtc27", FIXED),
         (MPCC_SPMSM, "mpcc", SHORT_MPCC), (MPCC_TLEVEL, "mpcc", {})]
IDS = [f"{c.stem}-{s}" + ("-fixed" if o.get("controller.number_format") == "fixed" else "") for c, s, o in CASES]


def model_of(config, strategy: str, overrides: dict) -> tuple[Model, object]:
    m = with_trained_tables(load_config(config, {"controller.strategy": strategy, **overrides}), [strategy])
    return m, topology_of(m).derive(m)


def simulate(m: Model, t: object):
    """``mpcgen simulate``'s run of the scenario (the compiled closed loop)."""
    topo = topology_of(m)
    return topo.closed_loop_trace(m, topo.host_library(m, t, with_sim=True))


@pytest.mark.board
@pytest.mark.parametrize("config,strategy,overrides", CASES, ids=IDS)
def test_closed_loop_equals_simulate(board, config, strategy, overrides):
    m, t = model_of(config, strategy, overrides)
    data = run_mode(board, closed_loop, m, t)
    ref = simulate(m, t)
    topo = topology_of(m)
    assert data["periods"] == data["periods_done"] == ref.n >= 4000
    assert data["lost_at"] is None and data["ok"]
    # the decision sequence, period by period, as the board gave it == mpcgen simulate's
    assert data["decision_field"] == topo.decision_field
    assert data["decisions"] == getattr(ref, topo.decision_field).astype(int).tolist()
    assert data["identical_to_simulate"] and data["differing_trace_fields"] == []
    assert len(set(data["decisions"])) > 3  # the run switches
    # simulate's metrics of the same trace
    assert data["metrics"] == clean_json(topo.trace_metrics(ref, m))
    assert data["cycles_min"] is not None and data["wire"]["resent_states"] == 0


class _WrongBoard:
    """A session whose 'board' is the compiled step, except one period's decision is changed."""

    def __init__(self, m: Model, t: object, bad_period: int) -> None:
        self.schema = Schema.of(m)
        self.lib = topology_of(m).host_library(m, t, with_sim=True)
        self.info = BoardInfo(1, self.schema.schema_hash, self.schema.config_hash, 0, 0, 32, 1024, "fake", "float32",
                              "ns")
        self.k, self.bad = 0, bad_period
        self.field = topology_of(m).decision_field

    def run(self, rec: np.ndarray) -> RunResult:
        out = self.lib.step_batch(rec)
        if self.k == self.bad:
            out[self.field] = (int(out[self.field][0]) + 1) % 7
        self.k += 1
        payload = np.frombuffer(b"\x07\x00\x00\x00" + self.schema.output.pack(out).tobytes(), np.uint8)
        return RunResult(payload.reshape(1, -1).copy(), np.ones(1, bool), RunStats(), 0.0, 0, 0)


def test_a_different_decision_is_caught_where_it_happens():
    m, t = model_of(SPMSM, "s2", {**SHORT_2L, "scenario.duration_s": 0.11,
                                   "scenario.speed_ref_rpm": [[0.0, 500.0]], "scenario.load_nm": [[0.0, 10.0]]})
    data = closed_loop(_WrongBoard(m, t, 300), m, t, show_progress=False)  # type: ignore[arg-type]
    assert not data["ok"] and not data["decisions_equal_simulate"] and not data["identical_to_simulate"]
    assert data["first_difference_period"] == 300 and "sw" in data["differing_trace_fields"]
    assert data["cycles_median"] == 7


def test_trace_differences():
    a = {"x": np.arange(5.0), "y": np.zeros((5, 7))}
    b = {"x": np.arange(5.0), "y": np.zeros((5, 7))}
    assert trace_differences(a, b) == ([], None)
    b["y"] = b["y"].copy()
    b["y"][3, 6] = -0.0  # another bit pattern
    assert trace_differences(a, b) == (["y"], 3)


@pytest.mark.board
def test_hil_closed_loop_command(tmp_path, capsys, board):
    if board.port is not None:
        pytest.skip("the command line test starts the virtual board")
    out = tmp_path / "cl.json"
    rc = main(["hil", str(SPMSM), "--mode", "closed-loop", "--strategy", "s1", *SHORT_2L_ARGS, "--json", str(out)])
    assert rc == 0, capsys.readouterr().err
    data = json.loads(out.read_text())
    assert data["mode"] == "closed-loop" and data["periods_done"] == 4000 and data["identical_to_simulate"]
    for key in ("T_rip_RMSE_nm", "psi_rip_RMSE_wb", "THD_ia_percent", "f_ave_hz", "Cal_ave"):
        assert key in data["metrics"]
    std = capsys.readouterr()
    assert "4000/4000 periods  identical to simulate" in std.out
    assert "hil closed-loop" in std.err  # the progress line
