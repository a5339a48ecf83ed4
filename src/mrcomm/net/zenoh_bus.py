"""The Bus port over Eclipse Zenoh (live mode, DESIGN ``live``; issue 7 §1).

:class:`ZenohNode` is one process's Zenoh *peer* session. It owns:

* the key space ``mrcomm/<team>/<agent>/<topic>`` (each agent publishes under its own
  id; subscribers use ``mrcomm/<team>/*/<topic>``);
* three quality-of-service lanes: task status and AON reliable with *blocking*
  congestion control on their own priority; other control traffic reliable and
  blocking on another; pose and the clock *dropping* under congestion. Blocking puts
  run on one worker thread per lane: a blocked status never stalls pose or the agent;
* an inbox: Zenoh calls back on its own threads, so every sample is decoded there and
  queued; the owning process drains the queue on its one agent thread (AON and the
  agents are single-threaded);
* liveliness tokens ``mrcomm/<team>/<agent>/alive/<incarnation>`` for team discovery:
  members appear and disappear as their sessions come and go.

:class:`ZenohBus` applies the receiver-side perturbations exactly as the in-process
bus does (``net.inprocess``), on the agent thread, and counts every decision:

1. range (AH): the receiver's own position (from its base) against the sender's last
   position, known from the pose messages seen on the wire — *all* of them, also those
   the emulated network then cut, as a radio would still hear a robot come back into
   range. A node without a position (virtual assigner) is always in range;
2. simulated packet loss SPL X %, drawn from the receiver's own seeded stream.

Each :class:`ZenohEndpoint` is one agent's endpoint (the Bus port); a process may host
several (a robot and the task assigner it hosts).

**The edge validates.** Nothing a peer sends is raised into an agent: a sample larger
than :data:`MAX_SAMPLE_BYTES` or that does not decode is dropped on the Zenoh thread;
on the agent thread :meth:`ZenohBus.handle` drops a message of another type than its
topic carries (:data:`~mrcomm.messaging.topics.TOPICS`),
whose ``sender`` is not the agent whose key it came under, or from an agent that is not
a team member. Every refusal is counted by cause (:data:`REFUSALS`; the journal's
``refused`` lines, ``mrcomm live --json`` under ``live.processes.<agent>.refused``).
"""

from __future__ import annotations

import contextlib
import heapq
import math
import queue
import struct
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import msgspec
import numpy as np

from mrcomm.errors import InputError
from mrcomm.messaging.messages import (
    Message,
    PoseMsg,
    decode,
    encode,
)
from mrcomm.messaging.topics import AGENT_TOPICS, TOPICS, Lane, lane_of
from mrcomm.net.delivery import (
    DROPPED_QUEUE,
    RECEIVED,
    DeliveryPolicy,
    LossStream,
    TopicCounts,
)
from mrcomm.net.inprocess import DeliveryObserver
from mrcomm.net.network import NetworkModel, Wlan
from mrcomm.net.radio.links import RadioLinks
from mrcomm.net.zenoh_config import ZenohOptions, build_config
from mrcomm.ports import Handler

Point = tuple[float, float]
#: A sample larger than this (bytes) is refused before decoding: the largest message a
#: team sends (an assignment of a few hundred tasks) is a few kB.
MAX_SAMPLE_BYTES = 256 * 1024
#: Why the bus edge refused a sample.
REFUSALS = (
    "oversized",  # larger than MAX_SAMPLE_BYTES
    "undecodable",  # not one of the team's messages
    "wrong_type",  # a message of another type than its topic carries
    "forged_sender",  # its sender field names another agent than its key
    "not_member",  # from an agent that is not in the team
)
#: Slack on due times (s): a message due at the current tick is handed over at it.
_DUE_SLACK = 1e-9
_STAMP = struct.Struct("<q")  # wall-clock send time (ns) carried as a Zenoh attachment
#: With a radio the attachment also carries the sender's mission time at publication
#: and the radio delay of its queue (s; NaN: the queue overflowed and lost it).
_RADIO_STAMP = struct.Struct("<qdd")

#: A message's radio facts from its sender: (mission time published, delay or NaN).
Airtime = tuple[float, float]


@dataclass(frozen=True, slots=True)
class Incoming:
    """One sample taken from Zenoh, decoded on the Zenoh thread."""

    channel: str  # "bus", "presence" or a live-protocol channel name
    key: str
    value: Any
    sent_wall: float | None  # sender's wall clock at put (s), when it sent one
    recv_wall: float
    radio: Airtime | None = None  # the sender's radio queue (radio network model only)


@dataclass(frozen=True, slots=True)
class Presence:
    """A liveliness token appeared (``alive``) or disappeared."""

    agent: str
    incarnation: int
    alive: bool


