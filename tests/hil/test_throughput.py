"""A perfect link shows no resend on any transport: 20 000 states over socket:// (the virtual board served
on a loopback TCP port, hil.virtual.SocketBoard) and over a pseudo-terminal (the virtual board), the
states/s of both printed side by side."""
from __future__ import annotations

import json

import pytest
from hil_support import SPMSM, example

from hil.cli import main
from hil.virtual import SocketBoard, build_virtual_board

pytestmark = pytest.mark.board

N = 20_000
CFG = [str(SPMSM), "--set", "controller.tables=published", "--strategy", "s1", "--states", str(N), "-q"]


def test_socket_and_pty_carry_20000_states_without_a_resend(tmp_path, capsys):
    m, t = example("spmsm", "s1")
    runs = {}
    with SocketBoard(build_virtual_board(m, t)) as sb:
        assert main(["hil", *CFG, "--port", sb.url, "--json", str(tmp_path / "socket.json")]) == 0
    runs["socket://"] = json.loads((tmp_path / "socket.json").read_text())
    assert main(["hil", *CFG, "--json", str(tmp_path / "pty.json")]) == 0
    runs["pty"] = json.loads((tmp_path / "pty.json").read_text())
    out = capsys.readouterr().out
    for name, data in runs.items():
        w = data["wire"]
        assert data["complete"] and data["answered"] == N and data["mismatches"] == 0, name
        assert w["resent_states"] == w["duplicates"] == w["reordered"] == w["handshake_retries"] == 0, (name, w)
        assert w["discarded"] == {} and w["board_errors"] == {} and not w["silent"], (name, w)
        assert data["octets_in"] == N * data["octets_per_state_in"], name  # every RESULT exactly once
        assert data["states_per_s"] > data["uart_921600_states_per_s"], name
    assert "wire:" not in out  # a perfect link: no wire counters on either line
    with capsys.disabled():
        print("\n" + "  ".join(f"{name} {data['states_per_s']:,.0f} states/s" for name, data in runs.items())
              + f"  (a 921600-baud UART: {runs['pty']['uart_921600_states_per_s']:,.0f} states/s)")
