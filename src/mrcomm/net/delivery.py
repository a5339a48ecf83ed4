"""The receiver-side delivery policy, one for every bus.

Network perturbations are applied by the *receiving* side, as in the original, so they
behave the same in every mode and every dropped message is counted where it was lost.
For one message reaching one receiver:

1. topics exempt from perturbation (the task assignment) are always received;
2. queue: a message the sender's radio queue could not take is lost (``radio`` only);
3. range: the link from the sender must be connected (the network model's decision);
4. radio packet error: lost with the link's packet error rate for the message's size,
   one uniform draw from the receiver's stream (``radio`` only; every topic that is not
   exempt, since the radio does not know topics);
5. simulated packet loss (SPL X %): on lossy topics the receiver drops X % of the
   messages, one uniform draw per message from its own seeded stream.

On the shared channel (simulation only) one draw u per delivery decides all three
(:meth:`DeliveryPolicy.decide_shared`, and for many at once
:meth:`DeliveryPolicy.shared_outcomes`): packet error when u < the error alone, a
collision when u < the error at the SINR (1 for a receiver that was sending or receiving
another frame), else SPL when (u − that) / (1 − that) < X %: the same chances as
separate draws, and a number of draws known before the decisions, so a step's frames
can be decided together.

The in-process bus (simulation) and the Zenoh bus (live mode) both call
:meth:`DeliveryPolicy.decide` with their receiver's :class:`LossStream` and count with
:class:`TopicCounts`, so they make the same decisions by construction.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mrcomm.messaging.topics import EXEMPT_TOPICS, LOSSY_TOPICS

RECEIVED = "received"
DROPPED_LOSS = "dropped_loss"
DROPPED_RANGE = "dropped_range"
DROPPED_RADIO = "dropped_radio"
DROPPED_QUEUE = "dropped_queue"
DROPPED_COLLISION = "dropped_collision"

#: What can become of one message at one receiver (an outcome code is an index here).
OUTCOMES = (
    RECEIVED, DROPPED_LOSS, DROPPED_RANGE, DROPPED_RADIO, DROPPED_QUEUE, DROPPED_COLLISION
)  # fmt: skip
_CODES = np.arange(len(OUTCOMES), dtype=np.int8)
#: The causes of a lost message, as reports name them.
DROP_CAUSES = {
    DROPPED_LOSS: "lost (SPL)",
    DROPPED_RANGE: "out of range",
    DROPPED_RADIO: "packet error (radio)",
    DROPPED_QUEUE: "queue overflow (radio)",
    DROPPED_COLLISION: "collision (shared channel)",
}
#: The message counts of one agent on one topic (the shared channel's last).
COUNT_KEYS = ("sent", RECEIVED, DROPPED_LOSS, DROPPED_RANGE, DROPPED_RADIO, DROPPED_QUEUE)
#: The counts only a radio produces (results of other network models leave them out).
RADIO_COUNT_KEYS = (DROPPED_RADIO, DROPPED_QUEUE)
#: The radio's delay statistics of the received messages.
DELAY_KEYS = ("delay_mean_s", "delay_max_s")
#: What only the shared channel counts: messages lost to collisions at the agent, and
#: the seconds its own messages on the topic took on the air (the channel load).
SHARED_KEYS = (DROPPED_COLLISION, "airtime_s")


def count_keys(radio: bool, shared: bool = False) -> list[str]:
    """The count keys a run's results have: the radio's only when it had a radio, the
    shared channel's collisions only when it had one."""
    keys = [key for key in COUNT_KEYS if radio or key not in RADIO_COUNT_KEYS]
    return [*keys, DROPPED_COLLISION] if shared else keys


def has_radio_counts(counts: Iterable[Mapping[str, float]]) -> bool:
    """Whether per-topic counts come from a run with a radio (they carry its causes)."""
    return any(key in c for c in counts for key in RADIO_COUNT_KEYS)


def has_shared_counts(counts: Iterable[Mapping[str, float]]) -> bool:
    """Whether per-topic counts come from a run on the shared channel."""
    return any(DROPPED_COLLISION in c for c in counts)


_UNIFORM_BATCH = 1024
#: A refill holds at most this many draws (32 kB): a receiver of 10,000 robots' first
#: poses takes ~10,000 at once, and four takes' worth for each of 10,000 receivers was
#: 3.2 GB. A larger take is then served from several refills.
_UNIFORM_MOST = 4096


