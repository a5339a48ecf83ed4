"""Which members of an AON team have been silent longer than the lease, and which
messages wait on them: kept up to date as members are heard and messages progress,
instead of looking through the whole team and every message every step.

An endpoint asks every step. Looking through its team each time cost a team of 100
(S4) 100 comparisons per robot per step as soon as one member was out of reach for
good — a tenth of an LF mission's time. Here each member that is not silent has one
entry in a heap, keyed by a time it was heard at (its last one, or an earlier one: times
heard only grow); an entry that falls out of the lease is looked at again with the
member's last time, and either marks it silent or goes back in with that time. A silent
member heard again goes back into the heap at the next look. So the answer is the same
set of members a full look would find — ``now - heard > lease`` with each member's last
time — at a cost of a few heap operations per member and lease period.
"""

from __future__ import annotations

import heapq

from mrcomm.messaging.aon_state import MessageId, MsgState


class SilentMembers:
    """The members silent for longer than ``lease`` at the last :meth:`update`, as a
    bitmap of their ``bits``."""

    __slots__ = ("_bits", "_fresh", "_heard", "_lease", "_reheard", "_silent", "bitmap")

    def __init__(self, lease: float, bits: dict[str, int]) -> None:
        self._lease = lease
        self._bits = bits
        #: Each member's last time heard (what a full look would read).
        self._heard: dict[str, float] = {}
        #: One (time heard at, member) per member not silent; the time may be older than
        #: the member's last.
        self._fresh: list[tuple[float, str]] = []
        self._silent: set[str] = set()
        self._reheard: list[str] = []  # silent members heard since the last update
        #: The silent members' bits, as of the last :meth:`update`.
        self.bitmap = 0

    def heard(self, member: str, time: float) -> None:
        """``member`` was last heard at ``time`` (normally no earlier than before)."""
        before = self._heard.get(member)
        self._heard[member] = time
        if member in self._silent:
            self._reheard.append(member)
        elif before is None or time < before:
            # A member's entry must be no later than its last time (an earlier time is
            # never given by the endpoint; kept right all the same).
            heapq.heappush(self._fresh, (time, member))

    def heard_at_least(self, member: str, time: float) -> None:
        """``member`` was heard at ``time``: its last time becomes the later of the two
        (what a member heard through other traffic is given: a pose, a heartbeat)."""
        before = self._heard.get(member)
        if before is None or time > before:
            self.heard(member, time)

    def heard_first(self, member: str, time: float) -> None:
        """``member`` counts as heard at ``time`` unless it has been heard already."""
        if member not in self._heard:
            self.heard(member, time)

    def last_heard(self, member: str) -> float | None:
        return self._heard.get(member)

    def update(self, now: float) -> int:
        """The bitmap of the members for which ``now - last heard > lease``."""
        lease = self._lease
        for member in self._reheard:
            if member in self._silent:
                self._silent.discard(member)
                self.bitmap &= ~self._bits[member]
                heapq.heappush(self._fresh, (self._heard[member], member))
        self._reheard.clear()
        fresh = self._fresh
        while fresh and now - fresh[0][0] > lease:
            _, member = heapq.heappop(fresh)
            last = self._heard[member]
            if now - last > lease:
                self._silent.add(member)
                self.bitmap |= self._bits[member]
            else:
                heapq.heappush(fresh, (last, member))
        return self.bitmap


def is_paused(st: MsgState, full: int, expired: int) -> bool:
    """Reported with left-out members that are still silent (``expired``: their bits),
    and no member heard again lacks it: re-sending is futile. (A left-out member heard
    again is brought up to date even while another is still away.)"""
    if st.reported_left_out is None:
        return False
    return (full & ~st.recv & expired) != 0 and (full & ~st.have & ~expired) == 0


class PausedMessages:
    """An endpoint's messages split into the paused ones (:func:`is_paused`) and the
    rest (``active``), judged again only where the answer can change: a message's bits
    or its left-out report, or the silent members. An endpoint's step then looks at the
    active messages only; a team whose left-out messages wait for silent members holds
    many, each past its re-send and fail-safe times (S4: 5 % of an LF mission asking
    each of them every step)."""

    __slots__ = ("_full", "active", "paused")

    def __init__(self, full: int) -> None:
        self._full = full
        self.active: dict[MessageId, MsgState] = {}
        self.paused: set[MessageId] = set()

    def add(self, msg_id: MessageId, st: MsgState) -> None:
        """A message new to the endpoint (not reported yet: never paused)."""
        self.active[msg_id] = st

    def remove(self, msg_id: MessageId) -> None:
        self.active.pop(msg_id, None)
        self.paused.discard(msg_id)

    def judge(self, msg_id: MessageId, st: MsgState, expired: int) -> None:
        """``st``'s bits or report changed (``expired``: the silent members' bits)."""
        if is_paused(st, self._full, expired):
            self.active.pop(msg_id, None)
            self.paused.add(msg_id)
        elif msg_id in self.paused:
            self.paused.discard(msg_id)
            self.active[msg_id] = st

    def judge_all(self, states: dict[MessageId, MsgState], expired: int) -> None:
        """The silent members changed: every reported message again (the others are
        never paused)."""
        for msg_id, st in states.items():
            if st.reported_left_out is not None:
                self.judge(msg_id, st, expired)
