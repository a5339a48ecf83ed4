"""Multi-hop relaying on the in-process network: a chain of robots carries a status
end to end, each node gets a message once, the hop limit holds, and it is off unless
asked for."""

from __future__ import annotations

import pytest

from mrcomm.messaging.messages import TOPIC_POSE, TOPIC_TASK_STATUS, PoseMsg, TaskState, TaskStatus
from mrcomm.net.delivery import DeliveryPolicy
from mrcomm.net.inprocess import InProcessNetwork
from mrcomm.net.network import AdHocParams
from mrcomm.net.relay import RelayOptions, make_relay, relay_options
from mrcomm.seeding import stream


def chain(n: int, hops: int) -> tuple[InProcessNetwork, dict[str, list[TaskStatus]]]:
    """``n`` robots in a line, each in range of its neighbours only."""
    ids = tuple(f"r{i}" for i in range(n))
    net = InProcessNetwork(
        ids,
        policy=DeliveryPolicy(0.0),
        loss_rngs={i: stream(0, "loss", i) for i in ids},
        relay=make_relay(ids, n, RelayOptions(hops)),
    )
    net.set_connected([[abs(a - b) <= 1 for b in range(n)] for a in range(n)])
    got: dict[str, list[TaskStatus]] = {i: [] for i in ids}
    for i in ids:
        net.endpoint(i).subscribe(TOPIC_TASK_STATUS, got[i].append)
    return net, got


def status(sender: str) -> TaskStatus:
    return TaskStatus(
        sender=sender, incarnation=1, seq=1, stamp=0.0, robot=sender, task_id="7",
        state=TaskState.SUCCESS,
    )  # fmt: skip


def test_three_robots_in_a_line_carry_a_status_end_to_end_in_two_hops() -> None:
    net, got = chain(3, hops=4)
    message = status("r0")
    net.endpoint("r0").publish(TOPIC_TASK_STATUS, message)
    net.deliver(0.1)  # r1 hears r0; r2 is out of r0's range
    assert got == {"r0": [], "r1": [message], "r2": []}
    net.deliver(0.2)  # r1's copy reaches r2 (and r0, which has it: a duplicate)
    assert got == {"r0": [], "r1": [message], "r2": [message]}
    net.deliver(0.3)  # r2's copy reaches r1, which has it
    assert net.pending() == 0
    stats = net.relay.stats()  # type: ignore[union-attr]
    assert stats["r2"]["hops"] == {"2": 1} and stats["r1"]["hops"] == {"1": 1}
    assert stats["r2"]["received_copies"] == 1
    assert stats["r0"]["duplicates"] == 1 and stats["r1"]["duplicates"] == 1
    assert [stats[i]["passed_on"] for i in ("r0", "r1", "r2")] == [0, 1, 1]
    # Copies are counted by the relay, not as receptions of the original publication.
    assert net.counts[("r1", TOPIC_TASK_STATUS)].received == 1
    r2 = net.counts[("r2", TOPIC_TASK_STATUS)]
    assert (r2.received, r2.dropped_range) == (0, 1)  # the original never reached it


def test_the_hop_limit_stops_a_long_chain() -> None:
    net, got = chain(5, hops=2)
    net.endpoint("r0").publish(TOPIC_TASK_STATUS, status("r0"))
    for k in range(6):
        net.deliver(0.1 * (k + 1))
    assert [len(got[f"r{i}"]) for i in range(5)] == [0, 1, 1, 0, 0]


def test_every_node_gets_each_message_once_in_a_dense_team() -> None:
    ids = tuple(f"r{i}" for i in range(6))
    net = InProcessNetwork(
        ids, policy=DeliveryPolicy(0.0), loss_rngs={i: stream(0, "loss", i) for i in ids},
        relay=make_relay(ids, 6, RelayOptions(6)),
    )  # fmt: skip
    got: dict[str, list[TaskStatus]] = {i: [] for i in ids}
    for i in ids:
        net.endpoint(i).subscribe(TOPIC_TASK_STATUS, got[i].append)
    for sender in ids:
        net.endpoint(sender).publish(TOPIC_TASK_STATUS, status(sender))
    for k in range(8):
        net.deliver(0.1 * (k + 1))
    for i in ids:  # everyone in range of everyone: 5 statuses each, none twice
        assert sorted(m.sender for m in got[i]) == sorted(s for s in ids if s != i)