class LossStream:
    """A receiver's stream of uniform draws, refilled in batches (one draw per lossy
    message that was in range). :meth:`draw` takes the next value, :meth:`take` the next
    ``k`` as an array: the same values in the same order whichever is used, so a bus may
    decide one message at a time or a batch of messages at once."""

    def __init__(self, rng: np.random.Generator) -> None:
        self._rng = rng
        self._array = np.empty(0)
        # The same batch as a list (a faster scalar read), made when draw() first needs
        # it: a stream read only by take() (a large team's poses) never does.
        self._buffer: list[float] | None = []
        self._next = 0

    def _refill(self, wanted: int = 0) -> None:
        # Any batch size gives the same values in the same order (the generator's
        # doubles one after the other; only this stream draws from it). A receiver in a
        # large team takes ~1,000 at a time: its batches hold four takes, so most takes
        # are a slice of one batch rather than a draw and a concatenation.
        self._array = self._rng.random(max(_UNIFORM_BATCH, min(4 * wanted, _UNIFORM_MOST)))
        self._buffer = None
        self._next = 0

    def draw(self) -> float:
        if self._next >= len(self._array):
            self._refill()
        buffer = self._buffer
        if buffer is None:
            buffer = self._buffer = self._array.tolist()
        value = buffer[self._next]
        self._next += 1
        return value

    def take(self, k: int) -> np.ndarray:
        """The next ``k`` draws (as ``k`` calls of :meth:`draw` would give them)."""
        parts = []
        while k > 0:
            if self._next >= len(self._array):
                self._refill(k)
            end = min(len(self._array), self._next + k)
            parts.append(self._array[self._next : end])
            k -= end - self._next
            self._next = end
        if len(parts) == 1:
            return parts[0]
        return np.concatenate(parts) if parts else np.empty(0)


@dataclass
class TopicCounts:
    """Message counts of one agent on one topic, and the radio delay (queue wait plus
    airtime) of the messages it received."""

    sent: int = 0
    received: int = 0
    dropped_loss: int = 0
    dropped_range: int = 0
    dropped_radio: int = 0
    dropped_queue: int = 0
    dropped_collision: int = 0
    airtime_s: float = 0.0
    delay_total: float = 0.0
    delay_max: float = 0.0

    def count(self, outcome: str, delay: float = 0.0) -> None:
        if outcome == RECEIVED:
            self.received += 1
            if delay > 0.0:
                self.delay_total += delay
                self.delay_max = max(self.delay_max, delay)
        elif outcome == DROPPED_LOSS:
            self.dropped_loss += 1
        elif outcome == DROPPED_RANGE:
            self.dropped_range += 1
        elif outcome == DROPPED_RADIO:
            self.dropped_radio += 1
        elif outcome == DROPPED_COLLISION:
            self.dropped_collision += 1
        else:
            self.dropped_queue += 1

    def add(self, *, received: int, dropped_loss: int, dropped_range: int) -> None:
        """Add the outcomes of several messages at once (no radio: no delays, no radio
        causes), as :meth:`count` would one by one."""
        self.received += received
        self.dropped_loss += dropped_loss
        self.dropped_range += dropped_range

    def as_dict(self, radio: bool = False, shared: bool = False) -> dict[str, float]:
        """The counts (:data:`COUNT_KEYS`; without a ``radio``, none of
        :data:`RADIO_COUNT_KEYS`, which are then always 0; on the ``shared`` channel
        also :data:`SHARED_KEYS`)."""
        out: dict[str, float] = {key: getattr(self, key) for key in count_keys(radio)}
        if shared:
            out[DROPPED_COLLISION] = self.dropped_collision
            out["airtime_s"] = round(self.airtime_s, 6)
        return out

    def delays(self) -> dict[str, float]:
        """Mean and largest radio delay of the received messages, s."""
        mean = self.delay_total / self.received if self.received else 0.0
        return {"delay_mean_s": round(mean, 6), "delay_max_s": round(self.delay_max, 6)}


