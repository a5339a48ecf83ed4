"""The Bus port over Zenoh: key space, lanes, receiver-side perturbations as in the
in-process bus, liveliness discovery. Real Zenoh peers on loopback."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from mrcomm.messaging.messages import (
    TOPIC_ASSIGNMENT,
    TOPIC_POSE,
    TOPIC_RELAYED,
    TOPIC_TASK_STATUS,
    Assignment,
    Message,
    PoseMsg,
    RelayedMsg,
    TaskState,
    TaskStatus,
    encode,
)
from mrcomm.messaging.topics import Lane, lane_of
from mrcomm.net.delivery import DeliveryPolicy
from mrcomm.net.inprocess import InProcessNetwork
from mrcomm.net.network import AdHoc, AdHocParams
from mrcomm.net.zenoh_bus import LinkRules, PositionBook, ZenohBus
from mrcomm.net.zenoh_node import Presence
from mrcomm.run.assemble import sum_counts
from mrcomm.seeding import stream

from .helpers import drain, mesh_options, nodes, wait_for


def pose(sender: str, seq: int, x: float, y: float = 0.0) -> PoseMsg:
    return PoseMsg(sender=sender, incarnation=1, seq=seq, stamp=0.0, x=x, y=y, theta=0.0)


def status(sender: str, seq: int) -> TaskStatus:
    return TaskStatus(
        sender=sender,
        incarnation=1,
        seq=seq,
        stamp=0.0,
        robot=sender,
        task_id=str(seq),
        state=TaskState.SUCCESS,
    )


def pump(bus: ZenohBus, got: list[Message], count: int, timeout: float = 10.0) -> None:
    """Feed the bus until ``count`` messages were handed to handlers."""

    def step() -> bool:
        item = bus.node.poll(0.05)
        if item is not None and item.channel == "bus":
            bus.handle(item)
        return len(got) >= count

    wait_for(step, timeout, f"{count} messages")


def test_lanes_keep_status_reliable_and_separate_from_pose() -> None:
    assert lane_of(TOPIC_POSE) is Lane.BEST_EFFORT
    assert lane_of(TOPIC_TASK_STATUS) is Lane.STATUS
    assert lane_of("aon") is Lane.STATUS
    assert lane_of(TOPIC_ASSIGNMENT) is Lane.CONTROL


def test_messages_reach_remote_and_local_endpoints_but_not_their_sender() -> None:
    with nodes(mesh_options(2)) as (a, b):
        bus_a = ZenohBus(a, LinkRules(), PositionBook())
        bus_b = ZenohBus(b, LinkRules(), PositionBook())
        r1 = bus_a.endpoint("robot_1", stream(1, "loss", "robot_1"))
        r2 = bus_b.endpoint("robot_2", stream(1, "loss", "robot_2"))
        assigner = bus_b.endpoint("assigner", stream(1, "loss", "assigner"))
        got_r1: list[Message] = []
        got_r2: list[Message] = []
        got_as: list[Message] = []
        r1.subscribe(TOPIC_TASK_STATUS, got_r1.append)
        r2.subscribe(TOPIC_TASK_STATUS, got_r2.append)
        assigner.subscribe(TOPIC_TASK_STATUS, got_as.append)
        wait_for(lambda: a.peers() and b.peers(), 10, "the peers to connect")
        # Declarations travel too: publish until the remote subscription has arrived.
        r2.publish(TOPIC_TASK_STATUS, status("robot_2", 1))
        pump(bus_b, got_as, 1)  # same process, other agent: delivered locally
        wait_for(lambda: _publish_until(r2, bus_a, got_r1), 10, "remote delivery")
        assert all(m.sender == "robot_2" for m in got_r1 + got_as)
        assert got_r2 == []  # never to itself
        assert r2.counts[TOPIC_TASK_STATUS].received == 0
        assert assigner.counts[TOPIC_TASK_STATUS].received >= 1


def _publish_until(sender, bus, got) -> bool:  # type: ignore[no-untyped-def]
    sender.publish(TOPIC_TASK_STATUS, status(sender.owner, 99))
    item = bus.node.poll(0.1)
    while item is not None:
        if item.channel == "bus":
            bus.handle(item)
        item = bus.node.poll(None)
    return bool(got)


def test_loss_draws_match_the_in_process_bus_exactly() -> None:
    """Same seed, same receiver stream: the same messages are dropped as in sim."""
    n = 200
    with nodes(mesh_options(1)) as (node,):
        bus = ZenohBus(node, LinkRules(loss_percent=50.0), PositionBook())
        sender = bus.endpoint("robot_1", stream(7, "loss", "robot_1"))
        receiver = bus.endpoint("robot_2", stream(7, "loss", "robot_2"))
        got: list[Message] = []
        receiver.subscribe(TOPIC_POSE, got.append)
        wait_for(lambda: _pose_until_first(sender, bus, receiver), 10, "the subscription")
        first = _seen(receiver)
        for seq in range(n):
            sender.publish(TOPIC_POSE, pose("robot_1", 1000 + seq, 0.0))
        wait_for(lambda: _handle_all(bus) or _seen(receiver) >= first + n, 10, "every pose")
        _handle_all(bus, 0.2)  # a probe still in flight counts before the batch
        offset = _seen(receiver) - n  # probes (seq 0) drew first, in publish order
    # The in-process bus with the same receiver stream decides the same way.
    ref = InProcessNetwork(
        ["robot_1", "robot_2"],
        policy=DeliveryPolicy(50.0),
        loss_rngs={a: stream(7, "loss", a) for a in ("robot_1", "robot_2")},
    )
    ref_got: list[Message] = []
    ref.endpoint("robot_2").subscribe(TOPIC_POSE, ref_got.append)
    for seq in range(offset + n):
        ref.endpoint("robot_1").publish(TOPIC_POSE, pose("robot_1", seq, 0.0))
    ref.deliver(0.0)
    kept_live = [m.seq - 1000 for m in got if m.seq >= 1000]
    kept_ref = [m.seq - offset for m in ref_got if m.seq >= offset]
    assert kept_live == kept_ref
    assert 0.35 < len(kept_live) / n < 0.65


def _pose_until_first(sender, bus, receiver) -> bool:  # type: ignore[no-untyped-def]
    sender.publish(TOPIC_POSE, pose("robot_1", 0, 0.0))
    _handle_all(bus, 0.05)
    return _seen(receiver) > 0


def _handle_all(bus: ZenohBus, wait: float | None = 0.05) -> bool:
    item = bus.node.poll(wait)
    while item is not None:
        if item.channel == "bus":
            bus.handle(item)
        item = bus.node.poll(None)
    return False


def _seen(endpoint) -> int:  # type: ignore[no-untyped-def]
    c = endpoint.counts.get(TOPIC_POSE)
    return 0 if c is None else c.received + c.dropped_loss + c.dropped_range


def test_ad_hoc_range_cut_uses_poses_seen_on_the_wire() -> None:
    """AH: a sender believed beyond 8 m is cut, all its topics but the assignment;
    it is heard again as soon as its poses show it back in range."""
    with nodes(mesh_options(1)) as (node,):
        own = {"xy": (0.0, 0.0)}
        book = PositionBook(fixed={"station": (100.0, 0.0)})
        book.own["robot_2"] = lambda: own["xy"]
        bus = ZenohBus(node, LinkRules(network=AdHoc(AdHocParams())), book)
        far = bus.endpoint("robot_1", stream(1, "loss", "robot_1"))
        me = bus.endpoint("robot_2", stream(1, "loss", "robot_2"))
        station = bus.endpoint("station", stream(1, "loss", "station"))
        got: list[Message] = []
        me.subscribe(TOPIC_POSE, lambda m: None)
        for topic in (TOPIC_TASK_STATUS, TOPIC_ASSIGNMENT):
            me.subscribe(topic, got.append)
        wait_for(lambda: _pose_until_first(far, bus, me), 10, "the subscription")
        far.publish(TOPIC_POSE, pose("robot_1", 1, 9.0))  # now believed 9 m away
        wait_for(
            lambda: _handle_all(bus) or book.heard.get("robot_1") == (9.0, 0.0), 5, "the far pose"
        )
        far.publish(TOPIC_TASK_STATUS, status("robot_1", 2))
        far.publish(
            TOPIC_ASSIGNMENT,
            Assignment(
                sender="robot_1",
                incarnation=1,
                seq=3,
                stamp=0.0,
                robot="robot_2",
                tasks=(),
                team=(),
            ),
        )
        station.publish(TOPIC_TASK_STATUS, status("station", 1))  # fixed at 100 m
        wait_for(
            lambda: _handle_all(bus) or _cut(me) >= 2,
            5,
            "the range cut",
        )
        wait_for(lambda: _handle_all(bus) or got, 5, "the exempt assignment")
        assert [type(m) for m in got] == [Assignment]
        own["xy"] = (8.5, 0.0)  # we drove towards it: 0.5 m apart
        far.publish(TOPIC_TASK_STATUS, status("robot_1", 4))
        wait_for(lambda: _handle_all(bus) or len(got) >= 2, 5, "the status in range")
        assert isinstance(got[-1], TaskStatus) and got[-1].seq == 4


def _cut(endpoint) -> int:  # type: ignore[no-untyped-def]
    c = endpoint.counts.get(TOPIC_TASK_STATUS)
    return 0 if c is None else c.dropped_range


def test_presence_reports_members_appearing_and_disappearing() -> None:
    with nodes(mesh_options(2)) as (a, b):
        a.watch_presence()
        b.declare_alive("robot_2", 42)
        items = drain(a, lambda xs: any(x.channel == "presence" for x in xs), 10)
        assert Presence("robot_2", 42, True) in [x.value for x in items]
        assert wait_for(lambda: a.present("robot_2"), 10, "the liveliness query") == [42]
        b.close()
        items = drain(
            a, lambda xs: any(x.channel == "presence" and not x.value.alive for x in xs), 10
        )
        assert Presence("robot_2", 42, False) in [x.value for x in items]


def test_a_blocked_status_put_never_stalls_pose_or_the_caller() -> None:
    with nodes(mesh_options(2)) as (a, b):
        bus_b = ZenohBus(b, LinkRules(), PositionBook())
        got: list[Message] = []
        bus_b.endpoint("robot_2", stream(1, "loss", "robot_2")).subscribe(TOPIC_POSE, got.append)
        sender = ZenohBus(a, LinkRules(), PositionBook()).endpoint(
            "robot_1", np.random.default_rng()
        )
        wait_for(lambda: a.peers(), 10, "the peers to connect")
        release = threading.Event()
        publisher = a._publisher(a.key("robot_1", TOPIC_TASK_STATUS), Lane.STATUS)

        class Blocked:
            def put(self, data: bytes, attachment: bytes) -> None:
                release.wait(10)  # the status lane is stuck (congested peer)
                publisher.put(data, attachment=attachment)

        a._publishers[(a.key("robot_1", TOPIC_TASK_STATUS), Lane.STATUS)] = Blocked()
        sender.publish(TOPIC_TASK_STATUS, status("robot_1", 1))  # returns at once
        wait_for(lambda: _pose_and_handle(sender, bus_b, got), 10, "poses past the block")
        release.set()
    assert got and all(isinstance(m, PoseMsg) for m in got)


def _pose_and_handle(sender, bus, got) -> bool:  # type: ignore[no-untyped-def]
    sender.publish(TOPIC_POSE, pose("robot_1", 5, 1.0))
    _handle_all(bus)
    return bool(got)


def test_counts_add_up_over_agents() -> None:
    a = {"pose": {"sent": 2, "received": 1, "dropped_loss": 1, "dropped_range": 0}}
    b = {"pose": {"sent": 1, "received": 2, "dropped_loss": 0, "dropped_range": 3}}
    assert sum_counts([a, b]) == {
        "pose": {"sent": 3, "received": 3, "dropped_loss": 1, "dropped_range": 3}
    }


def test_rules_reject_impossible_loss() -> None:
    with pytest.raises(ValueError):
        LinkRules(loss_percent=120.0)


def test_the_edge_refuses_what_no_agent_should_see() -> None:
    """A rogue peer's samples — a heartbeat on a pose key (the message that used to
    kill every agent), a pose claiming another sender, a pose from a non-member,
    bytes that decode to nothing, an oversized payload — are counted by cause and never
    reach a handler; the team's own poses still do."""
    from mrcomm.messaging.messages import Heartbeat, encode
    from mrcomm.net.zenoh_node import MAX_SAMPLE_BYTES

    with nodes(mesh_options(2)) as (rogue, node):
        bus = ZenohBus(node, LinkRules(), PositionBook(), members=frozenset({"robot_1", "robot_2"}))
        me = bus.endpoint("robot_2", stream(1, "loss", "robot_2"))
        mate = ZenohBus(rogue, LinkRules(), PositionBook()).endpoint(
            "robot_1", stream(1, "loss", "robot_1")
        )
        got: list[Message] = []
        me.subscribe(TOPIC_POSE, got.append)
        wait_for(lambda: rogue.peers() and node.peers(), 10, "the peers to connect")
        wait_for(lambda: _publish_pose_until(mate, bus, got), 10, "the mate's pose")
        got.clear()
        lane = lane_of(TOPIC_POSE)
        beat = Heartbeat(sender="evil", incarnation=1, seq=1, stamp=0.0)
        bad = [
            (rogue.key("evil", TOPIC_POSE), encode(beat)),  # wrong type
            (rogue.key("evil", TOPIC_POSE), encode(pose("robot_1", 7, 1.0))),  # forged
            (rogue.key("evil", TOPIC_POSE), encode(pose("evil", 8, 1.0))),  # not a member
            (rogue.key("robot_1", TOPIC_POSE), b"\xc1\xff not msgpack"),  # undecodable
            (rogue.key("robot_1", TOPIC_POSE), b"\x00" * (MAX_SAMPLE_BYTES + 1)),  # oversized
        ]
        expected = {
            "wrong_type": 1,
            "forged_sender": 1,
            "not_member": 1,
            "undecodable": 1,
            "oversized": 1,
        }

        def all_refused() -> bool:
            for key, data in bad:
                rogue.put(key, data, lane)
            _handle_all(bus, 0.1)
            return all(node.refused.get(c, 0) >= n for c, n in expected.items())

        wait_for(all_refused, 10, "every bad sample refused")
        mate.publish(TOPIC_POSE, pose("robot_1", 99, 2.0))
        wait_for(lambda: _handle_all(bus) or any(m.seq == 99 for m in got), 5, "a good pose")
    assert all(isinstance(m, PoseMsg) and m.sender == "robot_1" for m in got)
    assert set(node.refused) == set(expected)


