"""AON — all-or-nothing acknowledged messaging over the Bus port.

One :class:`AonEndpoint` per agent. It carries task-status payloads to every member of
a fixed team over plain best-effort publish/subscribe (topic ``TOPIC_AON``), with the
four stages of the original protocol:

1. the sender publishes the message;
2. each member that gets it re-publishes it (acknowledging: "I have it");
3. once a member knows every member has it, it sets *received* and publishes that;
4. once a member knows every member has set *received*, the message is *finished*
   there; its state is released.

Unfinished messages are re-sent at ``resend_period`` (3 Hz) when nothing was learnt
meanwhile; after ``failsafe_timeout`` (15 s) without finishing, the exchange is
restarted (the payload is re-announced to everyone with a request to reply).

Why it cannot deadlock (the original did, with two messages in flight):

* Every message is identified by (sender, incarnation, sequence) and has its own state;
  nothing is global, so messages never wait for each other, in any order.
* A publication carries the publisher's whole knowledge of every message it holds:
  per message two member bitmaps, ``have`` (known to have it) and ``recv`` (known to
  have set *received*), plus the payload while someone may still lack it. Knowledge
  is only ever merged by union of bitmaps that came from real receipts (the publisher
  of an entry has the message; its bitmaps are its own such knowledge), so it only
  grows and is never false, whatever order, duplication or delay.
* A re-send asks for replies: every member that knows something the asker does not
  answers — including a member that already finished and released the message, from a
  compact record (per (sender, incarnation): a contiguous watermark plus a small set),
  answering "everyone has it and set received". So the last member to finish is never
  stranded, and a stale copy is recognised and never delivered twice.

Aggregation: acknowledgements are bitmaps and several messages share a publication, so
in the loss-free case one message costs 2n publications (1 + (n-1) acknowledgements +
n *received*), against the original's n(n+1) — and concurrent messages share even those.

What it can honestly promise over lossy links (and no more):

* Never reports a message finished unless every member has it (or, with a lease,
  unless every member not named as left out has it).
* Delivers each payload to the application at most once per member incarnation, and
  exactly once to every member the network eventually lets it reach.
* Finishes at every member once the network lets enough publications through, for any
  loss rate below 100 %, any reordering, duplication or delay, and after partitions of
  any length — there is no give-up without a lease.
* With ``lease`` set: a member silent (no AON traffic and no :meth:`heard_from`) for
  longer than the lease no longer blocks the others — pending messages that every
  other member has are reported finished with it named in ``left_out``. Their state is
  kept, and when it is heard again it is brought up to date (the messages are re-sent
  to it) and a second, ``late`` report follows once it has them.

What a peer can make it hold is bounded (:data:`MAX_INTRODUCED`, :data:`MAX_SEQ_AHEAD`,
:data:`MAX_INCARNATIONS`): a member (or an intruder with a member's certificate) that
floods the team with messages fills only its own share, and the team's own messages
still go through. A payload is taken only from the member that authored it (its header
names the entry's origin; a task status names its own sender as its robot). Every
refusal is counted by cause (:attr:`AonEndpoint.refused`). Publications carry at most
:data:`MAX_ENTRIES` entries each (more go in several), so none outgrows a transport's
message size.

Limits: the endpoint is single-threaded (the bus must call its handler from the
agent's thread, between ``step`` calls, or from inside them). A member that restarts
with a new incarnation has lost what it held; peers still count its former
incarnation as having the messages it acknowledged. State for a message reported with
left-out members is kept until they return.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable, Sequence
from typing import Any

from mrcomm.messaging.aon_lease import PausedMessages, SilentMembers
from mrcomm.messaging.aon_state import (
    AonStats,
    FinishReport,
    MessageId,
    MsgState,
    SeqRecord,
    TeamIndex,
)
from mrcomm.messaging.messages import (
    TOPIC_AON,
    AonEntry,
    AonMsg,
    Message,
    OperatorCommand,
    TaskStatus,
)
from mrcomm.ports import Bus

__all__ = ["AonEndpoint", "AonStats", "FinishReport", "MessageId"]

#: What AON carries: task statuses (topic ``aon``), operator commands (``command``).
Payload = TaskStatus | OperatorCommand
DeliverFn = Callable[[Any, MessageId], None]
FinishFn = Callable[[MessageId, FinishReport], None]

# Placeholder time for state created before the endpoint first saw a clock (a message
# delivered before the first step); fixed up at the first step.
_UNSET = -math.inf

#: Unfinished messages a member may bring into this endpoint (those it was first to
#: publish here, whoever their origin); the endpoint holds at most this many per member.
MAX_INTRODUCED = 256
#: How far past the oldest unfinished sequence number of an origin's incarnation a new
#: message may be (a sender's numbers grow one by one).
MAX_SEQ_AHEAD = 1024
#: Incarnations of one origin whose finished messages are remembered (restarts are few).
MAX_INCARNATIONS = 8
#: Entries in one publication (more are published in several).
MAX_ENTRIES = 64


def authored_by(payload: object, origin: str) -> bool:
    """Whether ``payload`` is what member ``origin`` may send: its header names
    ``origin`` as its sender, and a task status names its sender as its robot."""
    sender = getattr(payload, "sender", None)
    if sender != origin:
        return False
    return not isinstance(payload, TaskStatus) or payload.robot == sender


class AonEndpoint:
    """One agent's AON endpoint (see the module docstring for the protocol)."""

    def __init__(
        self,
        bus: Bus,
        owner: str,
        incarnation: int,
        team: Sequence[str],
        *,
        resend_period: float = 1.0 / 3.0,
        failsafe_timeout: float = 15.0,
        lease: float | None = None,
        on_deliver: DeliverFn,
        on_finished: FinishFn | None = None,
        topic: str = TOPIC_AON,
        subscribe: bool = True,
        origins: frozenset[str] | None = None,
        payloads: tuple[type, ...] = (TaskStatus, OperatorCommand),
    ) -> None:
        """``topic``: where this team's AON messages travel (one AON team per topic);
        ``subscribe=False``: the owner hands the endpoint its messages
        (:meth:`receive`) instead of the bus; ``origins``: the members whose messages
        it takes (None: every member); ``payloads``: the payload types it takes."""
        if resend_period <= 0.0:
            raise ValueError("resend_period must be positive")
        if failsafe_timeout <= 0.0:
            raise ValueError("failsafe_timeout must be positive")
        if lease is not None and lease <= 0.0:
            raise ValueError("lease must be positive (or None for no lease)")
        self._team = TeamIndex(team)
        if owner not in self._team.bit:
            raise ValueError(f"AON owner {owner!r} is not in the team {list(team)}")
        self._bus = bus
        self.owner = owner
        self.incarnation = incarnation
        self._self_bit = self._team.bit[owner]
        self._resend = resend_period
        self._failsafe = failsafe_timeout
        self._lease = lease
        self._on_deliver = on_deliver
        self._origins = origins
        self._payloads = payloads
        self._on_finished = on_finished
        self._seq = 0
        self._pub_seq = 0
        self._states: dict[MessageId, MsgState] = {}
        self._records: dict[tuple[str, int], SeqRecord] = {}
        self._dirty: set[MessageId] = set()  # our own bits changed: publish soon
        self._replies: set[MessageId] = set()  # a peer asked and we know more
        self._now: float | None = None
        #: When each member was last heard, and who has been silent past the lease.
        self._silence = SilentMembers(lease, self._team.bit) if lease is not None else None
        self._heard: set[str] = set()  # publishers heard since the last step
        self._expired_bits = 0
        #: The messages held, paused (waiting on silent members) or active.
        self._pauses = PausedMessages(self._team.full)
        #: Unfinished messages each member brought in (see :data:`MAX_INTRODUCED`).
        self._introduced: Counter[str] = Counter()
        self._introducer: dict[MessageId, str] = {}
        self.stats = AonStats()
        #: Entries refused, by cause (a forged payload, a member over its share, ...).
        self.refused: Counter[str] = Counter()
        self.topic = topic
        if subscribe:
            bus.subscribe(topic, self._on_message)

    # ------------------------------------------------------------------ public API

    @property
    def team(self) -> tuple[str, ...]:
        """Team members, sorted by id (the bitmap order)."""
        return self._team.members

    def send(self, payload: Payload, now: float) -> MessageId:
        """Start communicating ``payload`` to the team; publishes at once (stage 1)."""
        self._clock(now)
        msg_id: MessageId = (self.owner, self.incarnation, self._seq)
        self._seq += 1
        st = MsgState(
            payload=payload,
            have=self._self_bit,
            recv=0,
            known_at=now,
            next_ask=now + self._resend,
            restart_at=now + self._failsafe,
        )
        self._states[msg_id] = st
        self._pauses.add(msg_id, st)
        self._dirty.add(msg_id)
        self._advance(msg_id, st)
        self._publish(now)
        return msg_id

    @property
    def lease(self) -> float | None:
        """Simulated s after which a silent member no longer blocks the others (None:
        never)."""
        return self._lease

    def step(self, now: float) -> None:
        """Advance time: lease checks, fail-safe restarts, re-sends and replies."""
        self._clock(now)
        if self._lease is not None:
            self._check_lease(now)
        # One pass over the messages not paused (the order changes nothing: each is
        # restarted on its own, and any one due makes a publication): a message is
        # restarted when its fail-safe time has come, and due when restarted or its
        # re-send time has come.
        due = False
        for st in self._pauses.active.values():
            restart = now >= st.restart_at
            if not (restart or st.restart or now >= st.next_ask):
                continue
            if restart:
                st.restart = True
                st.restart_at = now + self._failsafe
                self.stats.restarts += 1
            due = True
        if due or self._dirty or self._replies:
            self._publish(now)

    def heard_from(self, member: str, now: float) -> None:
        """Record that ``member`` is alive (any traffic from it, e.g. a pose)."""
        silence = self._silence
        if silence is not None and member in self._team.bit and member != self.owner:
            silence.heard_at_least(member, now)

    def pending_ids(self) -> tuple[MessageId, ...]:
        """Messages held here that have not been reported finished yet."""
        return tuple(m for m, st in self._states.items() if st.reported_left_out is None)

    def left_out_ids(self) -> tuple[MessageId, ...]:
        """Messages reported finished with left-out members; state kept to bring them
        up to date when they are heard again."""
        return tuple(m for m, st in self._states.items() if st.reported_left_out is not None)

    def holders(self, msg_id: MessageId) -> tuple[str, ...] | None:
        """The members known to have ``msg_id`` (None once its state is released)."""
        st = self._states.get(msg_id)
        if st is None:
            return None
        return self._team.names(st.have)

    def is_finished(self, msg_id: MessageId) -> bool:
        """True once ``msg_id`` has been reported finished here (also after release)."""
        st = self._states.get(msg_id)
        if st is not None:
            return st.reported_left_out is not None
        record = self._records.get((msg_id[0], msg_id[1]))
        return record is not None and msg_id[2] in record

    def memory(self) -> dict[str, int]:
        """Size of the protocol state: per-message states held, finished records and
        the out-of-order seqs those records hold above their watermark."""
        return {
            "states": len(self._states),
            "records": len(self._records),
            "record_extras": sum(len(r.above) for r in self._records.values()),
        }

    # ------------------------------------------------------------------ receiving

    def receive(self, message: Message) -> None:
        """Handle one message of the topic (what the bus calls when subscribed)."""
        self._on_message(message)

    def _on_message(self, message: Message) -> None:
        if not isinstance(message, AonMsg) or message.sender == self.owner:
            return
        publisher_bit = self._team.bit.get(message.sender)
        if publisher_bit is None or message.team_crc != self._team.crc:
            self.stats.foreign += 1
            return
        self._heard.add(message.sender)
        for entry in message.entries:
            self._on_entry(publisher_bit, entry, message.sender)

    def _on_entry(self, publisher_bit: int, entry: AonEntry, publisher: str = "") -> None:
        sender_bit = self._team.bit.get(entry.sender)
        if sender_bit is None:
            return
        msg_id: MessageId = (entry.sender, entry.incarnation, entry.seq)
        # The publisher and the original sender certainly have the message.
        have = self._team.decode(entry.have) | publisher_bit | sender_bit
        recv = self._team.decode(entry.recv)
        st = self._states.get(msg_id)
        if st is not None:
            new_have, new_recv = st.have | have, st.recv | recv
            if (new_have, new_recv) != (st.have, st.recv):
                st.have, st.recv = new_have, new_recv
                self._pauses.judge(msg_id, st, self._expired_bits)
                # Progress: postpone our own re-send.
                st.next_ask = self._time() + self._resend
            if entry.ask and (st.have & ~have or st.recv & ~recv):
                self._replies.add(msg_id)
            self._advance(msg_id, st)
            return
        record = self._records.get((entry.sender, entry.incarnation))
        if record is not None and entry.seq in record:
            self.stats.stale += 1
            if entry.ask and recv != self._team.full:
                self._replies.add(msg_id)
            return
        if entry.payload is None:
            # Knowledge about a message we never held: nothing to deliver, and keeping
            # bitmaps without the payload would not let us help anyone.
            return
        cause = self._refusal(entry, record, publisher)
        if cause:
            self.refused[cause] += 1
            return
        self._introduced[publisher] += 1
        self._introducer[msg_id] = publisher
        now = self._time()
        st = MsgState(
            payload=entry.payload,
            have=have | self._self_bit,
            recv=recv,
            known_at=now,
            next_ask=now + self._resend,
            restart_at=now + self._failsafe,
        )
        self._states[msg_id] = st
        self._pauses.add(msg_id, st)
        self._dirty.add(msg_id)  # stage 2: acknowledge
        self.stats.deliveries += 1
        self._on_deliver(entry.payload, msg_id)
        self._advance(msg_id, st)

    def _refusal(self, entry: AonEntry, record: SeqRecord | None, publisher: str) -> str:
        """Why a message new to this endpoint is not taken ("": it is)."""
        if self._origins is not None and entry.sender not in self._origins:
            return "origin may not send on this topic"
        if not isinstance(entry.payload, self._payloads):
            return "payload of the wrong type"
        if not authored_by(entry.payload, entry.sender):
            return "payload not authored by its origin"
        if self._introduced[publisher] >= MAX_INTRODUCED:
            return "member over its share of unfinished messages"
        floor = record.watermark if record is not None else 0
        if entry.seq >= floor + MAX_SEQ_AHEAD or entry.seq < 0:
            return "sequence number out of range"
        if record is None:
            known = [inc for sender, inc in self._records if sender == entry.sender]
            if len(known) >= MAX_INCARNATIONS and entry.incarnation < max(known):
                return "incarnation out of range"
        return ""

    # ------------------------------------------------------------------ progress

    def _advance(self, msg_id: MessageId, st: MsgState) -> None:
        full = self._team.full
        if st.have == full and not st.recv & self._self_bit:
            st.recv |= self._self_bit  # stage 3
            self._pauses.judge(msg_id, st, self._expired_bits)
            self._dirty.add(msg_id)
        if st.recv == full:
            self._finish(msg_id, st)  # stage 4

    def _finish(self, msg_id: MessageId, st: MsgState) -> None:
        now = self._time()
        del self._states[msg_id]
        self._pauses.remove(msg_id)
        introducer = self._introducer.pop(msg_id, None)
        if introducer is not None:
            self._introduced[introducer] -= 1
        if msg_id in self._dirty:
            # We set *received* in this very step (the last bit missing): the others
            # still need to hear it, from the finished record ("all set received").
            self._dirty.discard(msg_id)
            self._replies.add(msg_id)
        self._remember(msg_id)
        if st.reported_left_out is None:
            self._report(msg_id, st, (), now, late=False)
        elif st.reported_left_out:
            self._report(msg_id, st, (), now, late=True)

    def _remember(self, msg_id: MessageId) -> None:
        """Record ``msg_id`` as finished; of one origin, only the newest
        :data:`MAX_INCARNATIONS` incarnations are remembered."""
        key = (msg_id[0], msg_id[1])
        if key not in self._records:
            known = sorted(inc for sender, inc in self._records if sender == msg_id[0])
            for old in known[: max(0, len(known) + 1 - MAX_INCARNATIONS)]:
                del self._records[(msg_id[0], old)]
        self._records.setdefault(key, SeqRecord()).add(msg_id[2])

    def _report(
        self,
        msg_id: MessageId,
        st: MsgState,
        left_out: tuple[str, ...],
        now: float,
        *,
        late: bool,
    ) -> None:
        if not late:
            self.stats.finished += 1
            self.stats.finish_times[msg_id] = now - st.known_at
            if left_out:
                self.stats.left_out_reports += 1
        if self._on_finished is not None:
            report = FinishReport(msg_id, left_out, st.known_at, now, late=late)
            self._on_finished(msg_id, report)

    def _check_lease(self, now: float) -> None:
        assert self._silence is not None
        # A member heard again un-pauses the messages it blocked; their overdue re-send
        # then goes out at once, bringing it up to date.
        expired = self._silence.update(now)
        if expired != self._expired_bits:
            self._expired_bits = expired
            self._pauses.judge_all(self._states, expired)
        if not expired:
            return
        full = self._team.full
        for msg_id, st in self._states.items():
            if st.reported_left_out is not None:
                continue
            blockers = full & ~st.recv
            missing = full & ~st.have
            # Give up waiting only for silent members, and only once every member still
            # heard from has the message.
            if blockers & expired and not missing & ~expired:
                left_out = self._team.names(missing)
                st.reported_left_out = left_out
                self._pauses.judge(msg_id, st, expired)
                self._report(msg_id, st, left_out, now, late=False)

    # ------------------------------------------------------------------ sending

    def _publish(self, now: float) -> None:
        full = self._team.full
        if full == self._self_bit:  # a team of one: nobody to tell
            self._dirty.clear()
            self._replies.clear()
            return
        entries: list[AonEntry] = []
        asked = False
        replies = 0
        for msg_id, st in self._states.items():
            paused = msg_id in self._pauses.paused
            if paused and msg_id not in self._dirty and msg_id not in self._replies:
                continue
            ask = not paused and (now >= st.next_ask or st.restart)
            if ask:
                st.next_ask = now + self._resend
                asked = True
            if msg_id in self._replies:
                replies += 1
            entries.append(
                AonEntry(
                    sender=msg_id[0],
                    incarnation=msg_id[1],
                    seq=msg_id[2],
                    have=self._team.encode(st.have),
                    recv=self._team.encode(st.recv),
                    ask=ask,
                    payload=st.payload if st.have != full or st.restart else None,
                )
            )
            st.restart = False
        full_bytes = self._team.encode(full)
        for msg_id in self._replies:
            if msg_id in self._states:
                continue
            # Finished and released here: everyone has it and set received.
            replies += 1
            entries.append(AonEntry(msg_id[0], msg_id[1], msg_id[2], full_bytes, full_bytes))
        self._dirty.clear()
        self._replies.clear()
        for start in range(0, len(entries), MAX_ENTRIES):
            self._bus.publish(
                self.topic,
                AonMsg(
                    sender=self.owner,
                    incarnation=self.incarnation,
                    seq=self._pub_seq,
                    stamp=now,
                    team_crc=self._team.crc,
                    entries=tuple(entries[start : start + MAX_ENTRIES]),
                ),
            )
            self._pub_seq += 1
            self.stats.publications += 1
        if not entries:
            return
        self.stats.replies += replies
        if asked:
            self.stats.resend_publications += 1

    # ------------------------------------------------------------------ time

    def _clock(self, now: float) -> None:
        if self._now is None:
            for st in self._states.values():
                if st.known_at == _UNSET:
                    st.known_at = now
                    st.next_ask = now + self._resend
                    st.restart_at = now + self._failsafe
            if self._silence is not None:
                for member in self._team.members:
                    if member != self.owner:
                        self._silence.heard_first(member, now)
        self._now = now
        if self._silence is not None:
            for member in self._heard:
                self._silence.heard(member, now)
        self._heard.clear()

    def _time(self) -> float:
        return self._now if self._now is not None else _UNSET
