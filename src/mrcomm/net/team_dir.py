"""A team directory: the team's certificate authority and one certificate per member.

Live mode authenticates every process by a certificate of the team's CA (mutual TLS)
and lets each publish only under its own keys (the access-control list of
:mod:`mrcomm.net.zenoh_config`, subjects by certificate common name). This module
makes and reads the directory that holds them::

    DIR/team.yaml          members (certificate common names), validity, addresses
    DIR/ca.pem             the team CA's certificate (public: every member needs it)
    DIR/ca.key             the CA's private key (keep it off the robots; 0600)
    DIR/<member>.pem       a member's certificate, CN = its process id
    DIR/<member>.key       its private key (0600; copy it to that member's host only)

Certificates are ECDSA P-256, usable as TLS server and client (every Zenoh peer is
both); each names 127.0.0.1, localhost and the member's own addresses (``--address``)
so that ``verify_name_on_connect`` holds. Made with the ``cryptography`` package, no
external tool. A directory is written whole or not at all (made in a temporary
sibling, then renamed), and an existing team is never overwritten.
"""

from __future__ import annotations

import datetime
import ipaddress
import os
import re
import shutil
import tempfile
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

import yaml

from mrcomm.errors import InputError
from mrcomm.fileio import atomic_write_text
from mrcomm.net.zenoh_config import TlsFiles, check_key_chunk
from mrcomm.world.yamlfile import read_yaml

TEAM_FILE = "team.yaml"
#: Validity of the certificates ``mrcomm team init`` makes unless told otherwise.
DEFAULT_DAYS = 365
#: Addresses every certificate names (processes on one host reach each other there).
LOOPBACK = ("127.0.0.1", "localhost")


@dataclass(frozen=True)
class TeamDirectory:
    """A team directory on disk: where each member's PEM files are, and who is a member."""

    path: Path
    members: tuple[str, ...]

    def files(self, member: str) -> TlsFiles:
        """The CA, certificate and key a process presenting ``member`` uses."""
        return TlsFiles(
            self.path / "ca.pem", self.path / f"{member}.pem", self.path / f"{member}.key"
        )


def load_team(path: Path, option: str = "--team-dir") -> TeamDirectory:
    """Read ``path/team.yaml`` (one-line errors naming the file and what is wrong)."""
    if not path.is_dir():
        raise InputError(
            "not a directory (make one with mrcomm team init)", file=path, field=option
        )
    team_file = path / TEAM_FILE
    if not (path / "ca.pem").is_file():
        raise InputError(
            "no ca.pem: not a team directory (mrcomm team init)", file=path, field=option
        )
    if not team_file.is_file():
        raise InputError(f"no {TEAM_FILE}: not a team directory", file=path, field=option)
    data = read_yaml(team_file)
    members = data.get("members") if isinstance(data, dict) else None
    if not isinstance(members, list) or not members or not all(isinstance(m, str) for m in members):
        raise InputError(
            "members must be a non-empty list of names", file=team_file, field="members"
        )
    for member in members:
        check_key_chunk(member, "members")
    return TeamDirectory(path, tuple(members))


def member_files(team: TeamDirectory, member: str, option: str = "--team-dir") -> TlsFiles:
    """``member``'s files, refused in one line when it is not in the team or lacks them."""
    if member not in team.members:
        raise InputError(
            f"{member!r} is not a member of this team (members: {', '.join(team.members)}); "
            f"add it with mrcomm team add",
            file=team.path,
            field=option,
        )
    files = team.files(member)
    for path in (files.cert, files.key):
        if not path.is_file():
            raise InputError(
                f"no {path.name} for member {member!r} (copy it from the team directory)",
                file=team.path,
                field=option,
            )
    return files


