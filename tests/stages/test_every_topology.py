"""Every command works for every topology or refuses in one line with exit code 2.

The defects this pins: `firmware` on a t-type config ran the two-level table
builder (KeyError), `simulate --sweep-eps` ran the two-level controller and
plant on a t-type config, `generate` wrote no report for the t-type.
"""
from __future__ import annotations

from pathlib import Path

import pytest

from codegen.cli import main
from codegen.config import load_config
from codegen.registry import TOPOLOGY_PACKAGES as TOPOLOGIES
from codegen.topology import topology

from conftest import EXAMPLES

CONFIGS = {"two-level": EXAMPLES / "seed001_spmsm.toml", "t-type": EXAMPLES / "seed000_tlevel.toml"}


def test_every_registered_topology_has_an_example():
    assert set(CONFIGS) == set(TOPOLOGIES)
    for name in TOPOLOGIES:
        assert topology(name).name == name


@pytest.mark.parametrize("name", sorted(CONFIGS))
def test_generate_writes_c_and_a_report(tmp_path: Path, name: str):
    out = tmp_path / "c"
    assert main(["generate", str(CONFIGS[name]), "--target", "stm32h743", "-o", str(out), "-q",
                 "--set", "controller.tables=published"] if name == "two-level" else
                ["generate", str(CONFIGS[name]), "--target", "stm32h743", "-o", str(out), "-q"]) == 0
    reports = list(out.glob("*_report.md"))
    assert len(reports) == 1
    text = reports[0].read_text()
    assert topology(name).title in text
    for section in ("## Constants", "## Read-only data", "## Input guard", "## Assumptions"):
        assert section in text, section


def test_sweep_eps_on_a_ttype_config_is_refused(capsys):
    assert main(["simulate", str(CONFIGS["t-type"]), "--sweep-eps", "0.5:0.6:0.1", "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "t-type" in err[0] and "--sweep-eps" in err[0]


def test_tables_utilisation_on_a_ttype_config_is_refused(capsys):
    assert main(["tables", str(CONFIGS["t-type"]), "--utilisation", "published", "-q"]) == 2
    assert "--utilisation" in capsys.readouterr().err


@pytest.mark.parametrize("name", sorted(CONFIGS))
def test_firmware_project_is_the_configs_topology(tmp_path: Path, name: str):
    out = tmp_path / "fw"
    args = ["firmware", str(CONFIGS[name]), "--board", "qemu-m7", "-o", str(out), "-q"]
    if name == "two-level":
        args += ["--set", "controller.tables=published"]
    assert main(args) == 0
    header = next((out / "gen").glob("*_mpc.h")).read_text()
    for f in topology(name).input_record.fields + topology(name).output_record(load_config(CONFIGS[name])).fields:
        assert f" {f.name}" in header, f.name
    data = (out / "gen" / "mpc_selftest_data.c").read_text()
    assert topology(name).reference in data


def test_generate_target_all_writes_every_target(tmp_path: Path):
    from codegen.model import TARGETS

    assert main(["generate", str(CONFIGS["t-type"]), "--target", "all", "-o", str(tmp_path), "-q"]) == 0
    for t in TARGETS:
        assert (tmp_path / t / "tlevel_mpc.c").is_file() and (tmp_path / t / "tlevel_report.md").is_file()
    assert "ITCM" in (tmp_path / "stm32h743" / "tlevel_report.md").read_text()