def _publish_pose_until(sender, bus, got) -> bool:  # type: ignore[no-untyped-def]
    sender.publish(TOPIC_POSE, pose(sender.owner, 1, 0.0))
    _handle_all(bus, 0.1)
    return bool(got)


def test_relayed_copies_are_unwrapped_once_and_bad_ones_refused() -> None:
    def wrap(inner: object, topic: str = TOPIC_TASK_STATUS, hop: int = 2) -> RelayedMsg:
        payload = inner if isinstance(inner, bytes) else encode(inner)  # type: ignore[arg-type]
        return RelayedMsg(sender="robot_1", incarnation=1, seq=1, stamp=0.0, topic=topic,
                          hop=hop, payload=payload)  # fmt: skip

    relaying = LinkRules(network=AdHoc(AdHocParams()), relay_hops=4)
    members = frozenset({"robot_1", "robot_2", "robot_3", "assigner"})
    with nodes(mesh_options(1)) as (node,):
        bus = ZenohBus(node, relaying, PositionBook(), members=members,
                       robots=("robot_1", "robot_2", "robot_3"))  # fmt: skip
        relayer = bus.endpoint("robot_1", stream(1, "loss", "robot_1"))
        receiver = bus.endpoint("robot_2", stream(1, "loss", "robot_2"))
        got: list[Message] = []
        receiver.subscribe(TOPIC_TASK_STATUS, got.append)
        for bad in (
            wrap(status("intruder", 1)),  # not a team member
            wrap(pose("robot_3", 1, 0.0)),  # a pose under a status topic
            wrap(pose("robot_3", 1, 0.0), topic=TOPIC_POSE),  # poses are not relayed
            wrap(b"\x93garbage"),  # not a message
            wrap(status("robot_3", 1), hop=1),  # a copy has crossed at least 2 links
        ):
            relayer._put(TOPIC_RELAYED, bad)
        good = wrap(status("robot_3", 7))
        relayer._put(TOPIC_RELAYED, good)
        relayer._put(TOPIC_RELAYED, good)  # the same copy again: a duplicate
        wait_for(lambda: _pump_all(bus) and node.refused.get("bad_relay", 0) >= 5 and got,
                 10, "the copies")  # fmt: skip
        _pump_all(bus)
        assert node.refused["bad_relay"] == 5
        assert got == [status("robot_3", 7)]
        stats = bus.relay_stats()["robot_2"]
        assert stats["received_copies"] == 1 and stats["duplicates"] == 1
        # robot_2 received it first after 2 links and passes it on (hop limit 4).
        assert stats["passed_on"] == 1 and stats["hops"] == {"2": 1}


