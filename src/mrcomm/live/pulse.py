"""The ESD pulse as a live process (``mrcomm pulse`` with Zenoh options; issue 7 §2).

A robot's pulse publishes every reading on ``mrcomm/<team>/<robot>-pulse/rssi`` (the
best-effort lane, like pose) through a publish-only Bus endpoint. It is no team member:
it declares no liveliness token and subscribes to nothing of the team. It depends on
no agent either: Zenoh keeps retrying its connections and it publishes whether anyone
listens or not, so it keeps running when its robot's agent crashes, and the restarted
agent gets readings again as soon as its session is back.

It runs on one of two clocks:

* the host's wall clock when it reads the wireless card (``--iface``; a physical
  robot): ``cli.pulse_cmd.run_pulse`` polls at its rate until interrupted;
* the world's shared clock when it replays a recorded trace (``--trace``; ESD in live
  mode on one host): :func:`run_on_shared_clock` steps it on the world's ticks, like
  the agents, and stops with the mission (the world's end tick, or the world's
  liveliness token vanishing).
"""

from __future__ import annotations

import math
import time

from mrcomm.live.protocol import CH_TICK, WORLD_ID, Tick, decoder_of
from mrcomm.live.tick_guard import IMPLAUSIBLE_TICK, TickGuard
from mrcomm.messaging.messages import Message, encode
from mrcomm.messaging.topics import lane_of
from mrcomm.net.pulse import PulseBase
from mrcomm.net.zenoh_node import Presence, ZenohNode
from mrcomm.ports import Handler

#: Wall seconds between checks while no tick arrives (nothing is due meanwhile).
_IDLE_WAIT = 0.5


class PublishingEndpoint:
    """A Bus endpoint that only publishes, under ``mrcomm/<team>/<owner>/<topic>``:
    for a process that is no team member and receives nothing (the ESD pulse). Its
    topics' publishers are declared up front, like every live publisher."""

    def __init__(self, node: ZenohNode, owner: str, topics: tuple[str, ...]) -> None:
        self._node = node
        self._owner = owner
        self.sent: dict[str, int] = dict.fromkeys(topics, 0)
        for topic in topics:
            node.prepare(node.key(owner, topic), lane_of(topic))

    @property
    def owner(self) -> str:
        return self._owner

    def publish(self, topic: str, message: Message) -> None:
        self.sent[topic] = self.sent.get(topic, 0) + 1
        node = self._node
        node.put(node.key(self._owner, topic), encode(message), lane_of(topic))

    def subscribe(self, topic: str, handler: Handler) -> None:
        raise TypeError(f"{self._owner} only publishes (it has no subscriptions)")


def run_on_shared_clock(pulse: PulseBase, clock: ZenohNode, *, count: int | None = None) -> str:
    """Step ``pulse`` on the world's clock ticks (heard on ``clock``'s session) until the
    mission ends, the world goes or ``count`` polls are done; returns why it stopped."""
    clock.listen(f"{clock.prefix}/{WORLD_ID}/{CH_TICK}", CH_TICK, decoder_of(Tick))
    clock.watch_presence(WORLD_ID)
    worlds: set[int] = set()
    guard = TickGuard()
    world_seen = False
    last = -math.inf
    while True:
        item = clock.poll(_IDLE_WAIT)
        if item is None:
            continue
        if item.channel == "presence":
            presence: Presence = item.value
            if presence.alive:
                worlds.add(presence.incarnation)
                world_seen = True
            else:
                worlds.discard(presence.incarnation)
                if world_seen and not worlds:
                    return "the world has gone"
        elif item.channel == CH_TICK:
            tick: Tick = item.value
            if not guard.plausible(tick, time.monotonic()):
                clock.refuse(IMPLAUSIBLE_TICK)
                continue
            if tick.end:
                return "the mission has ended"
            if tick.time < last:
                continue  # a stale tick overtaken by a newer one
            last = tick.time
            pulse.step(tick.time)
            if count is not None and pulse.stats.polls >= count:
                return f"{count} polls done"
