"""The in-process bus of the ``sim`` mode.

Every agent gets an endpoint implementing the :class:`~mrcomm.ports.Bus` port. Messages
published during one simulation step are delivered at the start of the next, in publish
order. Network effects are applied by the *receiving* side, as in the original and as in
live mode, so every dropped message is counted where it was lost:

1. range: the link between sender and receiver must be connected (AH range limit);
2. simulated packet loss (SPL X %): each receiver drops X % of the messages on lossy
   topics, independently, from its own seeded random stream.

Topics in ``exempt_topics`` (the task assignment: all agents start with perfect
communication) are never perturbed.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from mrcomm.messaging.messages import LOSSY_TOPICS, TOPIC_ASSIGNMENT, Message
from mrcomm.ports import Handler

#: Observer of every delivery decision: (now, topic, sender, receiver, message, outcome)
#: with outcome "received" | "dropped_loss" | "dropped_range". Used by recordings.
DeliveryObserver = Callable[[float, str, str, str, Message, str], None]

#: Observer of every publication: (stamp, topic, sender, message).
PublishObserver = Callable[[float, str, str, Message], None]

_UNIFORM_BATCH = 1024


@dataclass
class TopicCounts:
    """Message counts of one agent on one topic."""

    sent: int = 0
    received: int = 0
    dropped_loss: int = 0
    dropped_range: int = 0

    def as_dict(self) -> dict[str, int]:
        return {
            "sent": self.sent,
            "received": self.received,
            "dropped_loss": self.dropped_loss,
            "dropped_range": self.dropped_range,
        }


class _LossStream:
    """A receiver's stream of uniform draws, refilled in batches (one draw per message)."""

    def __init__(self, rng: np.random.Generator) -> None:
        self._rng = rng
        self._buffer: list[float] = []
        self._next = 0

    def draw(self) -> float:
        if self._next >= len(self._buffer):
            self._buffer = self._rng.random(_UNIFORM_BATCH).tolist()
            self._next = 0
        value = self._buffer[self._next]
        self._next += 1
        return value


class InProcessEndpoint:
    """One agent's endpoint on the in-process network (implements the Bus port)."""

    def __init__(self, network: InProcessNetwork, owner: str, index: int) -> None:
        self._network = network
        self._owner = owner
        self._index = index

    @property
    def owner(self) -> str:
        return self._owner

    def publish(self, topic: str, message: Message) -> None:
        self._network._publish(self._index, topic, message)

    def subscribe(self, topic: str, handler: Handler) -> None:
        self._network._subscribe(self._index, topic, handler)


class InProcessNetwork:
    """Delivers messages between the endpoints of one simulated team."""

    def __init__(
        self,
        agent_ids: Sequence[str],
        *,
        loss_percent: float,
        loss_rngs: Mapping[str, np.random.Generator],
        lossy_topics: Iterable[str] = LOSSY_TOPICS,
        exempt_topics: Iterable[str] = (TOPIC_ASSIGNMENT,),
    ) -> None:
        if not 0.0 <= loss_percent <= 100.0:
            raise ValueError("loss_percent must be within 0-100")
        self.ids: tuple[str, ...] = tuple(agent_ids)
        self._loss = loss_percent / 100.0
        self._lossy = frozenset(lossy_topics)
        self._exempt = frozenset(exempt_topics)
        self._streams = [_LossStream(loss_rngs[a]) for a in self.ids]
        # topic -> receiver index -> handlers
        self._subs: dict[str, dict[int, list[Handler]]] = {}
        self._outbox: list[tuple[int, str, Message]] = []
        n = len(self.ids)
        self._connected: list[list[bool]] = [[True] * n for _ in range(n)]
        self.counts: dict[tuple[str, str], TopicCounts] = {}
        self.observer: DeliveryObserver | None = None
        self.publish_observer: PublishObserver | None = None
        self._now = 0.0

    def endpoint(self, agent_id: str) -> InProcessEndpoint:
        return InProcessEndpoint(self, agent_id, self.ids.index(agent_id))

    def set_connected(self, connected: list[list[bool]]) -> None:
        """Link matrix for this step: ``connected[s][r]`` (sender s can reach receiver r)."""
        self._connected = connected

    def pending(self) -> int:
        """Messages waiting for the next delivery."""
        return len(self._outbox)

    def deliver(self, now: float) -> None:
        """Deliver everything published since the last call. Messages published by
        handlers during delivery wait for the next call."""
        self._now = now
        outbox, self._outbox = self._outbox, []
        for sender, topic, message in outbox:
            receivers = self._subs.get(topic)
            if not receivers:
                continue
            exempt = topic in self._exempt
            lossy = (not exempt) and self._loss > 0.0 and topic in self._lossy
            links = self._connected[sender]
            for receiver, handlers in receivers.items():
                if receiver == sender:
                    continue
                outcome = "received"
                if not exempt and not links[receiver]:
                    outcome = "dropped_range"
                elif lossy and self._streams[receiver].draw() < self._loss:
                    outcome = "dropped_loss"
                counts = self._count(receiver, topic)
                if outcome == "received":
                    counts.received += 1
                elif outcome == "dropped_loss":
                    counts.dropped_loss += 1
                else:
                    counts.dropped_range += 1
                if self.observer is not None:
                    self.observer(
                        now, topic, self.ids[sender], self.ids[receiver], message, outcome
                    )
                if outcome == "received":
                    for handler in handlers:
                        handler(message)

    # -- endpoint plumbing ---------------------------------------------------------
    def _publish(self, sender: int, topic: str, message: Message) -> None:
        self._count(sender, topic).sent += 1
        self._outbox.append((sender, topic, message))
        if self.publish_observer is not None:
            self.publish_observer(message.stamp, topic, self.ids[sender], message)

    def _subscribe(self, receiver: int, topic: str, handler: Handler) -> None:
        self._subs.setdefault(topic, {}).setdefault(receiver, []).append(handler)

    def _count(self, index: int, topic: str) -> TopicCounts:
        key = (self.ids[index], topic)
        counts = self.counts.get(key)
        if counts is None:
            counts = self.counts[key] = TopicCounts()
        return counts

    def counts_by_topic(self) -> dict[str, dict[str, int]]:
        """Totals per topic over all agents."""
        totals: dict[str, TopicCounts] = {}
        for (_, topic), c in self.counts.items():
            t = totals.setdefault(topic, TopicCounts())
            t.sent += c.sent
            t.received += c.received
            t.dropped_loss += c.dropped_loss
            t.dropped_range += c.dropped_range
        return {topic: c.as_dict() for topic, c in sorted(totals.items())}

    def counts_by_agent(self) -> dict[str, dict[str, dict[str, int]]]:
        """agent -> topic -> counts."""
        out: dict[str, dict[str, dict[str, int]]] = {}
        for (agent, topic), c in sorted(self.counts.items()):
            out.setdefault(agent, {})[topic] = c.as_dict()
        return out