def _pump_all(bus: ZenohBus) -> bool:
    item = bus.node.poll(0.05)
    while item is not None:
        if item.channel == "bus":
            bus.handle(item)
        item = bus.node.poll(None)
    return True


def test_messages_of_another_mission_are_refused() -> None:
    """Every sample carries its mission's identity: statuses recorded in one mission
    and replayed into the next (or a member of another run on the same team name) are
    refused and counted; the mission's own still arrive."""
    with nodes(mesh_options(3)) as (old, replay, node):
        node.mission = b"mission2"
        old.mission = replay.mission = b"mission1"
        bus = ZenohBus(node, LinkRules(), PositionBook())
        me = bus.endpoint("robot_2", stream(1, "loss", "robot_2"))
        got: list[Message] = []
        me.subscribe(TOPIC_POSE, got.append)
        mate = ZenohBus(replay, LinkRules(), PositionBook()).endpoint(
            "robot_1", stream(1, "loss", "robot_1")
        )
        wait_for(lambda: replay.peers() and node.peers(), 10, "the peers to connect")
        sent = iter(range(1000))

        def replayed() -> int:  # one more at a time: until the links carry them
            mate.publish(TOPIC_POSE, pose("robot_1", next(sent), 1.0))
            return drain_into(bus)

        wait_for(lambda: replayed() >= 20, 10, "the replayed poses")
        assert got == [] and set(node.refused) == {"other_mission"}
        replay.mission = b"mission2"  # now in this mission
        wait_for(lambda: _publish_pose_until(mate, bus, got), 10, "the mate's pose")
        assert got


def drain_into(bus: ZenohBus) -> int:
    """Hand the bus what reached its node; the number refused so far."""
    while (item := bus.node.poll(0.05)) is not None:
        if item.channel == "bus":
            bus.handle(item)
    return sum(bus.node.refused.values())
