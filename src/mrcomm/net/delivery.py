"""The receiver-side delivery policy, one for every bus.

Network perturbations are applied by the *receiving* side, as in the original, so they
behave the same in every mode and every dropped message is counted where it was lost.
For one message reaching one receiver:

1. topics exempt from perturbation (the task assignment) are always received;
2. range: the link from the sender must be connected (the network model's decision);
3. simulated packet loss (SPL X %): on lossy topics the receiver drops X % of the
   messages, one uniform draw per message from its own seeded stream.

The in-process bus (simulation) and the Zenoh bus (live mode) both call
:meth:`DeliveryPolicy.decide` with their receiver's :class:`LossStream` and count with
:class:`TopicCounts`, so they make the same decisions by construction.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from mrcomm.messaging.topics import EXEMPT_TOPICS, LOSSY_TOPICS

RECEIVED = "received"
DROPPED_LOSS = "dropped_loss"
DROPPED_RANGE = "dropped_range"

_UNIFORM_BATCH = 1024


class LossStream:
    """A receiver's stream of uniform draws, refilled in batches (one draw per lossy
    message that was in range)."""

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


@dataclass
class TopicCounts:
    """Message counts of one agent on one topic."""

    sent: int = 0
    received: int = 0
    dropped_loss: int = 0
    dropped_range: int = 0

    def count(self, outcome: str) -> None:
        if outcome == RECEIVED:
            self.received += 1
        elif outcome == DROPPED_LOSS:
            self.dropped_loss += 1
        else:
            self.dropped_range += 1

    def as_dict(self) -> dict[str, int]:
        return {
            "sent": self.sent,
            "received": self.received,
            "dropped_loss": self.dropped_loss,
            "dropped_range": self.dropped_range,
        }


class DeliveryPolicy:
    """Range cut, then SPL loss (see the module docstring)."""

    def __init__(
        self,
        loss_percent: float,
        *,
        lossy_topics: Iterable[str] = LOSSY_TOPICS,
        exempt_topics: Iterable[str] = EXEMPT_TOPICS,
    ) -> None:
        if not 0.0 <= loss_percent <= 100.0:
            raise ValueError("loss_percent must be within 0-100")
        self.loss_percent = loss_percent
        self._loss = loss_percent / 100.0
        self.lossy_topics = frozenset(lossy_topics)
        self.exempt_topics = frozenset(exempt_topics)

    def exempt(self, topic: str) -> bool:
        return topic in self.exempt_topics

    def decide(self, topic: str, connected: bool, stream: LossStream) -> str:
        """The outcome of one message on ``topic`` reaching one receiver, whose link from
        the sender is ``connected``; draws from ``stream`` only when loss applies."""
        if topic in self.exempt_topics:
            return RECEIVED
        if not connected:
            return DROPPED_RANGE
        if self._loss > 0.0 and topic in self.lossy_topics and stream.draw() < self._loss:
            return DROPPED_LOSS
        return RECEIVED
