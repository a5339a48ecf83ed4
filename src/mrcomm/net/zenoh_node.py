"""One process's Zenoh session (live mode, DESIGN ``live``; issue 7 §1).

:class:`ZenohNode` is one process's Zenoh *peer* session. It owns:

* the key space ``mrcomm/<team>/<agent>/<topic>`` (each agent publishes under its own
  id; subscribers use ``mrcomm/<team>/*/<topic>``);
* three quality-of-service lanes: task status and AON reliable with *blocking*
  congestion control on their own priority; other control traffic reliable and
  blocking on another; pose and the clock *dropping* under congestion. Blocking puts
  run on one worker thread per lane: a blocked status never stalls pose or the agent;
* an inbox: Zenoh calls back on its own threads, so every sample is decoded there and
  queued; the owning process drains the queue on its one agent thread (AON and the
  agents are single-threaded); a sample larger than :data:`MAX_SAMPLE_BYTES` or that
  does not decode is refused there and counted (:attr:`ZenohNode.refused`);
* liveliness tokens ``mrcomm/<team>/<agent>/alive/<incarnation>`` for team discovery:
  members appear and disappear as their sessions come and go;
* queries (:meth:`ZenohNode.answer`, :meth:`ZenohNode.ask`): one process answers on a
  key of its own with what it knows (the world's roster of who is present);
* :func:`drain`: the owning thread's way of emptying the inbox, in bounded time;
* :meth:`ZenohNode.reopen`: a fresh session in place of one whose transports may be
  stale (the process was stopped past the link lease), everything declared again.

The team's bus on top of it is :mod:`mrcomm.net.zenoh_bus`.
"""

from __future__ import annotations

import contextlib
import queue
import struct
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import msgspec

from mrcomm.errors import InputError
from mrcomm.messaging.topics import Lane
from mrcomm.net.zenoh_config import ZenohOptions, build_config

