"""`mpcgen sweep --scheduler tls://...`: a cluster that lets no one else in.

A Dask scheduler without security runs whatever any client that reaches its port submits, on every
worker.  Here the scheduler and its worker take certificates signed by a CA made in the test (openssl);
a sweep with the client certificate runs and gives the serial results bit for bit, and a client
without credentials, or with a certificate of another CA, is refused.
"""
from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from codegen.cli import main
from codegen.errors import UsageError
from codegen.stages import sweep_runner

from conftest import SPMSM, require_tool

SHORT = ["--set", "scenario.duration_s=0.3", "--set", "scenario.window_s=0.1",
         "--set", "scenario.speed_ref_rpm=[[0.0, 500.0]]", "--set", "scenario.load_nm=[[0.0, 10.0]]"]


def _openssl(*args: str, cwd: Path) -> None:
    subprocess.run([require_tool("openssl", "openssl"), *args], cwd=cwd, check=True, capture_output=True)


def _credentials(d: Path, name: str) -> dict[str, Path]:
    """A CA and a certificate + key it signed (CN and SAN localhost / 127.0.0.1), EC P-256, valid 1 day."""
    d.mkdir()
    ec = ("-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes")
    _openssl("req", "-x509", *ec, "-keyout", "ca.key", "-out", "ca.pem", "-days", "1", "-subj", f"/CN={name} CA",
             cwd=d)
    _openssl("req", *ec, "-keyout", "node.key", "-out", "node.csr", "-subj", "/CN=localhost", cwd=d)
    (d / "san.ext").write_text("subjectAltName=DNS:localhost,IP:127.0.0.1\n")
    _openssl("x509", "-req", "-in", "node.csr", "-CA", "ca.pem", "-CAkey", "ca.key", "-CAcreateserial",
             "-out", "node.pem", "-days", "1", "-extfile", "san.ext", cwd=d)
    return {"ca": d / "ca.pem", "cert": d / "node.pem", "key": d / "node.key"}


def _tls_args(c: dict[str, Path]) -> list[str]:
    return ["--tls-ca-file", str(c["ca"]), "--tls-cert", str(c["cert"]), "--tls-key", str(c["key"])]


def _security(c: dict[str, Path]):
    from distributed import Security

    kw = {f"tls_{role}_{part}": str(c[part]) for role in ("client", "scheduler", "worker") for part in ("cert", "key")}
    return Security(require_encryption=True, tls_ca_file=str(c["ca"]), **kw)


def test_tls_cluster_runs_the_sweep_and_refuses_strangers(tmp_path, capsys, monkeypatch):
    from distributed import Client, LocalCluster

    good = _credentials(tmp_path / "good", "mpcgen test")
    rogue = _credentials(tmp_path / "rogue", "someone else")
    args = ["sweep", str(SPMSM), *SHORT, "-q", "--strategies", "s1", "--param", "controller.eps_t_nm=0.3,0.9"]
    serial, remote = tmp_path / "serial.json", tmp_path / "remote.json"
    assert main([*args, "--serial", "--json", str(serial)]) == 0
    monkeypatch.setattr(sweep_runner, "CONNECT_TIMEOUT_S", 3)
    with LocalCluster(n_workers=1, threads_per_worker=1, dashboard_address=None, protocol="tls://",
                      security=_security(good)) as cluster:
        address = cluster.scheduler_address
        assert address.startswith("tls://")
        # with the credentials: the sweep runs, as the serial one does
        assert main([*args, "--scheduler", address, *_tls_args(good), "--json", str(remote)]) == 0
        # a plain-TCP client at the same port: refused
        plain = address.replace("tls://", "tcp://")
        with pytest.raises((OSError, TimeoutError)):
            Client(plain, timeout="3s")
        capsys.readouterr()
        assert main([*args, "--scheduler", plain, "--json", str(tmp_path / "plain.json")]) == 2
        assert "cannot connect" in capsys.readouterr().err
        # a client that trusts the cluster's CA but holds a certificate another CA signed: the scheduler
        # refuses it (the handshake fails on the scheduler's side: it requires a client certificate of its CA)
        stranger = {**rogue, "ca": good["ca"]}
        assert main([*args, "--scheduler", address, *_tls_args(stranger), "--json", str(tmp_path / "rogue.json")]) == 2
        err = capsys.readouterr().err
        assert "cannot connect" in err and "TLS credentials" in err
        with pytest.raises((OSError, TimeoutError)):
            Client(address, timeout="3s", security=_security(stranger))
        # no credentials at all: refused before any connection
        assert main([*args, "--scheduler", address, "--json", str(tmp_path / "none.json")]) == 2
        assert "--tls-ca-file" in capsys.readouterr().err
    assert not any((tmp_path / f"{n}.json").exists() for n in ("plain", "rogue", "none"))

    def without_timing(p: Path) -> dict:
        d = json.loads(p.read_text())
        d.pop("timing")
        return d

    assert without_timing(serial) == without_timing(remote)


def test_tls_options_are_checked_before_anything_runs(tmp_path):
    pem = tmp_path / "x.pem"
    pem.write_text("not checked here\n")
    check = sweep_runner.check_runner_args
    with pytest.raises(UsageError, match="--tls-key missing"):
        check(False, "tls://127.0.0.1:8786", None, str(pem), str(pem), None)
    with pytest.raises(UsageError, match="not a readable file"):
        check(False, "tls://127.0.0.1:8786", None, str(pem), str(pem), str(tmp_path / "missing.pem"))
    with pytest.raises(UsageError, match="tls:// address"):
        check(False, "tcp://127.0.0.1:8786", None, str(pem), str(pem), str(pem))
    with pytest.raises(UsageError, match="--serial"):
        check(True, None, None, str(pem), str(pem), str(pem))
    runner = check(False, "tls://127.0.0.1:8786", None, str(pem), str(pem), str(pem))
    assert runner.tls == sweep_runner.Tls(str(pem), str(pem), str(pem))
    assert check(False, None, 1, str(pem), str(pem), str(pem)).tls is not None  # a LocalCluster over TLS