class _BlockingWorker:
    """Runs blocking puts of one lane in order on its own thread."""

    def __init__(self, name: str) -> None:
        self._queue: queue.SimpleQueue[tuple[Any, bytes, bytes] | None] = queue.SimpleQueue()
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def submit(self, publisher: Any, data: bytes, attachment: bytes) -> None:
        self._queue.put((publisher, data, attachment))

    def _run(self) -> None:
        import zenoh

        while True:
            item = self._queue.get()
            if item is None:
                return
            publisher, data, attachment = item
            with contextlib.suppress(zenoh.ZError):  # session closing: nobody to deliver to
                publisher.put(data, attachment=attachment)

    def stop(self, timeout: float) -> None:
        self._queue.put(None)
        self._thread.join(timeout)


class ZenohNode:
    """One process's peer session, its publishers, inbox and liveliness tokens."""

    def __init__(
        self, options: ZenohOptions, inbox: queue.SimpleQueue[Incoming] | None = None
    ) -> None:
        """``inbox``: share one queue between several sessions of a process (the team's
        and the world's), so one thread waits on both in arrival order."""
        import zenoh

        self.options = options
        self.prefix = options.prefix()
        config = build_config(options)
        try:
            self.session = zenoh.open(config)
        except zenoh.ZError as err:
            message = _open_error(err)
            tls = options.tls is not None and ("TLS" in message or "cert" in message)
            raise InputError(message, field="--tls-cert" if tls else "--listen") from None
        self._zenoh = zenoh
        self._inbox: queue.SimpleQueue[Incoming] = (
            inbox if inbox is not None else queue.SimpleQueue()
        )
        self._publishers: dict[tuple[str, Lane], Any] = {}
        self._subscribers: list[Any] = []
        self._tokens: dict[str, Any] = {}
        self._workers = {
            Lane.STATUS: _BlockingWorker("mrcomm-status"),
            Lane.CONTROL: _BlockingWorker("mrcomm-control"),
        }
        self._closed = False
        #: Samples refused at the edge, by cause (:data:`REFUSALS`).
        self.refused: dict[str, int] = {}
        self._refused_lock = threading.Lock()

    # -- keys ------------------------------------------------------------------------
    def key(self, agent: str, topic: str) -> str:
        return f"{self.prefix}/{agent}/{topic}"

    def sender_of(self, key: str) -> str:
        """The agent id in ``mrcomm/<team>/<agent>/...``."""
        return key[len(self.prefix) + 1 :].split("/", 1)[0]

    # -- publishing ------------------------------------------------------------------
    def put(self, key: str, data: bytes, lane: Lane, radio: Airtime | None = None) -> None:
        """Publish without ever blocking the caller (blocking lanes use a worker);
        ``radio``: the message's facts from the sender's radio queue."""
        if self._closed:
            return
        publisher = self._publisher(key, lane)
        if radio is None:
            attachment = _STAMP.pack(time.time_ns())
        else:
            attachment = _RADIO_STAMP.pack(time.time_ns(), *radio)
        if lane is Lane.BEST_EFFORT:
            with contextlib.suppress(self._zenoh.ZError):
                publisher.put(data, attachment=attachment)
        else:
            self._workers[lane].submit(publisher, data, attachment)

    def prepare(self, key: str, lane: Lane) -> None:
        """Declare the publisher of ``key`` now. Declaring can wait on a congested
        link (without letting Zenoh's threads deliver anything meanwhile), so every
        key a process will use is declared at start, never mid-mission."""
        self._publisher(key, lane)

    def _publisher(self, key: str, lane: Lane) -> Any:
        publisher = self._publishers.get((key, lane))
        if publisher is None:
            z = self._zenoh
            if lane is Lane.BEST_EFFORT:
                publisher = self.session.declare_publisher(
                    key,
                    congestion_control=z.CongestionControl.DROP,
                    priority=z.Priority.DATA,
                    # Reliable on the link (so only our injected loss loses a pose on
                    # a healthy network), but never waits: congestion drops it.
                    reliability=z.Reliability.RELIABLE,
                    express=True,
                )
            else:
                high = lane is Lane.STATUS
                priority = z.Priority.INTERACTIVE_HIGH if high else z.Priority.DATA_HIGH
                publisher = self.session.declare_publisher(
                    key,
                    congestion_control=z.CongestionControl.BLOCK,
                    priority=priority,
                    reliability=z.Reliability.RELIABLE,
                )
            self._publishers[(key, lane)] = publisher
        return publisher

    # -- receiving -------------------------------------------------------------------
    def listen(self, key_expr: str, channel: str, decoder: Callable[[bytes], Any]) -> None:
        """Queue every sample on ``key_expr``, decoded by ``decoder``; samples that do
        not decode are dropped (and never reach the agent thread)."""
        inbox = self._inbox

        def on_sample(sample: Any) -> None:
            recv = time.time()
            payload = sample.payload
            if len(payload) > MAX_SAMPLE_BYTES:
                self.refuse("oversized")
                return
            try:
                value = decoder(payload.to_bytes())
            except (msgspec.DecodeError, msgspec.ValidationError, ValueError):
                self.refuse("undecodable")
                return
            sent: float | None = None
            radio: Airtime | None = None
            attachment = sample.attachment
            if attachment is not None:
                raw = attachment.to_bytes()
                if len(raw) == _STAMP.size:
                    sent = _STAMP.unpack(raw)[0] / 1e9
                elif len(raw) == _RADIO_STAMP.size:
                    stamp_ns, published, delay = _RADIO_STAMP.unpack(raw)
                    sent, radio = stamp_ns / 1e9, (published, delay)
            inbox.put(Incoming(channel, str(sample.key_expr), value, sent, recv, radio))

        self._subscribers.append(self.session.declare_subscriber(key_expr, on_sample))

    def refuse(self, cause: str) -> None:
        """Count one sample refused at the edge (from any thread)."""
        with self._refused_lock:
            self.refused[cause] = self.refused.get(cause, 0) + 1

    def poll(self, timeout: float | None) -> Incoming | None:
        """Next queued sample, waiting at most ``timeout`` seconds (None: no wait)."""
        try:
            if timeout is None:
                return self._inbox.get_nowait()
            return self._inbox.get(timeout=max(timeout, 0.0))
        except queue.Empty:
            return None

    # -- liveliness --------------------------------------------------------------------
    def alive_key(self, agent: str, incarnation: int) -> str:
        return f"{self.prefix}/{agent}/alive/{incarnation}"

    def declare_alive(self, agent: str, incarnation: int) -> None:
        key = self.alive_key(agent, incarnation)
        self._tokens[key] = self.session.liveliness().declare_token(key)

    @property
    def inbox(self) -> queue.SimpleQueue[Incoming]:
        return self._inbox

    def watch_presence(self, agent: str = "*") -> None:
        """Queue a :class:`Presence` whenever a team member (or just ``agent``) appears
        or disappears, including those already present when the watch starts."""
        inbox = self._inbox
        z = self._zenoh

        def on_token(sample: Any) -> None:
            parsed = self._parse_alive(str(sample.key_expr))
            if parsed is None:
                return
            alive = sample.kind == z.SampleKind.PUT
            inbox.put(
                Incoming(
                    "presence",
                    str(sample.key_expr),
                    Presence(parsed[0], parsed[1], alive),
                    None,
                    time.time(),
                )
            )

        self._subscribers.append(
            self.session.liveliness().declare_subscriber(
                f"{self.prefix}/{agent}/alive/*", on_token, history=True
            )
        )

    def present(self, agent: str, timeout: float = 1.0) -> list[int]:
        """Incarnations of ``agent`` whose tokens are alive now (a liveliness query)."""
        found: list[int] = []
        replies = self.session.liveliness().get(f"{self.prefix}/{agent}/alive/*", timeout=timeout)
        for reply in replies:
            ok = reply.ok
            if ok is None:
                continue
            parsed = self._parse_alive(str(ok.key_expr))
            if parsed is not None:
                found.append(parsed[1])
        return found

    def _parse_alive(self, key: str) -> tuple[str, int] | None:
        parts = key[len(self.prefix) + 1 :].split("/")
        if len(parts) != 3 or parts[1] != "alive":
            return None
        try:
            return parts[0], int(parts[2])
        except ValueError:
            return None

    def peers(self) -> int:
        """Number of peers this session is connected to right now."""
        return len(list(self.session.info.peers_zid()))

    def close(self) -> None:
        """Flush the blocking lanes (briefly) and close the session."""
        if self._closed:
            return
        self._closed = True
        for worker in self._workers.values():
            worker.stop(timeout=2.0)
        with contextlib.suppress(self._zenoh.ZError):
            self.session.close()


