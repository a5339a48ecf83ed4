"""Zenoh configuration of live mode: endpoints, TLS files, ACL, config files; every bad
value a one-line error naming the option."""

from __future__ import annotations

from pathlib import Path

import pytest

from mrcomm.errors import InputError
from mrcomm.net.zenoh_config import (
    acl_json,
    build_config,
    check_key_chunk,
    config_json,
    make_options,
    normalise_endpoint,
)


def test_endpoints_take_the_protocol_and_reject_nonsense() -> None:
    assert normalise_endpoint("127.0.0.1:7447", "tcp", "--listen") == "tcp/127.0.0.1:7447"
    assert normalise_endpoint("udp/10.0.0.2:7447", "tcp", "--connect") == "udp/10.0.0.2:7447"
    assert normalise_endpoint("tcp/[::1]:7447", "tcp", "--connect") == "tcp/[::1]:7447"
    for bad, needle in (
        ("localhost", "expected PROTOCOL/HOST:PORT"),
        ("tcp/127.0.0.1:99999", "out of range"),
        ("serial/ttyUSB0:1", "unsupported protocol"),
    ):
        with pytest.raises(InputError, match=needle) as err:
            normalise_endpoint(bad, "tcp", "--connect")
        assert err.value.field == "--connect"


def test_ids_must_be_plain_key_chunks() -> None:
    assert check_key_chunk("robot_1", "--robot") == "robot_1"
    for bad in ("robot/1", "robot*", "a b", "$x"):
        with pytest.raises(InputError, match="not a valid id"):
            check_key_chunk(bad, "--robot")


def test_options_become_a_peer_config_without_multicast_by_default() -> None:
    options = make_options(team="red", listen=["127.0.0.1:7000"], connect=["127.0.0.1:7001"])
    settings = config_json(options)
    assert settings["mode"] == "peer"
    assert settings["scouting/multicast/enabled"] is False
    assert settings["listen/endpoints"] == ["tcp/127.0.0.1:7000"]
    assert settings["connect/endpoints"] == ["tcp/127.0.0.1:7001"]
    assert settings["connect/exit_on_failure"] is False
    assert options.prefix() == "mrcomm/red"
    udp = make_options(listen=["127.0.0.1:7000"], protocol="udp", multicast=True)
    assert config_json(udp)["listen/endpoints"] == ["udp/127.0.0.1:7000"]
    assert config_json(udp)["scouting/multicast/enabled"] is True
    build_config(options)  # Zenoh accepts every key we set


def _pem(path: Path, kind: str) -> Path:
    path.write_text(f"-----BEGIN {kind}-----\nAAAA\n-----END {kind}-----\n")
    return path


def test_tls_needs_all_three_readable_pem_files(tmp_path: Path) -> None:
    ca = _pem(tmp_path / "ca.pem", "CERTIFICATE")
    cert = _pem(tmp_path / "r.pem", "CERTIFICATE")
    key = _pem(tmp_path / "r.key", "PRIVATE KEY")
    options = make_options(tls_ca=ca, tls_cert=cert, tls_key=key, listen=["127.0.0.1:1"])
    tls = config_json(options)["transport/link/tls"]
    assert tls["enable_mtls"] is True and tls["root_ca_certificate"] == str(ca)
    assert options.listen == ("tls/127.0.0.1:1",)
    # TLS links only: nothing listens in the clear, no plain link is opened or accepted
    # (a session given no endpoint would listen on Zenoh's default, tcp/[::]:0).
    assert config_json(options)["transport/link/protocols"] == ["tls"]
    assert config_json(options)["listen/endpoints"] == ["tls/127.0.0.1:1"]
    quiet = make_options(tls_ca=ca, tls_cert=cert, tls_key=key, connect=["127.0.0.1:2"])
    assert config_json(quiet)["listen/endpoints"] == []
    assert "transport/link/protocols" not in config_json(make_options())
    with pytest.raises(InputError, match="needs all of"):
        make_options(tls_ca=ca, tls_cert=cert)
    with pytest.raises(InputError, match="file not found") as err:
        make_options(tls_ca=ca, tls_cert=tmp_path / "missing.pem", tls_key=key)
    assert err.value.field == "--tls-cert"
    with pytest.raises(InputError, match="not a PEM private key") as err:
        make_options(tls_ca=ca, tls_cert=cert, tls_key=cert)
    assert err.value.field == "--tls-key"
    with pytest.raises(InputError, match="TLS runs over TCP"):
        make_options(tls_ca=ca, tls_cert=cert, tls_key=key, protocol="udp")


def test_acl_binds_each_member_to_its_own_keys_and_needs_tls() -> None:
    acl = acl_json("mrcomm/red", {"robot_1": ("robot_1", "robot_1-pulse"), "world": ("world",)})
    assert acl["default_permission"] == "deny"
    rules = {rule["id"]: rule for rule in acl["rules"]}
    subjects = {s["id"]: s["cert_common_names"] for s in acl["subjects"]}
    granted = {
        subjects[subject][0]: rules[policy["rules"][0]]
        for policy in acl["policies"]
        for subject in policy["subjects"]
        if subject != "members"
    }
    # Publications and tokens from a member are accepted only under its own chunks.
    assert granted["robot_1"]["key_exprs"] == [
        "mrcomm/red/robot_1/**",
        "mrcomm/red/robot_1-pulse/**",
    ]
    assert granted["robot_1"]["flows"] == ["ingress"]
    assert set(granted["robot_1"]["messages"]) == {"put", "delete", "liveliness_token"}
    assert granted["world"]["key_exprs"] == ["mrcomm/red/world/**"]
    # Subscribing and querying: every member, the whole team's key space, nothing else.
    assert subjects["members"] == ["robot_1", "world"]
    assert rules["read"]["key_exprs"] == ["mrcomm/red/**"]
    assert "put" not in rules["read"]["messages"]
    assert rules["deliver"]["flows"] == ["egress"]
    with pytest.raises(InputError, match="needs TLS"):
        make_options(acl_grants={"robot_1": ("robot_1",)})


def test_grants_follow_what_each_process_publishes() -> None:
    from mrcomm.live.identity import grants
    from mrcomm.world.scenario import load_scenario

    from .helpers import S1

    scenario = load_scenario(S1)  # the task assigner runs on robot_2
    given = grants(("world", "robot_1", "robot_2", "robot_3", "assigner"), scenario)
    assert given["robot_1"] == ("robot_1", "robot_1-pulse")
    assert given["robot_2"] == ("robot_2", "robot_2-pulse", "assigner")
    assert given["world"] == ("world", "robot_1-pulse", "robot_2-pulse", "robot_3-pulse")
    assert given["assigner"] == ("assigner",)


def test_config_file_errors_name_the_file(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="file not found"):
        make_options(config_file=tmp_path / "nope.json5")
    bad = tmp_path / "bad.json5"
    bad.write_text("{ mode: 'peer', listen: { endpoints: 42 } ")
    options = make_options(config_file=bad)
    with pytest.raises(InputError, match="not a valid Zenoh config") as err:
        build_config(options)
    assert err.value.file == str(bad)
    good = tmp_path / "good.json5"
    good.write_text("{ mode: 'peer', listen: { endpoints: ['tcp/127.0.0.1:0'] } }")
    config = build_config(make_options(config_file=good))
    assert "127.0.0.1:0" in config.get_json("listen/endpoints")


def test_bad_protocol_and_team_are_one_line_errors() -> None:
    with pytest.raises(InputError, match="choose tcp or udp"):
        make_options(protocol="sctp")
    with pytest.raises(InputError, match="not a valid id"):
        make_options(team="a/b")
