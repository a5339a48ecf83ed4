"""Bookkeeping of the AON protocol: message ids, member bitmaps, per-message state,
the compact record of finished messages, finish reports and statistics.

Nothing here talks to the bus; :mod:`mrcomm.messaging.aon` drives these structures.
"""

from __future__ import annotations

import zlib
from collections.abc import Sequence
from dataclasses import dataclass, field

from mrcomm.messaging.messages import OperatorCommand, TaskStatus

#: Identity of an AON message: (sender id, sender incarnation, sender's AON sequence).
MessageId = tuple[str, int, int]


class TeamIndex:
    """Maps team members to bit positions. Members are ordered by id, so every member
    derives the same bitmaps from the same team whatever order it was given in."""

    def __init__(self, team: Sequence[str]) -> None:
        members = tuple(sorted(team))
        if not members:
            raise ValueError("AON team must not be empty")
        if len(set(members)) != len(members):
            raise ValueError(f"AON team has duplicate members: {list(team)}")
        self.members: tuple[str, ...] = members
        self.bit: dict[str, int] = {m: 1 << i for i, m in enumerate(members)}
        self.full: int = (1 << len(members)) - 1
        self.nbytes: int = (len(members) + 7) // 8
        # A checksum of the team on every publication: a peer configured with another
        # team would misread the bitmaps, so its publications are ignored instead.
        self.crc: int = zlib.crc32("\n".join(members).encode())

    def encode(self, bits: int) -> bytes:
        """Bitmap as little-endian bytes (any team size, unlike a 64-bit integer)."""
        return bits.to_bytes(self.nbytes, "little")

    def decode(self, data: bytes) -> int:
        """Inverse of :meth:`encode`; bits beyond the team are ignored."""
        return int.from_bytes(data, "little") & self.full

    def names(self, bits: int) -> tuple[str, ...]:
        """Members whose bit is set, in team order."""
        return tuple(m for m in self.members if bits & self.bit[m])


class SeqRecord:
    """Finished sequence numbers of one (sender, incarnation): every seq below
    ``watermark`` plus a (normally tiny) set above it, so memory stays bounded by how
    far out of order messages finish, not by how many were sent."""

    __slots__ = ("above", "watermark")

    def __init__(self) -> None:
        self.watermark = 0
        self.above: set[int] = set()

    def add(self, seq: int) -> None:
        if seq < self.watermark:
            return
        if seq != self.watermark:
            self.above.add(seq)
            return
        self.watermark += 1
        while self.watermark in self.above:
            self.above.remove(self.watermark)
            self.watermark += 1

    def __contains__(self, seq: object) -> bool:
        return isinstance(seq, int) and (seq < self.watermark or seq in self.above)


@dataclass(slots=True)
class MsgState:
    """What one member knows about one message it holds and has not yet released."""

    payload: TaskStatus | OperatorCommand
    #: Members known (from real receipts) to have the message.
    have: int
    #: Members known to have set *received* (each knew every member had it).
    recv: int
    #: When this member first held the message.
    known_at: float
    #: When to re-send asking for replies if nothing was learnt meanwhile.
    next_ask: float
    #: When the fail-safe restarts the exchange.
    restart_at: float
    #: Members named as left out in the FinishReport already issued (lease expiry);
    #: ``None`` while no report has been issued.
    reported_left_out: tuple[str, ...] | None = None
    #: The next publication re-announces the message (payload and a request to reply).
    restart: bool = False


@dataclass(frozen=True, slots=True)
class FinishReport:
    """How communication of one message ended at this member.

    ``left_out`` is empty when every member is known to have the message. It names the
    members that are not known to have it when the message was given up on because they
    had been silent longer than the lease. ``late`` marks the second report of a
    message first reported with left-out members, once they have it too.
    """

    msg_id: MessageId
    left_out: tuple[str, ...]
    started: float
    finished: float
    late: bool = False

    @property
    def duration(self) -> float:
        return self.finished - self.started


@dataclass
class AonStats:
    """Counters of one AON endpoint (AON re-sends and completion times)."""

    #: AON publications made by this member.
    publications: int = 0
    #: Publications that re-sent at least one message because no progress came.
    resend_publications: int = 0
    #: Entries published to answer a peer that asked (incl. from finished records).
    replies: int = 0
    #: Fail-safe restarts of an exchange.
    restarts: int = 0
    #: Payloads handed to the application.
    deliveries: int = 0
    #: Entries about messages already finished and released here (stale copies).
    stale: int = 0
    #: Publications ignored: from a non-member or a peer configured with another team.
    foreign: int = 0
    #: Messages finished here (strictly or with left-out members).
    finished: int = 0
    #: Finish reports naming left-out members.
    left_out_reports: int = 0

    def counters(self) -> dict[str, int]:  # keys: AON_COUNTERS
        """The integer counters, by name (for results and journals)."""
        return {
            "publications": self.publications,
            "resend_publications": self.resend_publications,
            "replies": self.replies,
            "restarts": self.restarts,
            "deliveries": self.deliveries,
            "finished": self.finished,
            "left_out_reports": self.left_out_reports,
        }

    #: Seconds from first holding a message to its (first) finish, per message.
    finish_times: dict[MessageId, float] = field(default_factory=dict)


#: The names of :meth:`AonStats.counters`, as results and journals carry them.
AON_COUNTERS = (
    "publications",
    "resend_publications",
    "replies",
    "restarts",
    "deliveries",
    "finished",
    "left_out_reports",
)
