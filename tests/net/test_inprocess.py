"""In-process bus: delivery order, the AH range cut and simulated packet loss."""

import math

import numpy as np
import pytest

from mrcomm.messaging.messages import (
    TOPIC_ASSIGNMENT,
    TOPIC_POSE,
    TOPIC_TASK_STATUS,
    TOPIC_UTILITY,
    Message,
    PoseMsg,
    TaskState,
    TaskStatus,
    UtilityMsg,
)
from mrcomm.net.delivery import DeliveryPolicy
from mrcomm.net.inprocess import InProcessNetwork
from mrcomm.net.links import LinkModel
from mrcomm.net.network import AdHoc, AdHocParams, Wlan
from mrcomm.net.radio.model import RadioNetwork, RadioParams
from mrcomm.net.thresholds import DistanceThreshold, NoThreshold
from mrcomm.seeding import stream
from mrcomm.world.occupancy import OccupancyGrid

IDS = ("a", "b", "c")


def _network(loss: float, seed: int = 0) -> InProcessNetwork:
    return InProcessNetwork(
        IDS, policy=DeliveryPolicy(loss), loss_rngs={i: stream(seed, "loss", i) for i in IDS}
    )


def _pose(sender: str, seq: int) -> PoseMsg:
    return PoseMsg(sender=sender, incarnation=1, seq=seq, stamp=0.0, x=0.0, y=0.0, theta=0.0)


def test_messages_arrive_at_the_next_delivery_in_order_and_not_at_the_sender() -> None:
    net = _network(0.0)
    got: dict[str, list[int]] = {i: [] for i in IDS}
    for i in IDS:
        net.endpoint(i).subscribe(TOPIC_POSE, lambda m, i=i: got[i].append(m.seq))
    a = net.endpoint("a")
    a.publish(TOPIC_POSE, _pose("a", 1))
    a.publish(TOPIC_POSE, _pose("a", 2))
    assert got["b"] == []
    net.deliver(0.1)
    assert got == {"a": [], "b": [1, 2], "c": [1, 2]}
    assert net.pending() == 0


def test_publishing_from_a_handler_waits_for_the_next_delivery() -> None:
    net = _network(0.0)
    b = net.endpoint("b")
    echoes: list[Message] = []
    b.subscribe(
        TOPIC_POSE,
        lambda m: b.publish(
            TOPIC_UTILITY,
            UtilityMsg(sender="b", incarnation=1, seq=m.seq, stamp=0.0, round=0, utility=1.0),
        ),
    )
    net.endpoint("a").subscribe(TOPIC_UTILITY, echoes.append)
    net.endpoint("a").publish(TOPIC_POSE, _pose("a", 7))
    net.deliver(0.0)
    assert echoes == [] and net.pending() == 1
    net.deliver(0.1)
    assert [m.seq for m in echoes] == [7]


@pytest.mark.parametrize("loss", [25.0, 50.0, 75.0])
def test_spl_drops_the_configured_fraction_at_each_receiver(loss: float) -> None:
    net = _network(loss, seed=3)
    received = {i: 0 for i in IDS}
    for i in IDS:
        net.endpoint(i).subscribe(
            TOPIC_POSE, lambda m, i=i: received.__setitem__(i, received[i] + 1)
        )
    n = 4000
    a = net.endpoint("a")
    for k in range(n):
        a.publish(TOPIC_POSE, _pose("a", k))
    net.deliver(0.0)
    p = loss / 100
    sigma = math.sqrt(n * p * (1 - p))
    for receiver in ("b", "c"):
        dropped = net.counts[(receiver, TOPIC_POSE)].dropped_loss
        assert abs(dropped - n * p) < 4 * sigma, (receiver, dropped)
        assert dropped + received[receiver] == n
    # receivers draw independently: their drop patterns differ
    assert (
        net.counts[("b", TOPIC_POSE)].dropped_loss != net.counts[("c", TOPIC_POSE)].dropped_loss
        or loss == 0
    )


def test_spl_is_reproducible_from_the_seed() -> None:
    def drops(seed: int) -> int:
        net = _network(50.0, seed)
        net.endpoint("b").subscribe(TOPIC_POSE, lambda m: None)
        for k in range(500):
            net.endpoint("a").publish(TOPIC_POSE, _pose("a", k))
        net.deliver(0.0)
        return net.counts[("b", TOPIC_POSE)].dropped_loss

    assert drops(1) == drops(1)
    assert drops(1) != drops(2)


