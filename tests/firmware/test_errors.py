"""User errors of the firmware tools: clear one-line messages."""
from __future__ import annotations

import pytest

from codegen.errors import MpcgenError
from codegen.stages import emulate
from codegen.stages import firmware as firmware

from fw_support import example


@pytest.mark.parametrize("board", ["stm32h7", "", "QEMU-M7", "arduino"])
def test_unknown_board(tmp_path, board):
    m, t = example("spmsm", "conventional")
    with pytest.raises(MpcgenError) as err:
        firmware.write_firmware_project(m, t, board, tmp_path, 10)
    msg = str(err.value)
    assert "\n" not in msg and repr(board) in msg
    for name in ("stm32h743", "tms320f28377", "qemu-m7", "host"):
        assert name in msg
    assert not any(tmp_path.iterdir())


def test_missing_toolchain_and_qemu(tmp_path, monkeypatch):
    m, t = example("spmsm", "conventional")
    firmware.write_firmware_project(m, t, "qemu-m7", tmp_path, 10, n_bench=0)
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    with pytest.raises(firmware.ToolchainError) as err:
        firmware.build_firmware(tmp_path, "qemu-m7")
    assert "\n" not in str(err.value) and "gcc-arm-none-eabi" in str(err.value)
    (tmp_path / "fake.elf").write_bytes(b"\x7fELF")
    with pytest.raises(MpcgenError) as err:
        emulate.run_qemu(tmp_path / "fake.elf")
    assert "\n" not in str(err.value) and "apt-get install qemu-system-arm" in str(err.value)


def test_too_many_states_for_the_board(tmp_path):
    m, t = example("spmsm", "conventional")
    with pytest.raises(MpcgenError) as err:
        firmware.write_firmware_project(m, t, "tms320f28377", tmp_path, 20_000, n_bench=0)
    assert "lower n_selftest" in str(err.value) and "\n" not in str(err.value)
