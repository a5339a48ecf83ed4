"""A fake lossy network for protocol tests, driven in simulated time.

Endpoints implement the :class:`~mrcomm.ports.Bus` port. Every publication is put
through the real wire encoding, then, per receiver: dropped if either end is cut off
(a member isolated, or one link down) at publish or delivery time, dropped with
probability ``loss``, otherwise delivered after a random delay of 1..``max_delay``
steps (so copies overtake each other), and duplicated with probability ``dup``.
All randomness comes from one seeded numpy Generator, so a case reruns exactly from
its seed. Like the simulator, ``tick`` delivers first, then steps the agents.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from mrcomm.messaging.messages import Message, decode, encode
from mrcomm.ports import Handler


@dataclass(frozen=True)
class Cut:
    """``a`` cannot talk with ``b`` (or with anyone when ``b`` is None) in [start, end);
    with ``inbound_only`` only what ``a`` would receive is cut."""

    a: str
    b: str | None
    start: float
    end: float
    inbound_only: bool = False

    def blocks(self, sender: str, receiver: str, t: float) -> bool:
        if not self.start <= t < self.end:
            return False
        if self.inbound_only:
            return receiver == self.a and self.b in (None, sender)
        if self.b is None:
            return self.a in (sender, receiver)
        return {sender, receiver} == {self.a, self.b}


class FakeBus:
    """One member's endpoint on the fake network."""

    def __init__(self, net: FakeNet, owner: str) -> None:
        self._net = net
        self._owner = owner
        self.handlers: dict[str, list[Handler]] = defaultdict(list)

    @property
    def owner(self) -> str:
        return self._owner

    def publish(self, topic: str, message: Message) -> None:
        self._net.publish(self._owner, topic, message)

    def subscribe(self, topic: str, handler: Handler) -> None:
        self.handlers[topic].append(handler)

    def reset(self) -> None:
        """Forget every subscription (the member's process restarted)."""
        self.handlers.clear()


@dataclass
class NetCounts:
    published: dict[str, int] = field(default_factory=lambda: defaultdict(int))
    delivered: int = 0
    dropped: int = 0
    duplicated: int = 0


class FakeNet:
    """Members, links and a delivery queue in simulated time (``dt`` per tick)."""

    def __init__(
        self,
        members: Sequence[str],
        seed: int,
        *,
        loss: float = 0.0,
        dup: float = 0.0,
        max_delay: int = 1,
        dt: float = 0.1,
        cuts: Sequence[Cut] = (),
    ) -> None:
        self.members = tuple(members)
        self.rng = np.random.default_rng(seed)
        self.loss = loss
        self.dup = dup
        self.max_delay = max_delay
        self.dt = dt
        self.cuts = list(cuts)
        self.buses = {m: FakeBus(self, m) for m in self.members}
        self.steppers: list[Callable[[float], None]] = []
        self.k = 0
        self._queue: dict[int, list[tuple[str, str, str, Message]]] = defaultdict(list)
        self.counts = NetCounts()
        #: Every publication as (time, sender, topic, message), when ``record`` is set.
        self.record = False
        self.log: list[tuple[float, str, str, Message]] = []

    @property
    def now(self) -> float:
        return self.k * self.dt

    def blocked(self, sender: str, receiver: str, t: float) -> bool:
        return any(c.blocks(sender, receiver, t) for c in self.cuts)

    def heal_time(self) -> float:
        """When the last cut ends."""
        return max((c.end for c in self.cuts), default=0.0)

    def publish(self, sender: str, topic: str, message: Message) -> None:
        self.counts.published[sender] += 1
        # Round-trip through the wire format: what arrives is what was decoded.
        wire = decode(encode(message))
        if self.record:
            self.log.append((self.now, sender, topic, wire))
        for receiver in self.members:
            if receiver == sender or topic not in self.buses[receiver].handlers:
                continue
            copies = 2 if self.rng.random() < self.dup else 1
            self.counts.duplicated += copies - 1
            for _ in range(copies):
                if self.blocked(sender, receiver, self.now) or self.rng.random() < self.loss:
                    self.counts.dropped += 1
                    continue
                at = self.k + int(self.rng.integers(1, self.max_delay + 1))
                self._queue[at].append((sender, receiver, topic, wire))

    def tick(self) -> None:
        """Advance one step: deliver what is due (shuffled), then step every agent."""
        self.k += 1
        now = self.now
        due = self._queue.pop(self.k, [])
        if len(due) > 1:
            due = [due[i] for i in self.rng.permutation(len(due))]
        for sender, receiver, topic, message in due:
            if self.blocked(sender, receiver, now):
                self.counts.dropped += 1
                continue
            self.counts.delivered += 1
            for handler in self.buses[receiver].handlers[topic]:
                handler(message)
        for step in self.steppers:
            step(now)

    def in_flight(self) -> int:
        return sum(len(v) for v in self._queue.values())

    def run(self, until: float, stop: Callable[[], bool] | None = None) -> None:
        """Tick until ``until`` (simulated seconds) or until ``stop()`` is true."""
        while self.now < until - 1e-9:
            self.tick()
            if stop is not None and stop():
                return
