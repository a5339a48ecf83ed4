"""Origin signatures: an AON entry's payload verifies only with its origin's
certificate, however it travelled; without every member's certificate a process signs
but verifies nothing (it cannot tell)."""

from __future__ import annotations

from pathlib import Path

import pytest

from mrcomm.live.identity import grants
from mrcomm.messaging.messages import TOPIC_AON, TOPIC_COMMAND, AonEntry, TaskState, TaskStatus
from mrcomm.net.origin_signatures import OriginSigner, pack_signatures, unpack_signatures
from mrcomm.net.team_dir import init_team, member_files
from mrcomm.net.zenoh_config import make_options

MEMBERS = ("world", "robot_1", "robot_2", "assigner", "operator")


@pytest.fixture(scope="module")
def team(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return init_team(tmp_path_factory.mktemp("pki") / "team", MEMBERS, days=1).path


def signer(team: Path, member: str) -> OriginSigner:
    from mrcomm.net.team_dir import load_team

    files = member_files(load_team(team), member)
    options = make_options(tls_ca=files.ca, tls_cert=files.cert, tls_key=files.key,
                           acl_grants=grants(MEMBERS))  # fmt: skip
    made = OriginSigner.from_options(options)
    assert made is not None
    return made


def entry(origin: str, robot: str, task: str = "1", seq: int = 0) -> AonEntry:
    status = TaskStatus(sender=origin, incarnation=1, seq=seq, stamp=0.0, robot=robot,
                        task_id=task, state=TaskState.SUCCESS)  # fmt: skip
    return AonEntry(origin, 1, seq, b"\0", b"\0", payload=status)


def test_only_the_origin_can_sign_its_entries(team: Path) -> None:
    one, two = signer(team, "robot_1"), signer(team, "robot_2")
    assert one.verifies and two.verifies
    mine = entry("robot_1", "robot_1")
    signature = one.sign(TOPIC_AON, mine)
    assert two.verify(TOPIC_AON, mine, signature)
    assert two.remembered(TOPIC_AON, mine) == signature  # goes with two's copies
    # The same bytes under another topic, another payload, or no signature: refused.
    assert not two.verify(TOPIC_COMMAND, mine, signature)
    assert not two.verify(TOPIC_AON, entry("robot_1", "robot_1", task="2"), signature)
    assert not two.verify(TOPIC_AON, mine, None)
    # robot_2 writing an entry in robot_1's name, payload and all (a consistent forgery
    # no check of the payload can catch): its own signature is not robot_1's.
    forged = entry("robot_1", "robot_1", task="3", seq=5)
    assert not one.verify(TOPIC_AON, forged, two.sign(TOPIC_AON, forged))


def test_the_assigner_is_spoken_for_by_its_host(team: Path) -> None:
    """In a scenario whose assigner rides on robot_2, robot_2's certificate speaks for
    the assigner's key chunk; where the assigner is a member of its own, it does not."""
    from mrcomm.net.team_dir import load_team

    directory = load_team(team)
    hosted = {"world": ("world",), "robot_1": ("robot_1",),
              "robot_2": ("robot_2", "assigner"), "operator": ("operator",)}  # fmt: skip

    def made(member: str, rules: dict[str, tuple[str, ...]]) -> OriginSigner:
        files = member_files(directory, member)
        options = make_options(tls_ca=files.ca, tls_cert=files.cert, tls_key=files.key,
                               acl_grants=rules)  # fmt: skip
        signer = OriginSigner.from_options(options)
        assert signer is not None
        return signer

    by_assigner = entry("assigner", "assigner")
    signature = made("robot_2", hosted).sign(TOPIC_AON, by_assigner)
    assert made("robot_1", hosted).verify(TOPIC_AON, by_assigner, signature)
    assert not signer(team, "robot_1").verify(TOPIC_AON, by_assigner, signature)


def test_without_every_certificate_nothing_is_verified(team: Path, tmp_path: Path) -> None:
    alone = tmp_path / "host"
    alone.mkdir()
    for name in ("ca.pem", "robot_1.pem", "robot_1.key"):
        (alone / name).write_bytes((team / name).read_bytes())
    options = make_options(tls_ca=alone / "ca.pem", tls_cert=alone / "robot_1.pem",
                           tls_key=alone / "robot_1.key", acl_grants=grants(MEMBERS))  # fmt: skip
    one = OriginSigner.from_options(options)
    assert one is not None and not one.verifies  # it signs its own, checks none
    assert signer(team, "robot_2").verify(
        TOPIC_AON, entry("robot_1", "robot_1"), one.sign(TOPIC_AON, entry("robot_1", "robot_1"))
    )


def test_signatures_pack_and_bad_bytes_are_none() -> None:
    packed = pack_signatures([("robot_1", 1, 0, b"sig")])
    assert unpack_signatures(packed) == {("robot_1", 1, 0): b"sig"}
    assert unpack_signatures(b"\xc1 garbage") == {} and unpack_signatures(b"") == {}


def test_a_relayed_status_carries_its_origins_signature(team: Path) -> None:
    """robot_2 relays robot_1's status with robot_1's signature (received with it); a
    status robot_2 makes up in robot_1's name has none, and robot_3's bus refuses it."""
    from mrcomm.messaging.messages import TOPIC_RELAYED, TOPIC_TASK_STATUS, RelayedMsg, encode

    one, two, three = (signer(team, m) for m in ("robot_1", "robot_2", "operator"))
    refused: list[str] = []
    status = TaskStatus(sender="robot_1", incarnation=1, seq=4, stamp=0.0, robot="robot_1",
                        task_id="1", state=TaskState.SUCCESS)  # fmt: skip
    sent = one.signatures_for(TOPIC_TASK_STATUS, status, {"robot_1"})
    assert two.checked(TOPIC_TASK_STATUS, status, sent, refused.append) is status

    def relayed(inner: TaskStatus) -> RelayedMsg:
        return RelayedMsg(sender="robot_2", incarnation=1, seq=9, stamp=0.0,
                          topic=TOPIC_TASK_STATUS, hop=2, payload=encode(inner))  # fmt: skip

    copy = relayed(status)
    carried = two.signatures_for(TOPIC_RELAYED, copy, {"robot_2"})
    assert three.checked(TOPIC_RELAYED, copy, carried, refused.append) is copy
    invented = TaskStatus(sender="robot_1", incarnation=1, seq=5, stamp=0.0, robot="robot_1",
                          task_id="4", state=TaskState.SUCCESS)  # fmt: skip
    made_up = relayed(invented)
    forged = two.signatures_for(TOPIC_RELAYED, made_up, {"robot_2"})
    assert three.checked(TOPIC_RELAYED, made_up, forged, refused.append) is None
    assert refused == ["unsigned_entry"]