#: A sample larger than this (bytes) is refused before decoding: the largest message a
#: team sends (an assignment of a few hundred tasks) is a few kB.
MAX_SAMPLE_BYTES = 256 * 1024
#: Why the bus edge refused a sample.
REFUSALS = (
    "oversized",  # larger than MAX_SAMPLE_BYTES (or its attachment than MAX_ATTACHMENT_BYTES)
    "undecodable",  # not one of the team's messages
    "wrong_type",  # a message of another type than its topic carries
    "forged_sender",  # its sender field names another agent than its key
    "not_member",  # from an agent that is not in the team
    "implausible_tick",  # a clock tick the world cannot have sent (live/tick_guard.py)
    "bad_relay",  # a relayed copy whose content no robot may relay (net/zenoh_bus.py)
    "other_mission",  # sent in another mission (a replay, or a team member of another run)
    "unsigned_entry",  # an AON entry without its origin's signature (net/origin_signatures.py)
)
#: Every attachment: whether the radio's facts follow (1) or not (0), the mission's
#: identity (8 bytes; zero: not known yet) and the sender's wall-clock send time (ns);
#: then, with a radio, the sender's mission time at publication and the radio delay of
#: its queue (s; NaN: the queue overflowed and lost it); then the origin signatures of
#: the message's AON entries, if any (net/origin_signatures.py).
_STAMP = struct.Struct("<B8sq")
_RADIO = struct.Struct("<dd")
#: Largest attachment taken (the stamps and a publication's origin signatures: ~100
#: bytes an entry, at most 64 entries); a larger one is refused as oversized.
MAX_ATTACHMENT_BYTES = 16 * 1024
#: The identity of a mission not known yet.
NO_MISSION = bytes(8)

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
    size: int = 0  # bytes of the encoded message
    mission: bytes = NO_MISSION  # the mission its sender was in
    signatures: bytes = b""  # the origin signatures the sample came with


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
        #: What :meth:`reopen` declares again on a new session, in declaration order.
        self._declared: list[Callable[[], None]] = []
        #: Times the session was reopened.
        self.reopened = 0
        self._inbox: queue.SimpleQueue[Incoming] = (
            inbox if inbox is not None else queue.SimpleQueue()
        )
        self._publishers: dict[tuple[str, Lane], Any] = {}
        #: Every declared subscriber, presence watch and queryable: kept, as Zenoh
        #: undeclares what is dropped.
        self._subscribers: list[Any] = []
        self._tokens: dict[str, Any] = {}
        self._workers = {
            Lane.STATUS: _BlockingWorker("mrcomm-status"),
            Lane.CONTROL: _BlockingWorker("mrcomm-control"),
        }
        self._closed = False
        #: Samples refused at the edge, by cause (:data:`REFUSALS`).
        self.refused: dict[str, int] = {}
        #: The mission this process is in (:data:`NO_MISSION` until it is known): sent
        #: with every sample; the bus refuses samples of another mission.
        self.mission = NO_MISSION
        self._refused_lock = threading.Lock()

    # -- keys ------------------------------------------------------------------------
    def key(self, agent: str, topic: str) -> str:
        return f"{self.prefix}/{agent}/{topic}"

    def sender_of(self, key: str) -> str:
        """The agent id in ``mrcomm/<team>/<agent>/...``."""
        return key[len(self.prefix) + 1 :].split("/", 1)[0]

    # -- publishing ------------------------------------------------------------------
    def put(
        self,
        key: str,
        data: bytes,
        lane: Lane,
        radio: Airtime | None = None,
        signatures: bytes = b"",
    ) -> None:
        """Publish without ever blocking the caller (blocking lanes use a worker);
        ``radio``: the message's facts from the sender's radio queue; ``signatures``:
        its AON entries' origin signatures."""
        if self._closed:
            return
        publisher = self._publisher(key, lane)
        attachment = _STAMP.pack(radio is not None, self.mission, time.time_ns())
        if radio is not None:
            attachment += _RADIO.pack(*radio)
        attachment += signatures
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
        self._declared.append(lambda: self._listen(key_expr, channel, decoder))
        self._listen(key_expr, channel, decoder)

    def _listen(self, key_expr: str, channel: str, decoder: Callable[[bytes], Any]) -> None:
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
            mission, signatures = NO_MISSION, b""
            attachment = sample.attachment
            raw = attachment.to_bytes() if attachment is not None else b""
            if len(raw) > MAX_ATTACHMENT_BYTES:
                self.refuse("oversized")
                return
            if len(raw) >= _STAMP.size:
                has_radio, mission, stamp_ns = _STAMP.unpack_from(raw)
                sent, rest = stamp_ns / 1e9, _STAMP.size
                if has_radio and len(raw) >= rest + _RADIO.size:
                    radio = _RADIO.unpack_from(raw, rest)
                    rest += _RADIO.size
                signatures = raw[rest:]
            key = str(sample.key_expr)
            item = Incoming(
                channel, key, value, sent, recv, radio, len(payload), mission, signatures
            )
            inbox.put(item)

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
        self._declared.append(lambda: self._watch_presence(agent))
        self._watch_presence(agent)

    def _watch_presence(self, agent: str) -> None:
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

    # -- queries -----------------------------------------------------------------------
    def answer(self, key: str, reply: Callable[[], bytes]) -> None:
        """Answer every query on ``key`` with ``reply()``. It is called on Zenoh's
        threads: it must only read a value the owning thread replaces whole."""
        self._declared.append(lambda: self._answer(key, reply))
        self._answer(key, reply)

    def _answer(self, key: str, reply: Callable[[], bytes]) -> None:
        def on_query(query: Any) -> None:
            query.reply(key, reply())

        self._subscribers.append(self.session.declare_queryable(key, on_query))

    def ask(self, key: str, timeout: float = 1.0) -> list[bytes]:
        """The payloads of every answer to a query on ``key`` (none: nobody answers)."""
        replies = self.session.get(key, timeout=timeout)
        return [reply.ok.payload.to_bytes() for reply in replies if reply.ok is not None]

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

    def reopen(self, timeout: float = 10.0) -> bool:
        """Close the session and open a new one with the same configuration (the same
        listening endpoints: peers find it where they did), then declare again, in
        order, every subscriber, presence watch, publisher and liveliness token.

        Why: a process that was stopped past the link lease comes back with transports
        its peers closed long ago. A peer that re-dialed meanwhile can have its new
        link merged into such a stale transport (peers that dial each other; Zenoh
        issue eclipse-zenoh/zenoh#2806): neither side then declares anything to the
        other again, and the peer never sees this process's token come back. A fresh
        session shares no state with the old one. Presence watches replay the tokens
        present (their history); a token that vanished while the session was being
        replaced is not reported gone. Samples queued on the blocking lanes meanwhile
        are lost (their senders re-send what matters: AON, the away re-reports).
        Returns False when no new session could be opened within ``timeout`` wall s
        (the listening port still held): the process then has none."""
        if self._closed:
            return False
        with contextlib.suppress(self._zenoh.ZError):
            self.session.close()
        deadline = time.monotonic() + timeout
        while True:
            try:
                self.session = self._zenoh.open(build_config(self.options))
                break
            except self._zenoh.ZError:  # the old listener not yet released
                if time.monotonic() >= deadline:
                    self._closed = True
                    return False
                time.sleep(0.1)  # wait for the port before trying again
        self.reopened += 1
        publishers = list(self._publishers)
        self._publishers = {}
        self._subscribers = []
        for declare in self._declared:
            declare()
        for key, lane in publishers:
            self._publisher(key, lane)
        for key in self._tokens:
            self._tokens[key] = self.session.liveliness().declare_token(key)
        return True

    def close(self) -> None:
        """Flush the blocking lanes (briefly) and close the session."""
        if self._closed:
            return
        self._closed = True
        for worker in self._workers.values():
            worker.stop(timeout=2.0)
        with contextlib.suppress(self._zenoh.ZError):
            self.session.close()


def drain(
    poll: Callable[[float | None], Incoming | None],
    handle: Callable[[Incoming], bool],
    wait: float,
    clock: Callable[[], float] = time.monotonic,
) -> None:
    """Handle what :meth:`ZenohNode.poll` brings within ``wait`` wall s, then return
    even while more keeps coming (``handle``: True to stop at once), so that a live
    agent's heartbeat and its check for having been away run between drains: a stopped
    process is flooded on its return, and draining until the inbox was empty held a
    loaded one there for 600 s of mission time, cut off from its mates (its session not
    reopened), not beating."""
    until = clock() + wait
    item = poll(wait)
    while item is not None:
        if handle(item) or clock() >= until:
            return
        item = poll(None)


def _open_error(err: BaseException) -> str:
    text = str(err).strip().splitlines()
    first = text[0] if text else type(err).__name__
    # Zenoh appends source locations after " at "; the cause is what matters.
    return "cannot open the Zenoh session: " + first.split(" at /", 1)[0]