def init_team(
    path: Path,
    members: Iterable[str],
    *,
    addresses: Mapping[str, Iterable[str]] | None = None,
    days: int = DEFAULT_DAYS,
    name: str = "mrcomm team",
) -> TeamDirectory:
    """Make a new team directory at ``path`` (absent or empty): a CA and every member's
    certificate. Written in a temporary sibling and renamed, so it exists whole or not."""
    names = _check_members(members)
    if days < 1 or days > 3650:
        raise InputError("validity must be 1 to 3650 days", field="--days")
    if path.exists() and (not path.is_dir() or any(path.iterdir())):
        raise InputError(
            "already exists and is not empty: a team is never overwritten "
            "(add members with mrcomm team add)",
            file=path,
            field="DIR",
        )
    extra = _check_addresses(addresses or {}, names)
    ca_key, ca_cert = _make_ca(name, days)
    parent = path.resolve().parent
    if not parent.is_dir():
        raise InputError("its parent directory does not exist", file=path, field="DIR")
    staging = Path(tempfile.mkdtemp(prefix=f".{path.name}.", dir=parent))
    try:
        _write(staging / "ca.pem", _cert_pem(ca_cert), private=False)
        _write(staging / "ca.key", _key_pem(ca_key), private=True)
        for member in names:
            _write_member(staging, member, ca_key, ca_cert, extra.get(member, ()), days)
        _write_team_file(staging, names, days)
        if path.exists():
            path.rmdir()  # empty (checked above): the rename needs it gone
        staging.rename(path)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    return TeamDirectory(path, names)


def add_members(
    path: Path,
    members: Iterable[str],
    *,
    addresses: Mapping[str, Iterable[str]] | None = None,
    days: int = DEFAULT_DAYS,
) -> TeamDirectory:
    """Sign certificates for new members with the team's CA (which must be present)."""
    team = load_team(path, "DIR")
    names = _check_members(members)
    known = [m for m in names if m in team.members]
    if known:
        raise InputError(f"already a member: {', '.join(known)}", file=path, field="--members")
    ca_key_path = path / "ca.key"
    if not ca_key_path.is_file():
        raise InputError("no ca.key: only the CA's holder can add members", file=path, field="DIR")
    from cryptography import x509
    from cryptography.hazmat.primitives import serialization
    from cryptography.hazmat.primitives.asymmetric import ec

    try:
        ca_cert = x509.load_pem_x509_certificate((path / "ca.pem").read_bytes())
        ca_key = serialization.load_pem_private_key(ca_key_path.read_bytes(), password=None)
    except ValueError as err:
        raise InputError(f"cannot read the team CA: {err}", file=path, field="DIR") from None
    if not isinstance(ca_key, ec.EllipticCurvePrivateKey):
        raise InputError("ca.key is not an EC private key", file=path, field="DIR")
    extra = _check_addresses(addresses or {}, names)
    written: list[Path] = []
    try:
        for member in names:
            written += _write_member(path, member, ca_key, ca_cert, extra.get(member, ()), days)
        _write_team_file(path, (*team.members, *names), days)
    except BaseException:
        for file in written:
            file.unlink(missing_ok=True)
        raise
    return TeamDirectory(path, (*team.members, *names))


# -- internals -------------------------------------------------------------------------
def _check_members(members: Iterable[str]) -> tuple[str, ...]:
    names = tuple(m.strip() for m in members if m.strip())
    if not names:
        raise InputError("give at least one member", field="--members")
    for member in names:
        check_key_chunk(member, "--members")
        if member in ("ca", "team"):
            raise InputError(f"{member!r} is reserved (file names of the team)", field="--members")
    duplicates = sorted({m for m in names if names.count(m) > 1})
    if duplicates:
        raise InputError(f"named twice: {', '.join(duplicates)}", field="--members")
    return names


def _check_addresses(
    addresses: Mapping[str, Iterable[str]], members: tuple[str, ...]
) -> dict[str, tuple[str, ...]]:
    out: dict[str, tuple[str, ...]] = {}
    for member, hosts in addresses.items():
        if member not in members:
            raise InputError(f"{member!r} is not among the members", field="--address")
        checked = []
        for host in hosts:
            if not _is_address(host):
                raise InputError(
                    f"{host!r} is neither an IP address nor a host name", field="--address"
                )
            checked.append(host)
        out[member] = tuple(checked)
    return out