def test_assignment_topic_is_never_perturbed() -> None:
    net = _network(100.0)
    got: list[Message] = []
    net.endpoint("b").subscribe(TOPIC_ASSIGNMENT, got.append)
    net.set_connected([[False] * 3 for _ in range(3)])
    net.endpoint("a").publish(TOPIC_ASSIGNMENT, _pose("a", 1))
    net.deliver(0.0)
    assert len(got) == 1


def test_ah_cuts_links_beyond_8_m_and_wlan_does_not() -> None:
    grid = OccupancyGrid(np.zeros((10, 400), dtype=bool), 0.1)
    positions = np.array([[1.0, 0.5], [8.9, 0.5], [9.1, 0.5]])
    ah = LinkModel(IDS, grid, AdHoc(AdHocParams()), NoThreshold()).update(positions, 0.0)
    assert ah.connected[0, 1] and ah.connected[1, 0]  # 7.9 m
    assert not ah.connected[0, 2] and not ah.connected[2, 0]  # 8.1 m
    wlan = LinkModel(IDS, grid, Wlan(), NoThreshold()).update(positions, 0.0)
    assert wlan.connected.all()

    net = _network(0.0)
    got: list[Message] = []
    net.endpoint("c").subscribe(TOPIC_POSE, got.append)
    net.endpoint("b").subscribe(TOPIC_POSE, got.append)
    net.set_connected(ah.connected.tolist())
    net.endpoint("a").publish(TOPIC_POSE, _pose("a", 1))
    net.deliver(0.0)
    assert len(got) == 1  # b only
    assert net.counts[("c", TOPIC_POSE)].dropped_range == 1


def test_virtual_node_is_always_connected_and_slt_warns_beyond_4_m() -> None:
    grid = OccupancyGrid(np.zeros((10, 400), dtype=bool), 0.1)
    positions = np.array([[0.0, 0.5], [4.5, 0.5], [math.nan, math.nan]])
    state = LinkModel(IDS, grid, AdHoc(AdHocParams()), DistanceThreshold(4.0)).update(
        positions, 0.0
    )
    assert state.connected[:, 2].all() and state.connected[2, :].all()
    assert state.warning[0, 1] and state.warning[1, 0]
    assert not state.warning[:, 2].any() and not state.warning.diagonal().any()


def _status(sender: str, seq: int) -> TaskStatus:
    return TaskStatus(
        sender=sender, incarnation=1, seq=seq, stamp=0.0, robot=sender, task_id="t1",
        state=TaskState.SUCCESS,
    )  # fmt: skip


def test_a_mission_waits_for_a_status_in_flight_not_for_a_pose() -> None:
    """Poses are sent on a timer for as long as a robot runs: one in flight must not hold
    a mission's end (with a hundred robots one always is); a status must."""
    net = _network(0.0)
    a = net.endpoint("a")
    a.publish(TOPIC_POSE, _pose("a", 1))
    assert (net.pending(), net.awaited()) == (1, 0)
    a.publish(TOPIC_TASK_STATUS, _status("a", 2))
    assert (net.pending(), net.awaited()) == (2, 1)
    net.deliver(0.1)
    assert (net.pending(), net.awaited()) == (0, 0)


def test_on_the_shared_channel_a_status_on_the_air_is_awaited_until_it_ends() -> None:
    network = RadioNetwork(RadioParams(channel="shared"), seed=1)
    net = InProcessNetwork(
        IDS, policy=DeliveryPolicy(0.0), loss_rngs={i: stream(0, "loss", i) for i in IDS},
        channel=network.channel(IDS),
    )  # fmt: skip
    power = np.full((3, 3), -50.0)
    np.fill_diagonal(power, np.nan)
    assert net.channel is not None
    net.channel.set_links(power, np.ones((3, 3), dtype=np.bool_))
    got: list[Message] = []
    net.endpoint("b").subscribe(TOPIC_TASK_STATUS, got.append)
    # One sender's queue: the pose goes first, then the status (no collision).
    net.endpoint("a").publish(TOPIC_POSE, _pose("a", 1))
    net.endpoint("a").publish(TOPIC_TASK_STATUS, _status("a", 2))
    assert (net.pending(), net.awaited()) == (2, 1)  # submitted to the air
    net.deliver(0.0)  # nothing has ended yet
    assert net.awaited() == 1 and got == []
    net.deliver(1.0)
    assert (net.pending(), net.awaited()) == (0, 0) and len(got) == 1
