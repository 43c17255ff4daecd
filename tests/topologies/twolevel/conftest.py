"""Fixtures of the simulator tests: the stub-controller build and the SPMSM model.

The model is built straight from examples/seed001_spmsm.toml with tomllib
(these tests exercise the simulator, not the config loader).
"""
from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

from codegen.model import Controller, Derivation, Inverter, Model, Motor, Scenario, SpeedLoop
from codegen.topologies.twolevel.sim import SIM
from tests.fixtures.simbuild import build_stub_library

ROOT = Path(__file__).resolve().parents[3]

STUB_CDEF = """
void stub_twolevel_set_params(float ld_h, float lq_h, float psi_f_wb, int pole_pairs,
                              float psi_ref_wb, float band_nm);
void stub_twolevel_set_echo(int mode);
"""


def model_from_toml(path: Path) -> Model:
    d = tomllib.loads(path.read_text())
    ctrl = dict(d["controller"])
    deriv = Derivation(**ctrl.pop("derivation", {}))
    scen = dict(d["scenario"])
    scen["speed_ref_rpm"] = tuple(tuple(map(float, s)) for s in scen["speed_ref_rpm"])
    scen["load_nm"] = tuple(tuple(map(float, s)) for s in scen["load_nm"])
    return Model(
        name=d["meta"]["name"],
        prefix=d["meta"]["prefix"],
        source=str(path),
        motor=Motor(**d["motor"]),
        inverter=Inverter(**d["inverter"]),
        controller=Controller(derivation=deriv, **ctrl),
        speed_loop=SpeedLoop(**d["speed_loop"]),
        scenario=Scenario(**scen),
        target=d["target"]["name"],
    )


@pytest.fixture(scope="session")
def spmsm_model() -> Model:
    return model_from_toml(ROOT / "examples" / "seed001_spmsm.toml")


@pytest.fixture(scope="session")
def stub(tmp_path_factory):
    """(ffi, lib): the two-level simulator + stub controller, strict flags, cffi ABI mode."""
    return build_stub_library(SIM, STUB_CDEF, tmp_path_factory.mktemp("stub_build"))


@pytest.fixture(scope="session")
def spmsm_tables_file(tmp_path_factory) -> tuple[Path, Path]:
    """A copy of the SPMSM example and its trained-tables file (``t/spmsm_tables.json`` next to it), written
    by ``mpcgen tables --derive`` (one training run for every test that needs it)."""
    import shutil

    from codegen.cli import main

    d = tmp_path_factory.mktemp("trained")
    cfg = d / "spmsm.toml"
    shutil.copy(ROOT / "examples" / "seed001_spmsm.toml", cfg)
    assert main(["tables", str(cfg), "--derive", "-o", str(d / "t" / "spmsm_tables.json"), "-q"]) == 0
    return cfg, d / "t" / "spmsm_tables.json"
