"""Same traffic, both buses: the delivery decisions of the in-process bus (simulation)
and of the Zenoh bus (live mode) compared message by message.

A simulated mission runs for some steps with observers on its in-process bus: every
message delivered in a step is kept with the nodes' positions at that step, and every
decision (received / dropped by loss / dropped by range) with its receiver. The same
messages are then published, in the same order, through a real Zenoh session on
loopback and handed to a :class:`~mrcomm.net.zenoh_bus.ZenohBus` with one endpoint
per agent (seeded as in the simulation, subscribed to the same topics, positions set to
those of the step). Each message is awaited before the next is sent, so every receiver
sees them in the simulation's order. With the radio each is queued by its sender at the
time it was published in the simulation, and one the radio delays beyond the next step
is held and judged at the step it is due, as in the simulation.
"""

from __future__ import annotations

import math
from typing import Any

from mrcomm.messaging.messages import Message
from mrcomm.net.zenoh_bus import LinkRules, PositionBook, ZenohBus
from mrcomm.net.zenoh_config import make_options
from mrcomm.net.zenoh_node import ZenohNode
from mrcomm.run.config import RunConfig
from mrcomm.run.resources import ScenarioResources
from mrcomm.run.wiring import build_network, build_radio_links, build_relay_options
from mrcomm.seeding import stream
from mrcomm.sim.mission import Mission

Decision = tuple[str, str, str, int, str]  # receiver, topic, sender, seq, outcome
#: A step's time and the nodes' positions then, and the (topic, sender, message)
#: published during the step before (delivered at this one, or later with a radio).
Batch = tuple[float, list[tuple[float, float]], list[tuple[str, str, Message]]]


def record_in_process(config: RunConfig, steps: int) -> tuple[Mission, list[Batch], list[Decision]]:
    """Run ``steps`` steps; return the mission, each step's batch and the in-process
    decisions."""
    mission = Mission(config, ScenarioResources.load(config.scenario))
    published: list[tuple[str, str, Message]] = []
    decisions: list[Decision] = []
    mission.network.publish_observer = lambda stamp, topic, sender, message: published.append(
        (topic, sender, message)
    )
    mission.network.observer = lambda now, topic, sender, receiver, message, outcome: (
        decisions.append((receiver, topic, sender, message.seq, outcome))
    )
    batches: list[Batch] = []
    for _ in range(steps):
        if mission.done:
            break
        # What this step delivers was published during the previous one.
        positions = mission.bodies.node_positions(mission.bodies.true_xy())
        batches.append((mission.now, positions, list(published)))
        published.clear()
        mission.step()
    return mission, batches, decisions


def compare_buses(config: RunConfig, steps: int, timeout: float = 5.0) -> int:
    """Number of decisions compared; AssertionError at the first that differs."""
    return len(compare_decisions(config, steps, timeout))


def compare_decisions(config: RunConfig, steps: int, timeout: float = 5.0) -> list[Decision]:
    """The decisions of both buses, identical (AssertionError at the first that
    differs), in the in-process bus's order."""
    mission, batches, expected = record_in_process(config, steps)
    ids = mission.node_ids
    resources = ScenarioResources.load(config.scenario)
    node = ZenohNode(make_options(team="conformance", listen=["tcp/127.0.0.1:0"]))
    try:
        book = PositionBook()
        network = build_network(config, resources)
        radio = build_radio_links(config, resources, network)
        hops = build_relay_options(config).hops
        rules = LinkRules(network=network, loss_percent=config.spl, radio=radio, relay_hops=hops)
        bus = ZenohBus(node, rules, book)
        got: list[Decision] = []
        bus.observer = lambda now, topic, sender, receiver, message, outcome: got.append(
            (receiver, topic, sender, message.seq, outcome)
        )
        endpoints = {a: bus.endpoint(a, stream(config.seed, "loss", a)) for a in ids}
        topics = {topic for _, _, batch in batches for topic, _, _ in batch}
        for topic in sorted(topics):
            for agent in mission.network.subscribers(topic):
                endpoints[agent].subscribe(topic, _ignore)
        published_at = 0.0
        for now, positions, batch in batches:
            book.fixed = {
                a: (x, y) for a, (x, y) in zip(ids, positions, strict=True) if not math.isnan(x)
            }
            bus.release(now)  # messages on the air due now, before this step's
            for topic, sender, message in batch:
                bus.now = published_at  # the sender's radio queues it when it was sent
                endpoints[sender].publish(topic, message)
                item = node.poll(timeout)
                assert item is not None, f"the Zenoh session lost a {topic} message"
                bus.now = now
                bus.handle(item)
            published_at = now
    finally:
        node.close()
    for k, (mine, theirs) in enumerate(zip(sorted(expected), sorted(got), strict=False)):
        assert mine == theirs, f"decision {k}: in-process {mine}, Zenoh {theirs}"
    assert len(expected) == len(got), f"{len(expected)} decisions in process, {len(got)} on Zenoh"
    assert expected, "no traffic to compare"
    return expected


def _ignore(message: Any) -> None:
    """Handlers of the replay: only the decisions matter."""