def test_poses_are_not_relayed_and_relaying_is_off_by_default() -> None:
    net, _ = chain(3, hops=4)
    poses: list[PoseMsg] = []
    net.endpoint("r2").subscribe(TOPIC_POSE, poses.append)
    net.endpoint("r0").publish(
        TOPIC_POSE, PoseMsg(sender="r0", incarnation=1, seq=1, stamp=0.0, x=0, y=0, theta=0)
    )
    net.deliver(0.1)
    net.deliver(0.2)
    assert poses == [] and net.pending() == 0
    assert relay_options(AdHocParams()) == RelayOptions(0, False)
    assert relay_options(AdHocParams(relay=True, relay_hops=3)) == RelayOptions(3, False)
    both = AdHocParams(relay=True, relay_store=True)
    assert relay_options(both) == RelayOptions(4, True)
    assert relay_options(AdHocParams(relay_store=True)) == RelayOptions(0, False)  # no relay
    assert make_relay(("a", "b"), 2, RelayOptions()) is None
    with pytest.raises(ValueError):
        AdHocParams(relay=True, relay_hops=1)


# -- store and forward ----------------------------------------------------------------


def alone(n: int, hops: int, store: bool) -> tuple[InProcessNetwork, dict[str, list[TaskStatus]]]:
    """``n`` robots nobody can hear (every link down)."""
    ids = tuple(f"r{i}" for i in range(n))
    net = InProcessNetwork(
        ids,
        policy=DeliveryPolicy(0.0),
        loss_rngs={i: stream(0, "loss", i) for i in ids},
        relay=make_relay(ids, n, RelayOptions(hops, store)),
    )
    net.set_connected([[a == b for b in range(n)] for a in range(n)])
    got: dict[str, list[TaskStatus]] = {i: [] for i in ids}
    for i in ids:
        net.endpoint(i).subscribe(TOPIC_TASK_STATUS, got[i].append)
    return net, got


def link(net: InProcessNetwork, n: int, *pairs: tuple[int, int]) -> None:
    up = {frozenset(p) for p in pairs}
    net.set_connected([[a == b or frozenset((a, b)) in up for b in range(n)] for a in range(n)])


@pytest.mark.parametrize("store", [False, True])
def test_a_status_published_out_of_range_travels_only_when_stored(store: bool) -> None:
    net, got = alone(3, hops=4, store=store)
    message = status("r0")
    net.endpoint("r0").publish(TOPIC_TASK_STATUS, message)
    net.deliver(0.1)  # nobody hears it
    assert got == {"r0": [], "r1": [], "r2": []}
    link(net, 3, (0, 1))  # r1 comes into r0's range
    net.deliver(0.2)
    link(net, 3, (1, 2))  # r1 leaves r0 and meets r2
    net.deliver(0.3)
    net.deliver(0.4)
    if not store:  # relaying alone passes on only what it hears as it is sent
        assert got == {"r0": [], "r1": [], "r2": []}
        return
    assert got == {"r0": [], "r1": [message], "r2": [message]}  # once each
    stats = net.relay.stats()  # type: ignore[union-attr]
    assert stats["r1"]["hops"] == {"1": 1} and stats["r2"]["hops"] == {"2": 1}


def test_stored_copies_respect_the_hop_limit_and_aon_is_not_stored() -> None:
    net, got = alone(4, hops=2, store=True)
    net.endpoint("r0").publish(TOPIC_TASK_STATUS, status("r0"))
    net.deliver(0.1)
    for t, pair in enumerate([(0, 1), (1, 2), (2, 3)]):
        link(net, 4, pair)
        net.deliver(0.2 + t / 10)
    assert [len(got[i]) for i in ("r1", "r2", "r3")] == [1, 1, 0]  # r3 is 3 links away
    store = net.relay.store  # type: ignore[union-attr]
    assert store is not None
    assert all(topic == TOPIC_TASK_STATUS for kept in store for topic, _, _ in kept.values())