def add_outcomes(
    entries: Sequence[TopicCounts],
    codes: NDArray[np.int8],
    decided: NDArray[np.bool_],
    delays: NDArray[np.float64],
) -> None:
    """Add to ``entries[c]`` the outcomes ``codes[m, c]`` (of :data:`OUTCOMES`) of the
    messages m it ``decided`` (a sender is not its own receiver), with their radio
    ``delays[m]``: the counts, delay sum and largest delay :meth:`TopicCounts.count`
    would give one message at a time. The sum is the same float sum: each column's
    delays added in order from its total (numpy's cumulative sum runs in order; a
    message not received adds 0.0, which changes no sum)."""
    tally = ((codes[:, :, None] == _CODES) & decided[:, :, None]).sum(axis=0).tolist()
    kept = decided & (codes == 0) & (delays[:, None] > 0.0)
    any_kept = kept.any(axis=0)
    totals: list[float] = []
    largest: list[float] = []
    if any_kept.any():
        added = np.where(kept, delays[:, None], 0.0)
        start = np.array([entry.delay_total for entry in entries])[None, :]
        totals = np.cumsum(np.vstack([start, added]), axis=0)[-1].tolist()
        largest = added.max(axis=0).tolist()
    for column, entry in enumerate(entries):
        for outcome, n in zip(OUTCOMES, tally[column], strict=True):
            if n:
                setattr(entry, outcome, getattr(entry, outcome) + n)
        if totals and any_kept[column]:
            entry.delay_total = totals[column]
            entry.delay_max = max(entry.delay_max, largest[column])


class DeliveryPolicy:
    """Range cut, radio packet error, then SPL loss (see the module docstring)."""

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

    def decide(
        self,
        topic: str,
        connected: bool,
        stream: LossStream,
        packet_error: float = 0.0,
    ) -> str:
        """The outcome of one message on ``topic`` reaching one receiver, whose link from
        the sender is ``connected`` and loses this message with probability
        ``packet_error`` (the radio's); draws from ``stream`` only when a loss applies."""
        if topic in self.exempt_topics:
            return RECEIVED
        if not connected:
            return DROPPED_RANGE
        if packet_error > 0.0 and stream.draw() < packet_error:
            return DROPPED_RADIO
        if self._loss > 0.0 and topic in self.lossy_topics and stream.draw() < self._loss:
            return DROPPED_LOSS
        return RECEIVED

    def decide_shared(
        self, topic: str, connected: bool, stream: LossStream, alone: float, shared: float
    ) -> str:
        """The outcome of one frame of the shared channel at one receiver: lost with
        probability ``alone`` to packet error, ``shared`` (at least ``alone``) with the
        other frames on the air; one draw decides these and SPL (module docstring)."""
        if topic in self.exempt_topics:
            return RECEIVED
        if not connected:
            return DROPPED_RANGE
        spl = self._loss > 0.0 and topic in self.lossy_topics
        if shared <= 0.0 and not spl:
            return RECEIVED
        draw = stream.draw()
        if draw < alone:
            return DROPPED_RADIO
        if draw < shared:
            return DROPPED_COLLISION
        if spl and (draw - shared) / (1.0 - shared) < self._loss:
            return DROPPED_LOSS
        return RECEIVED

    def shared_outcomes(
        self,
        topic: str,
        connected: NDArray[np.bool_],
        streams: Sequence[LossStream],
        alone: NDArray[np.float64],
        shared: NDArray[np.float64],
    ) -> NDArray[np.int8]:
        """:meth:`decide_shared` for k frames (rows, in order) at R receivers (columns,
        ``streams`` theirs): the outcome codes (indices of :data:`OUTCOMES`), from the
        same draws in the same order."""
        codes = np.where(connected, 0, OUTCOMES.index(DROPPED_RANGE)).astype(np.int8)
        if topic in self.exempt_topics:
            return np.zeros_like(codes)
        spl = self._loss > 0.0 and topic in self.lossy_topics
        needs = connected & ((shared > 0.0) | spl)
        counts = needs.sum(axis=0).tolist()
        draws = [stream.take(k) for stream, k in zip(streams, counts, strict=True) if k]
        if not draws:
            return codes
        u_t = np.zeros(needs.T.shape)
        u_t[needs.T] = np.concatenate(draws)  # receiver by receiver, frames in order
        u = u_t.T
        radio = needs & (u < alone)
        collision = needs & ~radio & (u < shared)
        codes[radio] = OUTCOMES.index(DROPPED_RADIO)
        codes[collision] = OUTCOMES.index(DROPPED_COLLISION)
        if spl:
            rest = needs & ~radio & ~collision
            with np.errstate(divide="ignore", invalid="ignore"):
                lost = rest & ((u - shared) / (1.0 - shared) < self._loss)
            codes[lost] = OUTCOMES.index(DROPPED_LOSS)
        return codes
