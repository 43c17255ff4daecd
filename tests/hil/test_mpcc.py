"""The long-horizon examples (docs/mpcc.md) through the serial HIL: ``mpcgen hil --mode replay`` on the
virtual board and on the emulated one (qemu-m7, the example's horizon N = 3), every state of every
source bit for bit; and ``mpcgen firmware --board qemu-m7``'s self-test in QEMU.  qemu and the arm
toolchain are required: a missing tool fails (require_tool), never skips."""
from __future__ import annotations

import json
import subprocess

import pytest

from codegen.cli import main as mpcgen
from codegen.config import load_config
from codegen.topology import topology_of

from conftest import EXAMPLES, require_tool

CONFIGS = {"spmsm": EXAMPLES / "mpcc_spmsm.toml", "tlevel": EXAMPLES / "mpcc_tlevel.toml"}


def _replay(config: str, tmp_path, *board: str) -> dict:  # type: ignore[type-arg]
    js = tmp_path / f"replay-{config}.json"
    assert mpcgen(["hil", str(CONFIGS[config]), "--mode", "replay", *board, "--json", str(js), "-q"]) == 0
    return json.loads(js.read_text())


def _check(data: dict) -> None:  # type: ignore[type-arg]
    assert data["sources"] == {"closed_loop": 2000, "random": 2000, "adversarial": 2000}
    assert data["states"] == data["answered"] == 6000
    assert data["mismatches"] == 0 and data["lost"] == 0, data["first_mismatches"]
    assert data["complete"]


@pytest.mark.parametrize("config", sorted(CONFIGS))
def test_replay_on_the_virtual_board(config, tmp_path):
    assert load_config(CONFIGS[config]).controller.horizon == 3
    _check(_replay(config, tmp_path))


@pytest.mark.slow
@pytest.mark.parametrize("config", sorted(CONFIGS))
def test_replay_on_qemu_m7(config, tmp_path):
    require_tool("qemu-system-arm", "qemu-system-arm")
    require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi")
    data = _replay(config, tmp_path, "--board", "qemu-m7")
    _check(data)
    assert data["cycle_unit"] == "instructions"


@pytest.mark.slow
@pytest.mark.parametrize("config", sorted(CONFIGS))
def test_firmware_selftest_bit_exact_on_qemu_m7(config, tmp_path):
    """`mpcgen firmware --board qemu-m7` writes a project whose `make run` passes its self-test (every
    self-test and bench state bit for bit against the embedded reference outputs)."""
    require_tool("qemu-system-arm", "qemu-system-arm")
    require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi")
    out = tmp_path / "fw"
    assert mpcgen(["firmware", str(CONFIGS[config]), "--board", "qemu-m7", "-o", str(out), "-q"]) == 0
    m = load_config(CONFIGS[config])
    assert f"{m.prefix}_search" in (out / "gen" / f"{m.prefix}_mpc.c").read_text()
    assert topology_of(m).derive(m).horizon == 3
    r = subprocess.run(["make", "-s", "-C", str(out), "run"], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0 and "RESULT PASS" in r.stdout, r.stdout[-2000:] + r.stderr[-2000:]
