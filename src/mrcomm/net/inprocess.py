"""The in-process bus of the ``sim`` mode.

Every agent gets an endpoint implementing the :class:`~mrcomm.ports.Bus` port. Messages
published during one simulation step are delivered at the start of the next, in publish
order. Whether each reaches each receiver is decided on the receiving side by the run's
:class:`~mrcomm.net.delivery.DeliveryPolicy` (range cut from the step's link matrix,
then simulated packet loss from the receiver's own seeded stream), the same policy the
Zenoh bus applies in live mode.

With a radio (:class:`~mrcomm.net.radio.channel.RadioChannel`) a message also queues at
its sender and is delivered at the first step at or after its publication plus its
delay (wait + airtime; within one step for light traffic), or is lost to the queue, and
each receiver may lose it to packet error. On the shared channel
(:mod:`mrcomm.net.radio.medium`) the senders contend for the air: each delivery first
runs the channel up to ``now`` and delivers the frames that ended, topic by topic in the
order they ended, each receiver losing a frame also to collisions.

With relaying on (:mod:`mrcomm.net.relay`), a robot that receives a task status or AON
message first passes a copy on at the next delivery; copies are counted by the relay,
not as publications.

In a large team most messages are poses, each reaching every mate. A run of consecutive
messages on one topic is then decided as a batch — the step's link matrix gathered for
all of them at once, each receiver's loss draws taken as an array from its own stream
(the same values in the same order as one draw per message), the counts added per
receiver — and the handlers are called in the same order as one message at a time
would call them, so the results are the same either way; a
:class:`~mrcomm.ports.BatchHandler` (a robot hearing its mates' poses) is given each
receiver's messages of the batch in one call, as its share (:class:`~mrcomm.ports.Received`)
of the step's :class:`~mrcomm.ports.StepBatch`, whose arrays are made once for all.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from mrcomm.messaging.latest import KEEP_LATEST_FROM, LatestMessages, bounded_blocks
from mrcomm.messaging.messages import Message
from mrcomm.messaging.topics import PERIODIC_TOPICS
from mrcomm.net.delivery import (
    DROPPED_QUEUE,
    RECEIVED,
    DeliveryPolicy,
    LossStream,
    TopicCounts,
    add_outcomes,
)
from mrcomm.net.handover import Takers, hand_over
from mrcomm.net.radio.channel import RadioChannel
from mrcomm.net.radio.medium import Frame
from mrcomm.net.relay import Relay
from mrcomm.ports import Handler, KeepLatest, StepBatch

#: A message on its way: sender index, topic, message, due time, radio delay (None:
#: lost to the sender's queue), bits on the air, links it crossed before this send (0:
#: an original publication), whether it is a relayed copy (a robot's own status sent
#: again from its store is a copy that crossed no link before), and on the shared
#: channel its frame (who was blocked, the interference each receiver had).
_Queued = tuple[int, str, Message, float, float | None, int, int, bool, Frame | None]

#: Observer of every delivery decision: (now, topic, sender, receiver, message, outcome)
#: with outcome one of :data:`~mrcomm.net.delivery.OUTCOMES`. Used by recordings.
DeliveryObserver = Callable[[float, str, str, str, Message, str], None]

#: Observer of every publication: (stamp, topic, sender, message).
PublishObserver = Callable[[float, str, str, Message], None]

#: Messages on one topic are decided as a batch when they have at least this many
#: receivers (below it, numpy's per-call cost exceeds what a batch saves).
BATCH_FROM = 8


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
        policy: DeliveryPolicy,
        loss_rngs: Mapping[str, np.random.Generator],
        channel: RadioChannel | None = None,
        relay: Relay | None = None,
    ) -> None:
        self.ids: tuple[str, ...] = tuple(agent_ids)
        # The endpoints' names and numbers as step batches hand them to receivers.
        self._members = np.array(self.ids, dtype=object)
        self._numbers = {agent: i for i, agent in enumerate(self.ids)}
        self.policy = policy
        self.channel = channel
        self.relay = relay
        self._streams = [LossStream(loss_rngs[a]) for a in self.ids]
        # topic -> receiver index -> handlers
        self._subs: dict[str, dict[int, list[Handler]]] = {}
        self._takers: dict[str, Takers] = {}  # each topic's, made on its first batch
        # topic -> the latest messages the bus keeps for its KeepLatest receivers
        self._latest: dict[str, LatestMessages] = {}
        self._outbox: list[_Queued] = []
        #: Frames of topics other than the periodic ones on the shared channel (submitted,
        #: not yet ended or dropped): what :meth:`awaited` counts there.
        self._awaited_on_air = 0
        n = len(self.ids)
        self._links = np.ones((n, n), dtype=bool)
        self._rows: list[list[bool]] | None = None  # the same matrix as lists, on demand
        #: Receivers from which a topic's messages are decided as a batch.
        self.batch_from = BATCH_FROM
        self.counts: dict[tuple[str, str], TopicCounts] = {}
        # The same counts by topic and receiver index, for the delivery loop (created on
        # first use, as in ``counts``: an agent never reached on a topic has no entry).
        self._counts_by_index: dict[str, list[TopicCounts | None]] = {}
        self.observer: DeliveryObserver | None = None
        self.publish_observer: PublishObserver | None = None
        self._now = 0.0

    def endpoint(self, agent_id: str) -> InProcessEndpoint:
        return InProcessEndpoint(self, agent_id, self.ids.index(agent_id))

    def set_connected(self, connected: np.ndarray | list[list[bool]]) -> None:
        """Link matrix for this step: ``connected[s][r]`` (sender s can reach receiver r).
        With store and forward, a robot that gains a neighbour sends its stored statuses
        again (delivered with this step's messages)."""
        links = np.asarray(connected, dtype=bool)  # a new matrix each step: no copy
        rows: list[list[bool]] | None = None
        relay = self.relay
        if relay is not None and relay.store is not None:
            rows = links.tolist()
            for relayer, topic, message, crossed in relay.on_links(self._connected(), rows):
                self._enqueue(relayer, topic, message, crossed, copy=True)
        self._links = links
        self._rows = rows

    def _connected(self) -> list[list[bool]]:
        """This step's link matrix as lists (a faster read one element at a time)."""
        if self._rows is None:
            self._rows = self._links.tolist()
        return self._rows

    def subscribers(self, topic: str) -> list[str]:
        """The agents subscribed to ``topic``, in subscription order."""
        return [self.ids[i] for i in self._subs.get(topic, {})]

    def pending(self) -> int:
        """Messages waiting for the next delivery (or on the shared channel)."""
        medium = self.channel.medium if self.channel is not None else None
        return len(self._outbox) + (medium.pending() if medium is not None else 0)

    def awaited(self) -> int:
        """Messages waiting (as :meth:`pending`) other than the periodic ones (poses,
        presence, RSSI readings): what a mission whose agents are all done still waits
        for. With a hundred robots publishing poses at staggered instants a pose is in
        flight at the end of every step, so waiting for none would never end."""
        queued = sum(1 for m in self._outbox if m[1] not in PERIODIC_TOPICS)
        return queued + self._awaited_on_air

    def deliver(self, now: float) -> None:
        """Deliver everything published since the last call (with a radio: everything
        due by ``now``). Messages published by handlers during delivery wait for the
        next call."""
        self._now = now
        outbox, self._outbox = self._outbox, []
        medium = self.channel.medium if self.channel is not None else None
        if medium is not None:
            # The step's frames topic by topic (in the order each topic's first frame
            # ended, each topic's in the order they ended): runs of one topic are
            # decided together.
            ended = self._ended(medium.advance(now))
            order = {topic: k for k, topic in enumerate(dict.fromkeys(m[1] for m in ended))}
            outbox = [*outbox, *sorted(ended, key=lambda m: order[m[1]])]
        elif self.channel is not None:
            due = [m for m in outbox if m[3] <= now + 1e-9]
            self._outbox = [m for m in outbox if m[3] > now + 1e-9]
            outbox = due
        decide = self.policy.decide
        streams = self._streams
        channel = self.channel
        exempt = self.policy.exempt
        observer = self.observer
        relay = self.relay
        copies: list[tuple[int, str, Message, int]] = []
        batching = channel is None and observer is None
        position = 0
        while position < len(outbox):
            sender, topic, message, _, delay, bits, crossed, copy, frame = outbox[position]
            position += 1
            receivers = self._subs.get(topic)
            if not receivers:
                continue
            relayed = relay is not None and relay.relays(topic)
            many = len(receivers) >= self.batch_from
            if frame is not None and many and not relayed and observer is None:
                frames = [frame]
                end = position
                while end < len(outbox) and outbox[end][1] == topic:
                    following = outbox[end][8]
                    if following is None:  # dropped from its queue: decided alone
                        break
                    frames.append(following)
                    end += 1
                messages = [message] + [queued[2] for queued in outbox[position:end]]
                self._deliver_frames(topic, frames, messages, receivers)
                position = end
                continue
            if batching and not relayed and len(receivers) >= self.batch_from:
                end = position
                while end < len(outbox) and outbox[end][1] == topic:
                    end += 1
                batch = [sender] + [queued[0] for queued in outbox[position:end]]
                messages = [message] + [queued[2] for queued in outbox[position:end]]
                self._deliver_batch(topic, batch, messages, receivers)
                position = end
                continue
            counts = self._topic_counts(topic)
            latest = self._latest.get(topic)
            links = self._connected()[sender]
            # Per message, not per receiver: lost to the sender's queue, and its delay.
            queued_out = delay is None and not exempt(topic)
            delay_s = delay or 0.0
            if frame is not None:  # the shared channel: this frame at every receiver
                assert channel is not None
                targets = np.fromiter(receivers, dtype=np.intp, count=len(receivers))
                judged = None
                if channel.fades:
                    # Fading is drawn for the receivers in range of a topic that can be
                    # lost.
                    reach = self._links[sender, targets] & (targets != sender)
                    judged = reach & (not exempt(topic))
                errors = channel.frame_errors(frame, targets, judged)
                alone, shared = errors[0].tolist(), errors[1].tolist()
            for column, (receiver, handlers) in enumerate(receivers.items()):
                if receiver == sender:
                    continue
                if queued_out:
                    outcome = DROPPED_QUEUE
                elif frame is not None:
                    outcome = self.policy.decide_shared(
                        topic, links[receiver], streams[receiver], alone[column], shared[column]
                    )
                else:  # (on the shared channel: an exempt frame its queue dropped)
                    per = (
                        channel.packet_error(sender, receiver, bits)
                        if channel is not None and medium is None and links[receiver]
                        else 0.0
                    )
                    outcome = decide(topic, links[receiver], streams[receiver], per)
                if not copy:  # relayed copies are counted by the relay
                    entry = counts[receiver]
                    if entry is None:
                        entry = counts[receiver] = self._count(receiver, topic)
                    entry.count(outcome, delay_s)
                if observer is not None:
                    observer(now, topic, self.ids[sender], self.ids[receiver], message, outcome)
                if outcome == RECEIVED:
                    if relayed:
                        assert relay is not None
                        hop = crossed + 1
                        if not relay.receive(receiver, topic, message, hop, copy):
                            continue  # a duplicate copy
                        if relay.passes_on(receiver, hop):
                            copies.append((receiver, topic, message, hop))
                    if latest is not None and latest.keeps[receiver]:
                        latest.write(receiver, sender, message, now)
                    for handler in handlers:
                        handler(message)
        for relayer, topic, message, crossed in copies:
            self._enqueue(relayer, topic, message, crossed, copy=True)

    def _deliver_batch(
        self,
        topic: str,
        senders: list[int],
        messages: list[Message],
        receivers: dict[int, list[Handler]],
    ) -> None:
        """Decide and deliver consecutive messages on ``topic`` (none relayed, no radio,
        no observer) together: the same decisions, counts and handler calls, in the same
        order, as one message at a time (see the module docstring)."""
        takers = self._takers.get(topic)
        if takers is None:
            takers = self._takers[topic] = Takers.of(receivers, self._latest.get(topic))
        targets = takers.targets
        rows = np.array(senders, dtype=np.intp)
        # Receivers a block at a time (each decides alone, from its own stream, in
        # target order): a large team's step keeps small arrays (bounded_blocks).
        blocks = list(bounded_blocks(len(targets), len(rows)))
        if len(blocks) == 1:  # (every team but the largest: no copy)
            received, decided, reached_n, received_n = self._decide_block(topic, rows, targets)
        else:
            received = np.empty((len(rows), len(targets)), dtype=np.bool_)
            decided, reached_n, received_n = [], [], []
            for block in blocks:
                part, decided_part, reached_part, received_part = self._decide_block(
                    topic, rows, targets[block]
                )
                received[:, block] = part
                decided += decided_part
                reached_n += reached_part
                received_n += received_part
        counts = self._topic_counts(topic)
        for column, receiver in enumerate(targets):
            if not decided[column]:
                continue
            entry = counts[receiver]
            if entry is None:
                entry = counts[receiver] = self._count(receiver, topic)
            entry.add(
                received=received_n[column],
                dropped_loss=reached_n[column] - received_n[column],
                dropped_range=decided[column] - reached_n[column],
            )
        self._hand_over(topic, takers, rows, messages, received, received_n)

    def _decide_block(
        self, topic: str, rows: NDArray[np.intp], targets: list[int]
    ) -> tuple[NDArray[np.bool_], list[int], list[int], list[int]]:
        """Which of a batch's messages (sent by ``rows``) reach each of ``targets``:
        the mask (messages × targets) and, per target, how many messages it decided,
        had in range and received."""
        columns = np.array(targets)
        others = rows[:, None] != columns[None, :]  # a sender does not hear itself
        exempt = self.policy.exempt(topic)
        in_range = others if exempt else self._links[rows[:, None], columns[None, :]] & others
        received = in_range
        decided = others.sum(axis=0).tolist()
        reached_n = decided if exempt else in_range.sum(axis=0).tolist()
        loss = self.policy.loss_percent / 100.0
        if not exempt and loss > 0.0 and topic in self.policy.lossy_topics:
            # Each receiver draws one number per message in range, in message order:
            # receiver by receiver, as the transposed mask lists them.
            streams = self._streams
            draws = [
                streams[receiver].take(k)
                for receiver, k in zip(targets, reached_n, strict=True)
                if k
            ]
            if draws:
                kept = in_range.T.copy()
                kept[in_range.T] = np.concatenate(draws) >= loss
                received = kept.T
        # (A mask that lost nothing has the counts already taken.)
        received_n = reached_n if received is in_range else received.sum(axis=0).tolist()
        return received, decided, reached_n, received_n

    def _hand_over(
        self,
        topic: str,
        takers: Takers,
        rows: NDArray[np.intp],
        messages: list[Message],
        received: NDArray[np.bool_],
        received_n: list[int] | None = None,
    ) -> None:
        """Hand a batch to its receivers (:func:`~mrcomm.net.handover.hand_over`):
        ``received[m, c]`` says whether the receiver of column c (of
        ``takers.targets``) got message m (sent by ``rows[m]``)."""
        batch = StepBatch(messages, rows, self._members, self._numbers)
        hand_over(takers, batch, received, received_n, self._latest.get(topic), self._now)

    # -- endpoint plumbing ---------------------------------------------------------
    def _publish(self, sender: int, topic: str, message: Message) -> None:
        self._count(sender, topic).sent += 1
        if self.relay is not None and self.relay.relays(topic):
            self.relay.published(sender, topic, message)
        self._enqueue(sender, topic, message, 0, copy=False)
        if self.publish_observer is not None:
            self.publish_observer(message.stamp, topic, self.ids[sender], message)

    def _enqueue(self, sender: int, topic: str, message: Message, crossed: int, copy: bool) -> None:
        """Put a message (or a relayed copy) on its way from ``sender``."""
        channel = self.channel
        if channel is None:
            self._outbox.append((sender, topic, message, 0.0, 0.0, 0, crossed, copy, None))
        elif channel.medium is not None:
            if topic not in PERIODIC_TOPICS:
                self._awaited_on_air += 1
            channel.medium.submit(
                sender, self._now, channel.bits(message), (topic, message, crossed, copy)
            )
        else:
            bits = channel.bits(message)
            delay = channel.transmit(sender, self._now, bits)
            due = self._now + (delay or 0.0)
            self._outbox.append((sender, topic, message, due, delay, bits, crossed, copy, None))

    def _ended(self, frames: list[Frame]) -> list[_Queued]:
        """The shared channel's finished frames as messages to deliver now (a dropped
        frame has no delay: lost to its sender's queue); each sent frame's airtime is
        counted for its sender and topic."""
        out: list[_Queued] = []
        for frame in frames:
            topic, message, crossed, copy = frame.token
            if topic not in PERIODIC_TOPICS:
                self._awaited_on_air -= 1
            if frame.dropped:
                out.append((frame.sender, topic, message, frame.end, None, frame.bits,
                            crossed, copy, None))  # fmt: skip
                continue
            self._count(frame.sender, topic).airtime_s += frame.airtime
            out.append((frame.sender, topic, message, frame.end, frame.delay, frame.bits,
                        crossed, copy, frame))  # fmt: skip
        return out

    def _deliver_frames(
        self,
        topic: str,
        frames: list[Frame],
        messages: list[Message],
        receivers: dict[int, list[Handler]],
    ) -> None:
        """Decide and deliver consecutive frames of the shared channel on ``topic``
        (none relayed, so none a copy; no observer) together: the same errors, draws,
        decisions, counts and handler calls, in the same order, as one at a time."""
        takers = self._takers.get(topic)
        if takers is None:
            takers = self._takers[topic] = Takers.of(receivers, self._latest.get(topic))
        targets = np.array(takers.targets, dtype=np.intp)
        rows = np.array([f.sender for f in frames], dtype=np.intp)
        others = rows[:, None] != targets[None, :]
        connected = self._links[rows[:, None], targets[None, :]] & others
        assert self.channel is not None
        judged = connected & (not self.policy.exempt(topic))  # as one frame at a time
        errors = [self.channel.frame_errors(f, targets, judged[k]) for k, f in enumerate(frames)]
        alone = np.array([e[0] for e in errors])
        shared = np.array([e[1] for e in errors])
        streams = [self._streams[r] for r in takers.targets]
        codes = self.policy.shared_outcomes(topic, connected, streams, alone, shared)
        received = (codes == 0) & others
        delays = np.array([f.delay for f in frames])
        counts = self._topic_counts(topic)
        deciding = others.any(axis=0).tolist()
        columns = [column for column, decides in enumerate(deciding) if decides]
        entries = []
        for column in columns:
            receiver = takers.targets[column]
            entry = counts[receiver]
            if entry is None:
                entry = counts[receiver] = self._count(receiver, topic)
            entries.append(entry)
        add_outcomes(entries, codes[:, columns], others[:, columns], delays)
        self._hand_over(topic, takers, rows, messages, received)

    def _subscribe(self, receiver: int, topic: str, handler: Handler) -> None:
        handlers = self._subs.setdefault(topic, {}).setdefault(receiver, [])
        self._takers.pop(topic, None)
        if isinstance(handler, KeepLatest) and len(self.ids) >= KEEP_LATEST_FROM:
            # Kept by the bus: the receiver reads its row; the handler is never called.
            latest = self._latest.get(topic)
            if latest is None:
                latest = LatestMessages(self._members, self._numbers, handler.fields)
                self._latest[topic] = latest
            if latest.fields != handler.fields:
                raise ValueError(f"{topic}: kept with fields {latest.fields}, not {handler.fields}")
            latest.keeps[receiver] = True
            handler.attach(latest, receiver)
            return
        handlers.append(handler)

    def _topic_counts(self, topic: str) -> list[TopicCounts | None]:
        """``topic``'s counts by receiver index (an entry made on a receiver's first
        delivery decision, as in ``counts``)."""
        counts = self._counts_by_index.get(topic)
        if counts is None:
            counts = self._counts_by_index[topic] = [None] * len(self.ids)
        return counts

    def _count(self, index: int, topic: str) -> TopicCounts:
        key = (self.ids[index], topic)
        counts = self.counts.get(key)
        if counts is None:
            counts = self.counts[key] = TopicCounts()
        return counts

    def counts_by_agent(self) -> dict[str, dict[str, dict[str, float]]]:
        """agent -> topic -> counts (and, with a radio, the delays of what it received)."""
        out: dict[str, dict[str, dict[str, float]]] = {}
        radio = self.channel is not None
        shared = radio and self.channel.medium is not None  # type: ignore[union-attr]
        for (agent, topic), c in sorted(self.counts.items()):
            entry: dict[str, float] = dict(c.as_dict(radio, shared))
            if radio:
                entry.update(c.delays())
            out.setdefault(agent, {})[topic] = entry
        return out
