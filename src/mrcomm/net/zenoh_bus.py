"""The Bus port over Eclipse Zenoh (live mode, DESIGN ``live``; issue 7 §1), on each
process's session (:class:`~mrcomm.net.zenoh_node.ZenohNode`).

:class:`ZenohBus` applies the receiver-side perturbations exactly as the in-process
bus does (``net.inprocess``), on the agent thread, and counts every decision:

1. range (AH): the receiver's own position (from its base) against the sender's last
   position, known from the pose messages seen on the wire — *all* of them, also those
   the emulated network then cut, as a radio would still hear a robot come back into
   range. A node without a position (virtual assigner) is always in range; with the
   radio, the radio's range, packet error and the sender's queue
   (:mod:`mrcomm.net.radio.links`);
2. simulated packet loss SPL X %, drawn from the receiver's own seeded stream.

Each :class:`ZenohEndpoint` is one agent's endpoint (the Bus port); a process may host
several (a robot and the task assigner it hosts).

**Relaying** (the network model's ``relay`` option) follows the simulation's rules
(:mod:`mrcomm.net.relay`, the same :class:`~mrcomm.net.relay.Relay` bookkeeping): a
robot's endpoint that receives a task status or AON message first passes on a copy at
once, wrapped in a :class:`~mrcomm.messaging.messages.RelayedMsg` under its own key (the
access control lets a member publish under its own keys only), with the links the copy
will have crossed; receivers judge the copy on the relaying robot's link, unwrap it, drop
it if they had the message (a duplicate), and hand it to the agent as the original
sender's. The relaying robot vouches for the copy: the origin inside it is not bound to
a certificate (with relaying on, a team member can pass on messages in another's name).

**The edge validates.** Nothing a peer sends is raised into an agent: the session
refuses oversized and undecodable samples; :meth:`ZenohBus.handle` drops a message of
another type than its topic carries (:data:`~mrcomm.messaging.topics.TOPICS`), whose
``sender`` is not the agent whose key it came under, or from an agent that is not a
team member. Every refusal is counted by cause
(:data:`~mrcomm.net.zenoh_node.REFUSALS`; the journal's ``refused`` lines,
``mrcomm live --json`` under ``live.processes.<agent>.refused``).
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import msgspec
import numpy as np

from mrcomm.messaging.messages import (
    TOPIC_RELAYED,
    Message,
    PoseMsg,
    RelayedMsg,
    decode,
    encode,
)
from mrcomm.messaging.topics import AGENT_TOPICS, TOPICS, lane_of
from mrcomm.net.delivery import (
    DROPPED_QUEUE,
    RECEIVED,
    DeliveryPolicy,
    LossStream,
    TopicCounts,
)
from mrcomm.net.inprocess import DeliveryObserver
from mrcomm.net.network import NetworkModel, Wlan
from mrcomm.net.origin_signatures import RELAY_SIGNED_TOPICS, SIGNED_TOPICS, OriginSigner
from mrcomm.net.radio.links import RadioLinks
from mrcomm.net.relay import RELAYED_TOPICS, Relay
from mrcomm.net.zenoh_node import Airtime, Incoming, ZenohNode
from mrcomm.ports import Handler

Point = tuple[float, float]
#: A received message's radio facts: (mission time its sender published it, its delay in
#: the sender's queue — NaN: lost there —, its bits on the air).
OnAir = tuple[float, float, int]
#: Slack on due times (s): a message due at the current tick is handed over at it.
_DUE_SLACK = 1e-9


def _arrival(held: tuple[float, int, Any, str, str, Message, OnAir]) -> int:
    return held[1]


# ----------------------------------------------------------------------------- the bus


@dataclass(frozen=True)
class LinkRules:
    """The receiver-side network model of a run, as in simulation: the network model's
    range cut and the delivery policy (:mod:`mrcomm.net.delivery`); with the ``radio``
    network model, the radio's links (range from received power, packet error, the
    senders' queues) in place of the range cut."""

    network: NetworkModel = field(default_factory=Wlan)
    loss_percent: float = 0.0
    radio: RadioLinks | None = None
    #: The hop limit of relaying (0: the robots relay nothing).
    relay_hops: int = 0
    policy: DeliveryPolicy = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "policy", DeliveryPolicy(self.loss_percent))


