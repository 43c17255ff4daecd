"""The installed package works outside the repository (templates and firmware as package data)."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

from conftest import ROOT, SPMSM


@pytest.mark.slow
def test_installed_package_generates_outside_the_repo(tmp_path):
    # install from a clean export of the tracked files (no stale build/ folder can leak in)
    export = subprocess.run(f"git -C {ROOT} ls-files -z | tar --null -C {ROOT} -T - -cf - "
                            f"| (mkdir -p {tmp_path / 'src'} && tar -C {tmp_path / 'src'} -xf -)",
                            shell=True, capture_output=True, text=True)
    assert export.returncode == 0, export.stderr
    target = tmp_path / "site"
    r = subprocess.run([sys.executable, "-m", "pip", "install", "-v", "--no-deps", "--no-build-isolation",
                        "--target", str(target), str(tmp_path / "src")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    for bad in ("BuildBackendWarning", "SetuptoolsDeprecationWarning", "is absent from the `packages`"):
        assert bad not in r.stdout + r.stderr, f"setuptools warns while installing: {bad}"
    pkg = target / "codegen"
    assert (pkg / "templates" / "twolevel" / "mpc.c.j2").is_file()
    assert (pkg / "firmware" / "runtime" / "main.c").is_file()
    assert list((pkg / "simulator" / "csrc").glob("*.c")) and list((pkg / "topologies" / "ttype" / "csrc").glob("*.c"))
    assert not list((pkg / "firmware").rglob("*plant*")), "host-simulator C shipped as firmware"
    work = tmp_path / "elsewhere"
    work.mkdir()
    env = {**os.environ, "PYTHONPATH": str(target)}
    code = ("import codegen.resources as r, codegen; print(codegen.__file__); "
            "print(r.templates_dir()); print(r.firmware_dir())")
    out = subprocess.run([sys.executable, "-c", code], cwd=work, env=env, capture_output=True, text=True, check=True).stdout
    assert all(line.startswith(str(target)) for line in out.split()), out
    r = subprocess.run([sys.executable, "-m", "codegen.cli", "generate", str(SPMSM), "--target", "stm32h743",
                        "--strategy", "s3", "--tables", "published", "-o", "out", "-q"],
                       cwd=work, env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert (work / "out" / "spmsm_mpc.c").is_file()
    # the closed-loop simulator's C comes from the installed package too
    r = subprocess.run([sys.executable, "-m", "codegen.cli", "simulate", str(SPMSM), "--strategies", "s1",
                        "--tables", "published", "--set", "scenario.duration_s=0.05",
                        "--set", "scenario.load_nm=[[0.0, 1.0]]", "--set", "scenario.speed_ref_rpm=[[0.0, 100.0]]",
                        "-q"], cwd=work, env={**env, "MPCGEN_CACHE": str(tmp_path / "cache")},
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
