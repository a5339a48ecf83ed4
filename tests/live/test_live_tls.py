"""Mutual TLS and the per-member access-control list: only processes holding a
certificate of the team's CA connect at all; of those only members publish on the
team's keys, and each member only under its own keys (its grants), so no certificate
can pose as another robot or as the world. A whole mission runs over mutual TLS by
default, and one runs with a member certificate turned rogue forging statuses, ticks
and liveliness in other members' names: none of it reaches any process."""

from __future__ import annotations

import json
import subprocess
import sys
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from mrcomm.live.identity import grants
from mrcomm.live.launcher import LiveTeam, free_port
from mrcomm.live.settings import LiveSettings
from mrcomm.messaging.topics import Lane
from mrcomm.net.team_dir import init_team
from mrcomm.net.zenoh_config import make_options
from mrcomm.net.zenoh_node import ZenohNode
from mrcomm.run.config import make_config

from .helpers import S1, wait_for

TEAM = ("world", "robot_1", "robot_2", "robot_3")


@pytest.fixture(scope="module")
def pki(tmp_path_factory: pytest.TempPathFactory) -> Path:
    directory = tmp_path_factory.mktemp("tls")
    init_team(directory / "team", (*TEAM, "observer"), days=1)
    init_team(directory / "other", ("robot_3",), days=1)  # a foreign CA, same names
    return directory / "team"


def tls_node(pki: Path, name: str, port: int, connect: list[int], *, cert_dir: Path | None = None,
             acl: bool = True) -> ZenohNode:  # fmt: skip
    certs = cert_dir or pki
    return ZenohNode(
        make_options(
            team="t",
            listen=[f"127.0.0.1:{port}"],
            connect=[f"127.0.0.1:{p}" for p in connect],
            tls_ca=certs / "ca.pem",
            tls_cert=certs / f"{name}.pem",
            tls_key=certs / f"{name}.key",
            acl_grants=grants(TEAM) if acl else None,
        )
    )


def reaches(
    sender: ZenohNode,
    receiver: ZenohNode,
    member: ZenohNode,
    key: str,
    rounds: int = 20,
    member_id: str = "robot_2",
) -> int:
    """Publish ``rounds`` samples on ``key`` from ``sender``, each followed by a marker
    from team ``member`` (``member_id``) under its own key; once every marker is in,
    count what came from ``key``. When the member is the sender itself, its marker
    follows its sample on the same lane and link, so nothing arrives after the count."""
    got: list[bytes] = []
    marker = f"{receiver.prefix}/{member_id}/marker"
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
        stranger = tls_node(pki, "robot_3", ports[3], [ports[0]], cert_dir=pki.parent / "other")
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


def test_a_member_publishes_only_under_its_own_keys(pki: Path) -> None:
    """robot_3 holds a valid member certificate: what it publishes under its own keys
    arrives; statuses in robot_1's or the assigner's key space, the world's clock, a
    pulse of another robot and liveliness tokens in others' names never do."""
    ports = [free_port("127.0.0.1") for _ in range(4)]
    robot_1 = tls_node(pki, "robot_1", ports[0], [ports[1], ports[2], ports[3]])
    robot_2 = tls_node(pki, "robot_2", ports[1], [ports[0]])
    robot_3 = tls_node(pki, "robot_3", ports[2], [ports[0]])
    world = tls_node(pki, "world", ports[3], [ports[0]])
    nodes = [robot_1, robot_2, robot_3, world]
    try:
        robot_1.listen("mrcomm/t/**", "bus", lambda data: data)
        wait_for(lambda: robot_1.peers() >= 3, 10, "the team to connect")
        # Positive controls: each under its own keys.
        for key in ("robot_3/task_status", "robot_3-pulse/rssi"):
            assert reaches(robot_3, robot_1, robot_3, f"mrcomm/t/{key}", 3, "robot_3") == 3
        assert reaches(world, robot_1, world, "mrcomm/t/world/tick", 3, "world") == 3
        # Posing as someone else: refused by the receiver, whoever the sender claims.
        for key in ("robot_1/task_status", "assigner/task_status", "world/tick",
                    "robot_2-pulse/rssi", "robot_2/base_cmd"):  # fmt: skip
            assert reaches(robot_3, robot_1, robot_3, f"mrcomm/t/{key}", 20, "robot_3") == 0, key
        # Liveliness: a token in robot_2's name never shows; its own does.
        robot_1.watch_presence()
        robot_3.declare_alive("robot_2", 99)
        robot_3.declare_alive("robot_3", 7)
        seen: list[tuple[str, int]] = []

        def own_token() -> bool:
            item = robot_1.poll(0.1)
            while item is not None:
                if item.channel == "presence":
                    seen.append((item.value.agent, item.value.incarnation))
                item = robot_1.poll(None)
            return ("robot_3", 7) in seen

        wait_for(own_token, 10, "robot_3's own token")
        assert ("robot_2", 99) not in seen
        assert 99 not in robot_1.present("robot_2")
    finally:
        for node in nodes:
            node.close()