@dataclass
class PositionBook:
    """Where every agent is believed to be, for the range cut.

    ``aliases`` maps an agent to the robot whose position it shares (an assigner
    hosted on a robot); ``fixed`` holds fixed positions (a base-station assigner);
    ``own`` gives the live pose of agents hosted in this process (from their base);
    everything else comes from the last pose message heard from it. ``None`` means
    no position (virtual, or never heard): always in range.
    """

    aliases: dict[str, str] = field(default_factory=dict)
    fixed: dict[str, Point] = field(default_factory=dict)
    own: dict[str, Callable[[], Point]] = field(default_factory=dict)
    heard: dict[str, Point] = field(default_factory=dict)

    def position(self, agent: str) -> Point | None:
        agent = self.aliases.get(agent, agent)
        fixed = self.fixed.get(agent)
        if fixed is not None:
            return fixed
        own = self.own.get(agent)
        if own is not None:
            return own()
        return self.heard.get(agent)


class ZenohEndpoint:
    """One agent's endpoint on the Zenoh bus (implements the Bus port)."""

    def __init__(self, bus: ZenohBus, owner: str, rng: np.random.Generator) -> None:
        self._bus = bus
        self._owner = owner
        self._loss = LossStream(rng)
        self._handlers: dict[str, list[Handler]] = {}
        self.counts: dict[str, TopicCounts] = {}
        #: Hook between perturbation and handlers: return the message to deliver (or a
        #: replacement), or None to hold it back (used to resynchronise a restart).
        self.gate: Callable[[str, Message], Message | None] | None = None
        node = bus.node
        for topic in AGENT_TOPICS:
            node.prepare(node.key(owner, topic), lane_of(topic))
        #: This agent's place in the bus's relay (None: relaying off).
        self._relay_index = bus.relay_index(owner)
        if self._relay_index is not None:
            bus._want(TOPIC_RELAYED)

    @property
    def owner(self) -> str:
        return self._owner

    def publish(self, topic: str, message: Message) -> None:
        self._count(topic).sent += 1
        relay = self._bus.relay
        if relay is not None and self._relay_index is not None and topic in RELAYED_TOPICS:
            relay.published(self._relay_index, topic, message)
        self._put(topic, message)

    def _put(self, topic: str, message: Message) -> None:
        """Send one message under this agent's key."""
        bus = self._bus
        node = bus.node
        data = encode(message)
        radio = bus.rules.radio
        airtime: Airtime | None = None
        if radio is not None:
            # Queued here, at the sender, as in simulation; receivers learn the delay.
            delay = radio.transmit(self._owner, bus.now, radio.bits_of(len(data)))
            airtime = (bus.now, math.nan if delay is None else delay)
        signatures = b""
        if bus.signer is not None and topic in bus.signed_topics:
            signatures = bus.signer.signatures_for(topic, message, bus.endpoints)
        node.put(node.key(self._owner, topic), data, lane_of(topic), airtime, signatures)

    def subscribe(self, topic: str, handler: Handler) -> None:
        self._handlers.setdefault(topic, []).append(handler)
        self._bus._want(topic)

    def inject(self, topic: str, message: Message) -> None:
        """Hand a message to this agent's handlers directly (not counted as traffic)."""
        for handler in self._handlers.get(topic, ()):
            handler(message)

    def _receive(
        self, topic: str, sender: str, message: Message, on_air: OnAir | None = None
    ) -> None:
        if sender == self._owner:
            return
        if topic not in self._handlers and not (
            topic == TOPIC_RELAYED and self._relay_index is not None
        ):
            return
        bus = self._bus
        if on_air is not None:
            due = on_air[0] + on_air[1]  # NaN (lost to the queue) is never held
            if due > bus.now + _DUE_SLACK:
                # Still on the air: judged when it arrives, as the in-process bus does.
                bus._hold(due, self, topic, sender, message, on_air)
                return
        self._settle(topic, sender, message, on_air)

    def _settle(self, topic: str, sender: str, message: Message, on_air: OnAir | None) -> None:
        """Decide, count and record what becomes of one message here, and hand it to
        the agent when it was received."""
        bus = self._bus
        if on_air is None:
            outcome, delay = bus._decide(self, topic, sender), 0.0
        else:
            outcome, delay = bus._decide_radio(self, topic, sender, on_air)
        if topic != TOPIC_RELAYED:  # relayed copies are counted by the relay
            self._count(topic).count(outcome, delay)
        observer = bus.observer
        if observer is not None:
            observer(bus.now, topic, sender, self._owner, message, outcome)
        if outcome != RECEIVED:
            return
        if topic == TOPIC_RELAYED:
            assert isinstance(message, RelayedMsg)
            self._unwrap(message)
            return
        if self._relay_index is not None and topic in RELAYED_TOPICS:
            self._relayed(topic, message, hop=1, copy=False)
            return
        self._hand(topic, message)

    def _unwrap(self, wrapper: RelayedMsg) -> None:
        """A relayed copy reached this agent: the message inside, if it is one a robot
        may relay, from a team member, and well formed (else refused as a bad relay)."""
        spec = TOPICS.get(wrapper.topic)
        try:
            inner: Message | None = decode(wrapper.payload)
        except msgspec.DecodeError:  # whatever a peer put in the payload
            inner = None
        bus = self._bus
        if (
            wrapper.topic not in RELAYED_TOPICS
            or spec is None
            or type(inner) is not spec.message
            or not 2 <= wrapper.hop <= 64
            or (bus.members is not None and inner.sender not in bus.members)
        ):
            bus.node.refuse("bad_relay")
            return
        assert inner is not None
        self._relayed(wrapper.topic, inner, hop=wrapper.hop, copy=True)

    def _relayed(self, topic: str, message: Message, hop: int, copy: bool) -> None:
        """A relayed-topic message that crossed ``hop`` links: handed to the agent unless
        it is a copy of one it had; passed on when the relay says so."""
        relay = self._bus.relay
        index = self._relay_index
        assert relay is not None and index is not None
        if not relay.receive(index, topic, message, hop, copy):
            return  # a duplicate copy
        if relay.passes_on(index, hop):
            # The header names the relaying robot (the edge binds it to the key); the
            # message's own header travels inside.
            wrapper = RelayedMsg(
                sender=self._owner,
                incarnation=message.incarnation,
                seq=message.seq,
                stamp=self._bus.now,
                topic=topic,
                hop=hop + 1,
                payload=encode(message),
            )
            self._put(TOPIC_RELAYED, wrapper)
        if topic in self._handlers:
            self._hand(topic, message)

    def _hand(self, topic: str, message: Message) -> None:
        """Hand a received message to the agent (through the gate)."""
        handlers = self._handlers.get(topic, [])
        if self.gate is not None:
            gated = self.gate(topic, message)
            if gated is None:
                return
            message = gated
        for handler in handlers:
            handler(message)

    def _count(self, topic: str) -> TopicCounts:
        counts = self.counts.get(topic)
        if counts is None:
            counts = self.counts[topic] = TopicCounts()
        return counts

    def counts_dict(self) -> dict[str, dict[str, float]]:
        """topic -> counts (and, with a radio, the delays of what it received), as the
        in-process bus reports them."""
        radio = self._bus.rules.radio is not None
        out: dict[str, dict[str, float]] = {}
        for topic, c in sorted(self.counts.items()):
            entry: dict[str, float] = dict(c.as_dict(radio))
            if radio:
                entry.update(c.delays())
            out[topic] = entry
        return out


