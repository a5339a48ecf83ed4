"""Throwaway certificates for the TLS tests, made with the openssl command line: a team
CA, one certificate per process (CN = its id, SAN 127.0.0.1 / localhost), and the
same for an intruder's own CA."""

from __future__ import annotations

import shutil
import subprocess
from collections.abc import Iterable
from pathlib import Path

import pytest

_EXT = "subjectAltName=IP:127.0.0.1,DNS:localhost\nextendedKeyUsage=serverAuth,clientAuth\n"


def need_openssl() -> str:
    openssl = shutil.which("openssl")
    if openssl is None:
        pytest.skip("openssl is not installed: cannot make throwaway certificates")
    return openssl


def _run(*args: str) -> None:
    subprocess.run(args, check=True, capture_output=True, timeout=60)


def make_ca(directory: Path, name: str = "ca") -> tuple[Path, Path]:
    openssl = need_openssl()
    directory.mkdir(parents=True, exist_ok=True)
    key, cert = directory / f"{name}.key", directory / f"{name}.pem"
    _run(
        openssl, "req", "-x509", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:P-256",
        "-nodes", "-keyout", str(key), "-out", str(cert), "-days", "2",
        "-subj", f"/CN=mrcomm-test-{name}",
    )  # fmt: skip
    return cert, key


def make_certs(directory: Path, names: Iterable[str], ca: tuple[Path, Path]) -> None:
    """``<name>.pem`` / ``<name>.key`` signed by ``ca`` for every name."""
    openssl = need_openssl()
    ext = directory / "ext.cnf"
    ext.write_text(_EXT)
    ca_cert, ca_key = ca
    for name in names:
        key, csr, cert = (directory / f"{name}{s}" for s in (".key", ".csr", ".pem"))
        _run(
            openssl, "req", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:P-256", "-nodes",
            "-keyout", str(key), "-out", str(csr), "-subj", f"/CN={name}",
        )  # fmt: skip
        _run(
            openssl, "x509", "-req", "-in", str(csr), "-CA", str(ca_cert), "-CAkey",
            str(ca_key), "-CAcreateserial", "-out", str(cert), "-days", "2",
            "-extfile", str(ext),
        )  # fmt: skip
