"""The trained s2/s3 switch tables as an explicit artefact: `tables --derive -o FILE`, `controller.tables_file`,
read into the model when the config is loaded (``tables_file.load_into``)."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

import codegen.hostbuild as hostbuild
from codegen.cli import main
from codegen.config import load_config
from codegen.errors import ConfigError
from codegen.stages.training import with_trained_tables
from codegen.topologies.twolevel.tables_file import load_into
from codegen.topology import topology_of

from conftest import EXAMPLES, SPMSM


@pytest.fixture
def derived(spmsm_tables_file) -> tuple[Path, Path]:
    """A copy of the SPMSM example and its trained-tables file (conftest's, one training run)."""
    return spmsm_tables_file


def test_file_holds_tables_counts_and_provenance(derived):
    cfg, path = derived
    data = json.loads(path.read_text())
    assert data["format"] == "mpcgen-switch-tables/1"
    assert data["training"]["strategy"] == "conventional" and data["training"]["samples_outside_eps"] > 1000
    assert len(data["tables"]["s2"]) == 2 and len(data["tables"]["s3"]) == 4
    assert len(data["counts"]["s3"]) == 4 and len(data["counts"]["s3"][0]) == 12
    assert data["derivation"]["min_cell_samples"] == 100


def test_generate_from_the_file_needs_no_compiler(derived, tmp_path, monkeypatch):
    cfg, path = derived
    ref = with_trained_tables(load_config(cfg, {"controller.strategy": "s3"}), ["s3"])  # the training stage
    want = topology_of(ref).render(ref, topology_of(ref).derive(ref), "stm32h743")
    monkeypatch.setenv("MPCGEN_CACHE", str(tmp_path / "empty-cache"))  # no cached training counts

    def no_compiler() -> str:
        raise AssertionError("generating from a tables file must not compile anything")

    monkeypatch.setattr(hostbuild, "compiler", no_compiler)
    overrides = {"controller.strategy": "s3", "controller.tables_file": f"t/{path.name}", "target.name": "stm32h743"}
    m = load_into(load_config(cfg, overrides))
    got = topology_of(m).render(m, topology_of(m).derive(m), "stm32h743")
    assert got[f"{m.prefix}_mpc.c"].split("*/", 1)[1] == want[f"{ref.prefix}_mpc.c"].split("*/", 1)[1]
    sets = [f"--set=controller.{k.split('.')[1]}={v}" for k, v in overrides.items() if k.startswith("controller")]
    assert main(["generate", str(cfg), *sets, "--target", "stm32h743", "-o", str(tmp_path / "c"), "-q"]) == 0


def test_file_from_another_training_config_is_refused(derived, tmp_path):
    cfg, path = derived
    other = tmp_path / "other.toml"
    other.write_text(cfg.read_text().replace("rs_ohm = ", "rs_ohm = 1.5 # was ", 1))
    (tmp_path / "t").mkdir()
    shutil.copy(path, tmp_path / "t" / path.name)
    with pytest.raises(ConfigError) as err:  # at load time, before anything runs
        load_into(load_config(other, {"controller.strategy": "s2", "controller.tables_file": f"t/{path.name}"}))
    msg = str(err.value)
    assert "controller.tables_file" in msg and "was derived for training configuration" in msg


def test_bad_tables_file_fields(tmp_path, capsys):
    assert main(["generate", str(SPMSM), "--set", "controller.tables_file=nope.json", "-o", str(tmp_path), "-q"]) == 2
    assert "controller.tables_file" in capsys.readouterr().err
    bad = tmp_path / "bad.json"
    bad.write_text("{}")
    tl = EXAMPLES / "seed000_tlevel.toml"
    with pytest.raises(ConfigError, match="tables_file = .*: belongs to inverter.topology = 'two-level'"):
        load_config(tl, {"controller.tables_file": str(bad)})
    assert main(["tables", str(tl), "--derive", "-o", str(tmp_path / "x.json"), "-q"]) == 2
    assert main(["tables", str(SPMSM), "--derive", "-q"]) == 2