class ZenohBus:
    """The agents of one process on the team's Zenoh network, with the receiver-side
    network model. Drive it from the agent thread: feed every :class:`Incoming` of
    channel ``"bus"`` to :meth:`handle`."""

    def __init__(
        self,
        node: ZenohNode,
        rules: LinkRules,
        positions: PositionBook,
        members: frozenset[str] | None = None,
        robots: tuple[str, ...] = (),
        signer: OriginSigner | None = None,
    ) -> None:
        """``members``: the agents of the team (None: anyone); ``robots``: the ones
        among them that relay when the network model's relaying is on; ``signer``: the
        origin signatures of AON entries, and with relaying of task statuses and relayed
        copies (a team with certificates; None: unsigned)."""
        self.node = node
        self.signer = signer
        self.rules = rules
        self.positions = positions
        self.members = members
        hops = rules.relay_hops
        #: The relay's bookkeeping over the team (robots first), when relaying is on.
        self.relay: Relay | None = None
        self._relay_ids: dict[str, int] = {}
        if hops and members is not None:
            ids = (*robots, *sorted(members - set(robots)))
            self.relay = Relay(ids, range(len(robots)), hops)
            self._relay_ids = {agent: i for i, agent in enumerate(ids)}
        #: The topics whose messages carry origin signatures (none without a signer).
        self.signed_topics = (
            frozenset()
            if signer is None
            else SIGNED_TOPICS | (RELAY_SIGNED_TOPICS if self.relay is not None else frozenset())
        )
        self.endpoints: dict[str, ZenohEndpoint] = {}
        self._topics: set[str] = set()
        self.observer: DeliveryObserver | None = None
        self.now = 0.0
        #: Transport latency (s) of every pose sample that reached this process.
        self.pose_latency: list[float] = []
        #: Samples the edge let through, per sender (before any emulated drop): what
        #: says a sender's process is still at work (``live.mates``).
        self.samples: dict[str, int] = {}
        #: Messages still on the air (due mission time, order, endpoint, topic, sender,
        #: message, on_air): judged by :meth:`release` once the clock reaches them.
        self._held: list[tuple[float, int, ZenohEndpoint, str, str, Message, OnAir]] = []
        self._held_order = 0

    def relay_index(self, agent: str) -> int | None:
        """``agent``'s index in the relay (None: relaying off, or not a member)."""
        return self._relay_ids.get(agent) if self.relay is not None else None

    def relay_stats(self) -> dict[str, dict[str, Any]]:
        """What relaying did at this process's agents (empty when it is off)."""
        if self.relay is None:
            return {}
        stats = self.relay.stats()
        return {agent: stats[agent] for agent in self.endpoints}

    def endpoint(self, owner: str, rng: np.random.Generator) -> ZenohEndpoint:
        if owner in self.endpoints:
            raise ValueError(f"agent {owner!r} already has an endpoint here")
        endpoint = ZenohEndpoint(self, owner, rng)
        self.endpoints[owner] = endpoint
        return endpoint

    def handle(self, item: Incoming) -> None:
        """Deliver one sample to every local endpoint subscribed to its topic."""
        key = item.key
        topic = key.rsplit("/", 1)[-1]
        sender = self.node.sender_of(key)
        message = item.value
        refusal = self._refusal(topic, sender, message)
        if refusal is None and item.mission != self.node.mission:
            refusal = "other_mission"  # a replay of another run, or a member of one
        if refusal is not None:
            self.node.refuse(refusal)
            return
        self.samples[sender] = self.samples.get(sender, 0) + 1
        if isinstance(message, PoseMsg):
            if sender not in self.positions.own:
                self.positions.heard[sender] = (message.x, message.y)
            if item.sent_wall is not None:
                self.pose_latency.append(item.recv_wall - item.sent_wall)
        on_air: OnAir | None = None
        if self.rules.radio is not None:
            # Once per sample, for every local endpoint: when it was sent, its delay (0
            # without a sender's queue) and its bits on the air (from the payload's size).
            published, delay = item.radio if item.radio is not None else (self.now, 0.0)
            on_air = (published, delay, self.rules.radio.bits_of(item.size))
        if self.signer is not None and self.signer.verifies and topic in self.signed_topics:
            checked = self.signer.checked(topic, message, item.signatures, self.node.refuse)
            if checked is None:
                return
            message = checked
        for endpoint in self.endpoints.values():
            endpoint._receive(topic, sender, message, on_air)

    def _refusal(self, topic: str, sender: str, message: Any) -> str | None:
        """Why the edge refuses this message (None: it may reach the agents)."""
        spec = TOPICS.get(topic)
        if spec is None or type(message) is not spec.message:
            return "wrong_type"
        if message.sender != sender:
            return "forged_sender"
        if self.members is not None and sender not in self.members:
            return "not_member"
        return None

    def release(self, now: float) -> None:
        """Set the mission clock and judge the messages on the air now due (in due
        order, as the in-process bus delivers at the first step at or after the due
        time)."""
        self.now = now
        held = self._held
        due = []
        while held and held[0][0] <= now + _DUE_SLACK:
            due.append(heapq.heappop(held))
        # Those due together in the order they arrived, as the in-process bus takes its
        # outbox in publication order.
        for _, _, endpoint, topic, sender, message, on_air in sorted(due, key=_arrival):
            endpoint._settle(topic, sender, message, on_air)

    def _hold(
        self,
        due: float,
        endpoint: ZenohEndpoint,
        topic: str,
        sender: str,
        message: Message,
        on_air: OnAir,
    ) -> None:
        self._held_order += 1
        heapq.heappush(
            self._held, (due, self._held_order, endpoint, topic, sender, message, on_air)
        )

    def _want(self, topic: str) -> None:
        if topic not in self._topics:
            self._topics.add(topic)
            self.node.listen(f"{self.node.prefix}/*/{topic}", "bus", decode)

    def _decide(self, receiver: ZenohEndpoint, topic: str, sender: str) -> str:
        policy = self.rules.policy
        # Exempt topics need no position look-up: the policy ignores the range for them.
        connected = policy.exempt(topic) or self._in_range(sender, receiver.owner)
        return policy.decide(topic, connected, receiver._loss)

    def _decide_radio(
        self,
        receiver: ZenohEndpoint,
        topic: str,
        sender: str,
        on_air: OnAir,
    ) -> tuple[str, float]:
        """The outcome of one message under the radio and its delay, as the in-process
        bus decides it: lost to the sender's queue; else the link's range from its power
        and its packet error (one fading draw when in range, whatever the topic), then
        the delivery policy."""
        radio = self.rules.radio
        assert radio is not None
        policy = self.rules.policy
        _, delay, bits = on_air
        if delay != delay:  # NaN: the sender's queue overflowed
            if not policy.exempt(topic):
                return DROPPED_QUEUE, 0.0
            delay = 0.0  # the task assignment is never lost
        if not (radio.knows(sender) and radio.knows(receiver.owner)):
            return policy.decide(topic, True, receiver._loss), delay  # not a team node
        at = self.positions.position(sender)
        to = self.positions.position(receiver.owner)
        connected, per = radio.judge(sender, at, receiver.owner, to, bits)
        return policy.decide(topic, connected, receiver._loss, per), delay

    def _in_range(self, sender: str, receiver: str) -> bool:
        a = self.positions.position(sender)
        b = self.positions.position(receiver)
        if a is None or b is None:
            return True
        return self.rules.network.in_range(math.hypot(a[0] - b[0], a[1] - b[1]))

    def counts_by_agent(self) -> dict[str, dict[str, dict[str, float]]]:
        return {owner: ep.counts_dict() for owner, ep in self.endpoints.items()}