@pytest.mark.slow
def test_a_mission_with_a_team_made_by_team_init(tmp_path: Path) -> None:
    code = "from mrcomm.cli.main import app; app()"
    team_dir = tmp_path / "team"
    made = subprocess.run(
        [sys.executable, "-c", code, "team", "init", str(team_dir), "--scenario", str(S1)],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert made.returncode == 0, made.stderr
    records = tmp_path / "records"
    done = subprocess.run(
        [sys.executable, "-c", code, "live", str(S1), "--speed", "20", "--json",
         "--team-dir", str(team_dir), "--record-dir", str(records)],
        capture_output=True, text=True, timeout=240,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    assert "warning" not in done.stderr
    summary = json.loads(done.stdout)
    assert summary["mission"]["successful"] is True
    assert summary["messages"]["task_status"]["received"] > 0
    world = json.loads(next(records.glob("world.*.jsonl")).read_text().splitlines()[0])
    assert world["listen"][0].startswith("tls/")  # the team really talked TLS


@pytest.mark.slow
def test_a_rogue_member_certificate_cannot_forge_statuses_ticks_or_presence(
    tmp_path: Path,
) -> None:
    """A process holding robot_3's certificate (a stolen robot) publishes, all mission
    long, SUCCESS statuses and poses in every other member's name under their keys,
    clock ticks far in the future and an ending tick under the world's key, and tokens
    in others' names — and garbage under its own keys. With the team's ACL nothing but
    the garbage reaches any process (counted there as undecodable), and the S1 mission
    succeeds. Without the ACL the same attack is counted by the bus edge as wrong types
    and forged senders (test_live_faults.py) — or, for the ending tick, obeyed."""
    import msgspec

    from mrcomm.live.identity import live_members
    from mrcomm.live.protocol import Tick
    from mrcomm.messaging.messages import PoseMsg, TaskState, TaskStatus, encode
    from mrcomm.messaging.topics import lane_of
    from mrcomm.world.scenario import load_scenario

    team_dir = init_team(tmp_path / "team", live_members(load_scenario(S1)), days=1).path
    config = make_config(None, scenario=S1)
    settings = LiveSettings(config, make_options(), tmp_path / "records", speed=20.0)
    stop = threading.Event()
    sent = {"samples": 0}
    others = ("robot_1", "robot_2", "assigner")

    def attack(node: ZenohNode) -> None:
        seq = 0
        for member in (*others, "world"):
            node.declare_alive(member, 424242)
        while not stop.is_set():
            seq += 1
            for member in others:
                status = TaskStatus(
                    sender=member, incarnation=1, seq=seq, stamp=0.0, robot=member,
                    task_id="4", state=TaskState.SUCCESS,
                )  # fmt: skip
                node.put(node.key(member, "task_status"), encode(status), lane_of("task_status"))
                pose = PoseMsg(sender=member, incarnation=1, seq=seq, stamp=0.0, x=0, y=0, theta=0)
                node.put(node.key(member, "pose"), encode(pose), lane_of("pose"))
            future = Tick(time=1e9, speed=20.0, states=())
            ending = Tick(time=1.0, speed=20.0, states=(), end=True, end_time=1.0)
            for tick in (future, ending):
                node.put(node.key("world", "tick"), msgspec.msgpack.encode(tick), Lane.BEST_EFFORT)
            node.put(node.key("robot_3", "pose"), b"\xc1 garbage", Lane.BEST_EFFORT)
            sent["samples"] += 2 * len(others) + 3
            stop.wait(0.05)

    result, report = mission_with_rogue(settings, team_dir, attack, stop)
    assert report["died"] == []
    assert result.mission["successful"] is True and result.mission["timed_out"] is False
    assert sent["samples"] > 1000
    for robot in ("robot_1", "robot_2"):
        refused = report["processes"][robot]["refused"]
        # Nothing of the rogue's but its own garbage reached either robot ...
        assert set(refused) <= {"undecodable"}, (robot, refused)
        # ... and it was connected and heard.
        assert refused.get("undecodable", 0) > 10, (robot, refused)


def test_a_rogue_member_cannot_falsify_the_result_from_its_own_keys(tmp_path: Path) -> None:
    """A process holding robot_3's certificate, knowing the mission's identity (it is in
    the traffic), attacks all mission long from robot_3's own key space, where the ACL
    lets it speak: statuses crediting robot_1's and robot_2's tasks, AON entries whose
    payload names another robot or whose origin is another member, the operator's
    pause commands for robot_1 and robot_2 in its own name, and a flood of AON messages
    of its own. The LF mission's result is the true one — every task credited to the
    robot that did it, none paused — and every refusal is counted in the result's live
    report. (Before: the assigner credited robot_1's and robot_2's tasks and both were
    paused; the result said successful with 2 of 7 tasks done.)"""
    from mrcomm.live.identity import live_members
    from mrcomm.messaging.aon_state import TeamIndex
    from mrcomm.messaging.messages import (
        AonEntry,
        AonMsg,
        CommandKind,
        OperatorCommand,
        TaskState,
        TaskStatus,
        encode,
    )
    from mrcomm.messaging.topics import lane_of
    from mrcomm.net.origin_signatures import OriginSigner, pack_signatures
    from mrcomm.net.team_dir import load_team, member_files
    from mrcomm.world.scenario import load_scenario

    scenario = load_scenario(S1)
    team_dir = init_team(tmp_path / "team", live_members(scenario), days=1).path
    config = make_config(None, scenario=S1, behaviour="lf", network="ah", threshold="slt")
    settings = LiveSettings(config, make_options(), tmp_path / "records", speed=20.0)
    stop = threading.Event()
    robots = tuple(r.id for r in scenario.robots)
    team = TeamIndex((*robots, "assigner"))
    commands = TeamIndex((*robots, "assigner", "operator"))
    nothing = team.encode(0)

    def status(robot: str, task: str, seq: int) -> TaskStatus:
        return TaskStatus(sender="robot_3", incarnation=1, seq=seq, stamp=0.0, robot=robot,
                          task_id=task, state=TaskState.SUCCESS)  # fmt: skip

    # It holds robot_3's key: it signs the entries whose origin is robot_3 (those then
    # meet AON's own checks); the others it cannot sign.
    key_files = member_files(load_team(team_dir), "robot_3")
    signer = OriginSigner.from_options(
        make_options(
            tls_ca=key_files.ca,
            tls_cert=key_files.cert,
            tls_key=key_files.key,
            acl_grants=grants(live_members(scenario), scenario),
        )
    )
    assert signer is not None

    def own_signatures(topic: str, message: AonMsg) -> bytes:
        return pack_signatures([
            (e.sender, e.incarnation, e.seq, signer.sign(topic, e))
            for e in message.entries if e.sender == "robot_3"
        ])  # fmt: skip

    def attack(node: ZenohNode) -> None:
        seq = 0
        while not stop.is_set():
            seq += 1
            entries = []
            for robot, task in (("robot_1", "1"), ("robot_2", "2"), ("robot_1", "4")):
                node.put(node.key("robot_3", "task_status"), encode(status(robot, task, seq)),
                         lane_of("task_status"))  # fmt: skip
                entries.append(AonEntry("robot_3", 7, seq, nothing, nothing,
                                        payload=status(robot, task, seq)))  # fmt: skip
                entries.append(AonEntry(robot, 1, seq, nothing, nothing,
                                        payload=status(robot, task, seq)))  # fmt: skip
                forged = TaskStatus(
                    sender=robot,
                    incarnation=1,
                    seq=seq,
                    stamp=0.0,
                    robot=robot,
                    task_id=task,
                    state=TaskState.SUCCESS,
                )
                entries.append(AonEntry(robot, 1, 5000 + seq, nothing, nothing,
                                        payload=forged))  # fmt: skip
            # A flood of its own messages (each with its own new sequence number).
            entries += [
                AonEntry(
                    "robot_3",
                    9,
                    100 * seq + k,
                    nothing,
                    nothing,
                    payload=status("robot_3", f"bogus{seq}-{k}", seq),
                )
                for k in range(20)
            ]
            aon = AonMsg(sender="robot_3", incarnation=7, seq=seq, stamp=0.0,
                         team_crc=team.crc, entries=tuple(entries))  # fmt: skip
            node.put(node.key("robot_3", "aon"), encode(aon), lane_of("aon"),
                     signatures=own_signatures("aon", aon))  # fmt: skip
            # Pauses in its own name, and in the operator's (a consistent forgery: the
            # entry's origin and its payload's sender both say "operator").
            pauses = tuple(
                AonEntry(
                    origin,
                    8,
                    2 * seq + i,
                    commands.encode(0),
                    commands.encode(0),
                    payload=OperatorCommand(
                        sender=origin,
                        incarnation=8,
                        seq=seq,
                        stamp=0.0,
                        command=CommandKind.PAUSE,
                        robot=robot,
                    ),
                )
                for origin in ("robot_3", "operator")
                for i, robot in enumerate(("robot_1", "robot_2"))
            )
            command = AonMsg(sender="robot_3", incarnation=8, seq=seq, stamp=0.0,
                             team_crc=commands.crc, entries=pauses)  # fmt: skip
            node.put(node.key("robot_3", "command"), encode(command), lane_of("command"),
                     signatures=own_signatures("command", command))  # fmt: skip
            stop.wait(0.1)

    result, report = mission_with_rogue(settings, team_dir, attack, stop, knows_mission=True)
    assert report["died"] == []
    mission = result.mission
    assert mission["timed_out"] is False and mission["successful"] is True
    for robot in robots:  # every task credited was done by its robot, none paused
        metrics = result.robots[robot]
        assert metrics["tasks_completed"] == metrics["tasks_assigned"], (robot, metrics)
    refused: dict[str, int] = {}
    for process in report["processes"].values():
        for cause, count in process["refused"].items():
            refused[cause] = refused.get(cause, 0) + count
    assert refused.get("assigner: status of another robot", 0) > 10, refused
    assert refused.get("aon: payload not authored by its origin", 0) > 10, refused
    assert refused.get("aon: origin may not send on this topic", 0) > 10, refused
    # The consistent forgeries (in robot_1's and the operator's names, payload and all)
    # carry no signature of their origin: dropped at the bus edge.
    assert refused.get("unsigned_entry", 0) > 10, refused


def mission_with_rogue(
    settings: LiveSettings,
    team_dir: Path,
    attack: Callable[[ZenohNode], None],
    stop: threading.Event,
    *,
    knows_mission: bool = False,
) -> tuple[Any, dict[str, Any]]:
    """A live mission with a rogue node holding robot_3's certificate running ``attack``
    (until ``stop``) in a thread of its own; ``knows_mission``: it uses the mission's
    identity (as a process reading the traffic could). The mission starts when every
    member is present: robot_3 joins only once the rogue's TLS links to the other
    processes are up, so the attack covers the whole mission however slowly a loaded
    machine starts processes."""
    with LiveTeam(settings, team_dir=team_dir) as t:
        t.start(hold=("robot_3",))
        peers = [f"tls/127.0.0.1:{port}" for port in t.ports.values()]
        rogue = ZenohNode(
            make_options(
                team=settings.zenoh.team, connect=peers, tls_ca=team_dir / "ca.pem",
                tls_cert=team_dir / "robot_3.pem", tls_key=team_dir / "robot_3.key",
            )
        )  # fmt: skip
        if knows_mission:
            assert t.settings.mission is not None
            rogue.mission = bytes.fromhex(t.settings.mission)
        thread = threading.Thread(target=attack, args=(rogue,))
        thread.start()
        try:
            started = len(t.children)
            wait_for(lambda: rogue.peers() >= started, 60, "the rogue's links to the team")
            t.spawn("robot_3")
            t.wait()
        finally:
            stop.set()
            thread.join()
            rogue.close()
        return t.collect()
