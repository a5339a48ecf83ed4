"""Same traffic, both buses: the delivery decisions of the in-process bus (simulation)
and of the Zenoh bus (live mode) compared message by message.

A simulated mission runs for some steps with observers on its in-process bus: every
message delivered in a step is kept with the nodes' positions at that step, and every
decision (received / dropped by loss / dropped by range) with its receiver. The same
messages are then published, in the same order, through a real Zenoh session on
loopback and handed to a :class:`~mrcomm.net.zenoh_bus.ZenohBus` with one endpoint
per agent (seeded as in the simulation, subscribed to the same topics, positions set to
those of the step). Each message is awaited before the next is sent, so every receiver
sees them in the simulation's order.
"""

from __future__ import annotations

import math
from typing import Any

from mrcomm.messaging.messages import Message
from mrcomm.net.zenoh_bus import LinkRules, PositionBook, ZenohBus, ZenohNode
from mrcomm.net.zenoh_config import make_options
from mrcomm.run.config import RunConfig
from mrcomm.run.resources import ScenarioResources
from mrcomm.run.wiring import build_network
from mrcomm.seeding import stream
from mrcomm.sim.mission import Mission

Decision = tuple[str, str, str, int, str]  # receiver, topic, sender, seq, outcome
#: The nodes' positions at a step, and the (topic, sender, message) it delivered.
Batch = tuple[list[tuple[float, float]], list[tuple[str, str, Message]]]


def record_in_process(
    config: RunConfig, steps: int
) -> tuple[
    Mission, list[tuple[list[tuple[float, float]], list[tuple[str, str, Message]]]], list[Decision]
]:
    """Run ``steps`` steps; return the mission, each step's (positions, messages
    delivered) and the in-process decisions."""
    mission = Mission(config, ScenarioResources.load(config.scenario))
    published: list[tuple[str, str, Message]] = []
    decisions: list[Decision] = []
    mission.network.publish_observer = lambda stamp, topic, sender, message: published.append(
        (topic, sender, message)
    )
    mission.network.observer = lambda now, topic, sender, receiver, message, outcome: (
        decisions.append((receiver, topic, sender, message.seq, outcome))
    )
    batches = []
    for _ in range(steps):
        if mission.done:
            break
        # What this step delivers was published during the previous one.
        positions = mission.bodies.node_positions(mission.bodies.true_xy())
        batches.append((positions, list(published)))
        published.clear()
        mission.step()
    return mission, batches, decisions


def compare_buses(config: RunConfig, steps: int, timeout: float = 5.0) -> int:
    """Number of decisions compared; AssertionError at the first that differs."""
    mission, batches, expected = record_in_process(config, steps)
    ids = mission.node_ids
    node = ZenohNode(make_options(team="conformance", listen=["tcp/127.0.0.1:0"]))
    try:
        book = PositionBook()
        bus = ZenohBus(
            node, LinkRules(network=build_network(config), loss_percent=config.spl), book
        )
        got: list[Decision] = []
        bus.observer = lambda now, topic, sender, receiver, message, outcome: got.append(
            (receiver, topic, sender, message.seq, outcome)
        )
        endpoints = {a: bus.endpoint(a, stream(config.seed, "loss", a)) for a in ids}
        topics = {topic for _, batch in batches for topic, _, _ in batch}
        for topic in sorted(topics):
            for agent in mission.network.subscribers(topic):
                endpoints[agent].subscribe(topic, _ignore)
        for positions, batch in batches:
            book.fixed = {
                a: (x, y) for a, (x, y) in zip(ids, positions, strict=True) if not math.isnan(x)
            }
            for topic, sender, message in batch:
                endpoints[sender].publish(topic, message)
                item = node.poll(timeout)
                assert item is not None, f"the Zenoh session lost a {topic} message"
                bus.handle(item)
    finally:
        node.close()
    for k, (mine, theirs) in enumerate(zip(sorted(expected), sorted(got), strict=False)):
        assert mine == theirs, f"decision {k}: in-process {mine}, Zenoh {theirs}"
    assert len(expected) == len(got), f"{len(expected)} decisions in process, {len(got)} on Zenoh"
    assert expected, "no traffic to compare"
    return len(expected)


def _ignore(message: Any) -> None:
    """Handlers of the replay: only the decisions matter."""
