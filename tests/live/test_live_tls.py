"""TLS with mutual authentication and the team's access-control list (issue 7 §1):
only processes holding a certificate of the team's CA connect at all, and of those
only the team members (by certificate name) may publish on the team's keys. A whole
mission runs over mutual TLS on loopback."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from mrcomm.live.launcher import free_port
from mrcomm.messaging.topics import Lane
from mrcomm.net.zenoh_config import make_options
from mrcomm.net.zenoh_node import ZenohNode

from .certs import make_ca, make_certs
from .helpers import S1, wait_for

TEAM = ("robot_1", "robot_2")


@pytest.fixture(scope="module")
def pki(tmp_path_factory: pytest.TempPathFactory) -> Path:
    directory = tmp_path_factory.mktemp("tls")
    make_certs(
        directory, ("world", "robot_1", "robot_2", "robot_3", "observer"), make_ca(directory)
    )
    other = directory / "other"
    make_certs(other, ("robot_3",), make_ca(other, "ca"))
    return directory


def tls_node(pki: Path, name: str, port: int, connect: list[int], *, ca: Path | None = None,
             cert_dir: Path | None = None, acl: bool = True) -> ZenohNode:  # fmt: skip
    certs = cert_dir or pki
    return ZenohNode(
        make_options(
            team="t",
            listen=[f"127.0.0.1:{port}"],
            connect=[f"127.0.0.1:{p}" for p in connect],
            tls_ca=ca or certs / "ca.pem",
            tls_cert=certs / f"{name}.pem",
            tls_key=certs / f"{name}.key",
            acl_members=list(TEAM) if acl else None,
        )
    )


def reaches(
    sender: ZenohNode, receiver: ZenohNode, member: ZenohNode, key: str, rounds: int = 20
) -> int:
    """Publish ``rounds`` samples on ``key`` from ``sender``, each followed by a marker
    from team ``member``; once every marker is in, count what came from ``key``."""
    got: list[bytes] = []
    marker = receiver.prefix + "/robot_2/marker"
    # Warm-up: once a marker lands, the receiver's subscription has reached the member
    # (for the positive control, the sender itself), so no sample is put too early.
    for k in range(-1, rounds):
        if k >= 0:
            sender.put(key, f"x{k}".encode(), Lane.CONTROL)
        want = f"m{k}".encode()

        def arrived(want: bytes = want) -> bool:
            # Re-sent until it lands: a fresh subscription takes a moment to propagate.
            member.put(marker, want, Lane.CONTROL)
            item = receiver.poll(0.05)
            while item is not None:
                if item.key == marker and item.value == want:
                    return True
                if item.key == key:
                    got.append(item.value)
                item = receiver.poll(None)
            return False

        wait_for(arrived, 10, f"marker {k}")
    return len(got)


def test_only_the_team_publishes_on_team_keys(pki: Path) -> None:
    ports = [free_port("127.0.0.1") for _ in range(5)]
    robot_1 = tls_node(pki, "robot_1", ports[0], [ports[1]])
    robot_2 = tls_node(pki, "robot_2", ports[1], [ports[0]])
    nodes = [robot_1, robot_2]
    try:
        robot_1.listen("mrcomm/t/**", "bus", lambda data: data)
        wait_for(lambda: robot_1.peers() and robot_2.peers(), 10, "the team to connect")
        # A team member gets through (positive control).
        assert reaches(robot_2, robot_1, robot_2, "mrcomm/t/robot_2/task_status", rounds=3) == 3
        # Signed by the team's CA but not a member: connects, yet may not publish.
        observer = tls_node(pki, "observer", ports[2], [ports[0]], acl=False)
        nodes.append(observer)
        wait_for(lambda: observer.peers(), 10, "the observer to connect")
        assert reaches(observer, robot_1, robot_2, "mrcomm/t/robot_3/task_status") == 0
        # A certificate of another CA: the handshake fails, it never joins.
        stranger = tls_node(pki, "robot_3", ports[3], [ports[0]], cert_dir=pki / "other")
        nodes.append(stranger)
        assert reaches(stranger, robot_1, robot_2, "mrcomm/t/robot_3/task_status") == 0
        assert stranger.peers() == 0
        # No certificate at all: plain TCP to a TLS endpoint gets nowhere either.
        plain = ZenohNode(
            make_options(team="t", listen=[f"127.0.0.1:{ports[4]}"],
                         connect=[f"127.0.0.1:{ports[0]}"])
        )  # fmt: skip
        nodes.append(plain)
        assert reaches(plain, robot_1, robot_2, "mrcomm/t/robot_3/task_status") == 0
        assert plain.peers() == 0
    finally:
        for node in nodes:
            node.close()


@pytest.mark.slow
def test_a_mission_over_mutual_tls_with_the_acl(pki: Path, tmp_path: Path) -> None:
    code = "from mrcomm.cli.main import app; app()"
    done = subprocess.run(
        [sys.executable, "-c", code, "live", str(S1), "--speed", "20", "--json",
         "--tls-dir", str(pki), "--acl", "--record-dir", str(tmp_path)],
        capture_output=True, text=True, timeout=240,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    summary = json.loads(done.stdout)
    assert summary["mission"]["successful"] is True
    assert summary["messages"]["task_status"]["received"] > 0
    world = json.loads(next(tmp_path.glob("world.*.jsonl")).read_text().splitlines()[0])
    assert world["listen"][0].startswith("tls/")  # the team really talked TLS
