"""The team directory: a CA and member certificates that verify against it, with the
names peers connect to; private keys readable by their owner only; written whole or
not at all; bad directories and members refused in one line."""

from __future__ import annotations

from pathlib import Path

import pytest
from cryptography import x509
from cryptography.exceptions import InvalidSignature
from cryptography.x509.oid import NameOID

from mrcomm.errors import InputError
from mrcomm.net.team_dir import add_members, init_team, load_team, member_files


def _cert(path: Path) -> x509.Certificate:
    return x509.load_pem_x509_certificate(path.read_bytes())


def test_members_are_signed_by_the_team_ca_with_their_names(tmp_path: Path) -> None:
    team = init_team(tmp_path / "team", ("world", "robot_1"), addresses={"robot_1": ["10.0.0.2"]})
    assert load_team(team.path).members == ("world", "robot_1")
    ca = _cert(team.path / "ca.pem")
    cert = _cert(member_files(team, "robot_1").cert)
    cert.verify_directly_issued_by(ca)  # raises if not signed by the team's CA
    assert cert.subject.get_attributes_for_oid(NameOID.COMMON_NAME)[0].value == "robot_1"
    names = cert.extensions.get_extension_for_class(x509.SubjectAlternativeName).value
    assert "localhost" in names.get_values_for_type(x509.DNSName)
    assert [str(a) for a in names.get_values_for_type(x509.IPAddress)] == ["127.0.0.1", "10.0.0.2"]
    assert not cert.extensions.get_extension_for_class(x509.BasicConstraints).value.ca
    for key in ("ca.key", "world.key", "robot_1.key"):
        assert (team.path / key).stat().st_mode & 0o077 == 0, key
    # Another team's CA does not vouch for this team's members.
    other = init_team(tmp_path / "other", ("robot_1",))
    with pytest.raises((ValueError, InvalidSignature)):
        cert.verify_directly_issued_by(_cert(other.path / "ca.pem"))


def test_added_members_are_signed_by_the_same_ca(tmp_path: Path) -> None:
    team = init_team(tmp_path / "team", ("world",))
    grown = add_members(team.path, ("robot_9",))
    assert grown.members == ("world", "robot_9") == load_team(team.path).members
    _cert(team.path / "robot_9.pem").verify_directly_issued_by(_cert(team.path / "ca.pem"))
    with pytest.raises(InputError, match="already a member: robot_9"):
        add_members(team.path, ("robot_9",))
    (team.path / "ca.key").unlink()  # a robot's copy: no CA key
    with pytest.raises(InputError, match="only the CA's holder"):
        add_members(team.path, ("robot_10",))
    assert not (team.path / "robot_10.pem").exists()


@pytest.mark.parametrize(
    ("members", "message"),
    [
        ((), "at least one member"),
        (("robot/1",), "not a valid id"),
        (("ca",), "reserved"),
        (("r", "r"), "named twice: r"),
    ],
)
def test_bad_members_leave_nothing(tmp_path: Path, members: tuple[str, ...], message: str) -> None:
    with pytest.raises(InputError, match=message):
        init_team(tmp_path / "team", members)
    assert list(tmp_path.iterdir()) == []


def test_an_existing_team_is_never_overwritten(tmp_path: Path) -> None:
    team = init_team(tmp_path / "team", ("world",))
    before = (team.path / "ca.pem").read_bytes()
    with pytest.raises(InputError, match="never overwritten"):
        init_team(team.path, ("world",))
    assert (team.path / "ca.pem").read_bytes() == before
    empty = tmp_path / "empty"
    empty.mkdir()
    assert init_team(empty, ("world",)).path == empty  # an empty directory is fine


def test_bad_team_directories_are_named(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="not a directory"):
        load_team(tmp_path / "nope")
    with pytest.raises(InputError, match=r"no ca\.pem"):
        load_team(tmp_path)
    team = init_team(tmp_path / "team", ("world",))
    (team.path / "team.yaml").write_text("members: 3\n")
    with pytest.raises(InputError, match="members must be a non-empty list") as err:
        load_team(team.path)
    assert err.value.file == str(team.path / "team.yaml")
    (team.path / "team.yaml").write_text("members: [world, robot_1]\n")
    with pytest.raises(InputError, match=r"no robot_1\.pem"):
        member_files(load_team(team.path), "robot_1")
    with pytest.raises(InputError, match="'robot_2' is not a member"):
        member_files(load_team(team.path), "robot_2")


@pytest.mark.parametrize("host", ["é.local", "a b", "-x", "x" * 300, "", "robot_1", "1.2.3.4/8"])
def test_addresses_must_be_ip_addresses_or_host_names(tmp_path: Path, host: str) -> None:
    """Found by the CLI fuzz: a non-ASCII name reached the certificate builder."""
    with pytest.raises(InputError, match="neither an IP address nor a host name"):
        init_team(tmp_path / "team", ("robot_1",), addresses={"robot_1": [host]})
    assert list(tmp_path.iterdir()) == []