_HOST_NAME = re.compile(r"^(?=.{1,253}$)([A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?\.?)+$")


def _is_address(host: str) -> bool:
    """An IP address or an ASCII DNS name (what a certificate's subjectAltName holds)."""
    try:
        ipaddress.ip_address(host)
        return True
    except ValueError:
        return _HOST_NAME.match(host) is not None


def _now() -> datetime.datetime:
    return datetime.datetime.now(datetime.UTC)


def _make_ca(name: str, days: int):  # type: ignore[no-untyped-def]
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import NameOID

    key = ec.generate_private_key(ec.SECP256R1())
    subject = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, f"{name} CA")])
    start = _now() - datetime.timedelta(minutes=5)  # tolerate clocks a little behind
    cert = (
        x509.CertificateBuilder()
        .subject_name(subject)
        .issuer_name(subject)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(start)
        .not_valid_after(start + datetime.timedelta(days=days))
        .add_extension(x509.BasicConstraints(ca=True, path_length=0), critical=True)
        .add_extension(
            x509.KeyUsage(
                digital_signature=True,
                key_cert_sign=True,
                crl_sign=True,
                content_commitment=False,
                key_encipherment=False,
                data_encipherment=False,
                key_agreement=False,
                encipher_only=False,
                decipher_only=False,
            ),
            critical=True,
        )
        .add_extension(x509.SubjectKeyIdentifier.from_public_key(key.public_key()), critical=False)
        .sign(key, hashes.SHA256())
    )
    return key, cert


def _write_member(  # type: ignore[no-untyped-def]
    directory: Path, member: str, ca_key, ca_cert, hosts: tuple[str, ...], days: int
) -> list[Path]:
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

    key = ec.generate_private_key(ec.SECP256R1())
    names: list[x509.GeneralName] = []
    for host in (*LOOPBACK, *hosts):
        try:
            names.append(x509.IPAddress(ipaddress.ip_address(host)))
        except ValueError:
            names.append(x509.DNSName(host))
    start = _now() - datetime.timedelta(minutes=5)
    cert = (
        x509.CertificateBuilder()
        .subject_name(x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, member)]))
        .issuer_name(ca_cert.subject)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(start)
        .not_valid_after(min(start + datetime.timedelta(days=days), ca_cert.not_valid_after_utc))
        .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
        .add_extension(x509.SubjectAlternativeName(names), critical=False)
        .add_extension(
            x509.ExtendedKeyUsage(
                [ExtendedKeyUsageOID.SERVER_AUTH, ExtendedKeyUsageOID.CLIENT_AUTH]
            ),
            critical=False,
        )
        .add_extension(
            x509.AuthorityKeyIdentifier.from_issuer_public_key(ca_key.public_key()), critical=False
        )
        .sign(ca_key, hashes.SHA256())
    )
    cert_path, key_path = directory / f"{member}.pem", directory / f"{member}.key"
    _write(cert_path, _cert_pem(cert), private=False)
    _write(key_path, _key_pem(key), private=True)
    return [cert_path, key_path]


def _write_team_file(directory: Path, members: Iterable[str], days: int) -> None:
    text = yaml.safe_dump({"members": list(members), "days": days}, sort_keys=False)
    atomic_write_text(directory / TEAM_FILE, text)  # readers see the old list or the new


def _cert_pem(cert) -> bytes:  # type: ignore[no-untyped-def]
    from cryptography.hazmat.primitives import serialization

    return bytes(cert.public_bytes(serialization.Encoding.PEM))


def _key_pem(key) -> bytes:  # type: ignore[no-untyped-def]
    from cryptography.hazmat.primitives import serialization

    return bytes(
        key.private_bytes(
            serialization.Encoding.PEM,
            serialization.PrivateFormat.PKCS8,
            serialization.NoEncryption(),
        )
    )


def _write(path: Path, data: bytes, *, private: bool) -> None:
    """Write ``data``; a private key is created readable by its owner only (never
    world-readable, not even for an instant)."""
    mode = 0o600 if private else 0o644
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, mode)
    with os.fdopen(fd, "wb") as handle:
        handle.write(data)