def _arrival(held: tuple[float, int, Any, str, str, Message, Airtime]) -> int:
    return held[1]


def _open_error(err: BaseException) -> str:
    text = str(err).strip().splitlines()
    first = text[0] if text else type(err).__name__
    # Zenoh appends source locations after " at "; the cause is what matters.
    return "cannot open the Zenoh session: " + first.split(" at /", 1)[0]


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

    @property
    def owner(self) -> str:
        return self._owner

    def publish(self, topic: str, message: Message) -> None:
        self._count(topic).sent += 1
        bus = self._bus
        node = bus.node
        data = encode(message)
        radio = bus.rules.radio
        airtime: Airtime | None = None
        if radio is not None:
            # Queued here, at the sender, as in simulation; receivers learn the delay.
            delay = radio.transmit(self._owner, bus.now, radio.bits(message))
            airtime = (bus.now, math.nan if delay is None else delay)
        node.put(node.key(self._owner, topic), data, lane_of(topic), airtime)

    def subscribe(self, topic: str, handler: Handler) -> None:
        self._handlers.setdefault(topic, []).append(handler)
        self._bus._want(topic)

    def inject(self, topic: str, message: Message) -> None:
        """Hand a message to this agent's handlers directly (not counted as traffic)."""
        for handler in self._handlers.get(topic, ()):
            handler(message)

    def _receive(
        self, topic: str, sender: str, message: Message, airtime: Airtime | None = None
    ) -> None:
        if sender == self._owner or topic not in self._handlers:
            return
        bus = self._bus
        if airtime is not None and bus.rules.radio is not None:
            due = airtime[0] + airtime[1]  # NaN (lost to the queue) is never held
            if due > bus.now + _DUE_SLACK:
                # Still on the air: judged when it arrives, as the in-process bus does.
                bus._hold(due, self, topic, sender, message, airtime)
                return
        self._settle(topic, sender, message, airtime)

    def _settle(self, topic: str, sender: str, message: Message, airtime: Airtime | None) -> None:
        """Decide, count and record what becomes of one message here, and hand it to
        the agent when it was received."""
        bus = self._bus
        if bus.rules.radio is None:
            outcome, delay = bus._decide(self, topic, sender), 0.0
        else:
            outcome, delay = bus._decide_radio(self, topic, sender, message, airtime)
        self._count(topic).count(outcome, delay)
        observer = bus.observer
        if observer is not None:
            observer(bus.now, topic, sender, self._owner, message, outcome)
        if outcome == RECEIVED:
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
    ) -> None:
        """``members``: the agents of the team (None: anyone)."""
        self.node = node
        self.rules = rules
        self.positions = positions
        self.members = members
        self.endpoints: dict[str, ZenohEndpoint] = {}
        self._topics: set[str] = set()
        self.observer: DeliveryObserver | None = None
        self.now = 0.0
        #: Transport latency (s) of every pose sample that reached this process.
        self.pose_latency: list[float] = []
        #: Messages still on the air (due mission time, order, endpoint, topic, sender,
        #: message, airtime): judged by :meth:`release` once the clock reaches them.
        self._held: list[tuple[float, int, ZenohEndpoint, str, str, Message, Airtime]] = []
        self._held_order = 0

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
        if refusal is not None:
            self.node.refuse(refusal)
            return
        if isinstance(message, PoseMsg):
            if sender not in self.positions.own:
                self.positions.heard[sender] = (message.x, message.y)
            if item.sent_wall is not None:
                self.pose_latency.append(item.recv_wall - item.sent_wall)
        for endpoint in self.endpoints.values():
            endpoint._receive(topic, sender, message, item.radio)

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
        for _, _, endpoint, topic, sender, message, airtime in sorted(due, key=_arrival):
            endpoint._settle(topic, sender, message, airtime)

    def _hold(
        self,
        due: float,
        endpoint: ZenohEndpoint,
        topic: str,
        sender: str,
        message: Message,
        airtime: Airtime,
    ) -> None:
        self._held_order += 1
        heapq.heappush(
            self._held, (due, self._held_order, endpoint, topic, sender, message, airtime)
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
        message: Message,
        airtime: Airtime | None,
    ) -> tuple[str, float]:
        """The outcome of one message under the radio and its delay, as the in-process
        bus decides it: lost to the sender's queue; else the link's range from its power
        and its packet error (one fading draw when in range, whatever the topic), then
        the delivery policy."""
        radio = self.rules.radio
        assert radio is not None
        policy = self.rules.policy
        delay = 0.0 if airtime is None else airtime[1]
        if delay != delay:  # NaN: the sender's queue overflowed
            if not policy.exempt(topic):
                return DROPPED_QUEUE, 0.0
            delay = 0.0  # the task assignment is never lost
        if not (radio.knows(sender) and radio.knows(receiver.owner)):
            return policy.decide(topic, True, receiver._loss), delay  # not a team node
        at = self.positions.position(sender)
        to = self.positions.position(receiver.owner)
        connected, per = radio.judge(sender, at, receiver.owner, to, radio.bits(message))
        return policy.decide(topic, connected, receiver._loss, per), delay

    def _in_range(self, sender: str, receiver: str) -> bool:
        a = self.positions.position(sender)
        b = self.positions.position(receiver)
        if a is None or b is None:
            return True
        return self.rules.network.in_range(math.hypot(a[0] - b[0], a[1] - b[1]))

    def counts_by_agent(self) -> dict[str, dict[str, dict[str, float]]]:
        return {owner: ep.counts_dict() for owner, ep in self.endpoints.items()}
