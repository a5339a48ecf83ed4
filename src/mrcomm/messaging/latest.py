"""What each receiver last heard from each sender on one topic, as arrays: kept by a bus
that delivers a step's messages to many receivers at once (the in-process bus, for a
team of :data:`KEEP_LATEST_FROM` endpoints or more), so that a step's poses are recorded
for the whole team with a few array operations instead of one call per receiver.

This is the keep-last (depth 1) subscription of ROS topics, which the original robots'
pose topics were, per receiver and sender: the latest message, when it arrived, the
order in which each receiver first heard its senders, and chosen float fields of the
message as columns (a pose's ``x`` and ``y``, for finding mates near a point). Only the
bus writes; a receiver reads its own row (the row of its endpoint number).

In a team of n endpoints the store holds n² entries of each kind (36 bytes an entry
with two columns: 36 MB for 1,000 robots), the same as one row per receiver kept by the
receivers themselves.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping

import numpy as np
from numpy.typing import NDArray

from mrcomm.messaging.messages import Message

#: A bus keeps the latest messages of a topic for its receivers when the team has at
#: least this many endpoints; below it a receiver's own dict costs less than the arrays'
#: upkeep and numpy's per-call overhead (measured: see agents/team_view.py).
KEEP_LATEST_FROM = 64
#: In :attr:`LatestMessages.first`: never heard.
NEVER = np.iinfo(np.int32).max
#: A step's (message, receiver) pairs are handled at most about this many at a time
#: (:func:`bounded_blocks`): their masks, draws and index arrays take ~40 bytes a pair.
_BLOCK_ENTRIES = 1 << 20


def bounded_blocks(count: int, width: int) -> Iterator[slice]:
    """Consecutive slices of ``count`` items (a step's receivers, or its messages), each
    item ``width`` entries wide (the messages, or the receivers), with at most about
    :data:`_BLOCK_ENTRIES` entries a slice: receivers independent of each other, taken a
    block at a time, keep a large team's step arrays small (5,000 poses reaching 10,000
    receivers at once took ~9 GB of them)."""
    block = max(1, _BLOCK_ENTRIES // max(1, width))
    for start in range(0, count, block):
        yield slice(start, min(count, start + block))


class LatestMessages:
    """Each receiver's latest message from each sender on one topic, ``[receiver,
    sender]`` by the bus's endpoint numbers, and what goes with it."""

    def __init__(
        self, members: NDArray[np.object_], index: Mapping[str, int], fields: tuple[str, ...]
    ) -> None:
        n = len(members)
        #: The endpoints' names by number, and each name's number (the bus's).
        self.members = members
        self.index = index
        self.fields = fields
        #: The latest message (None: never heard).
        self.message: NDArray[np.object_] = np.full((n, n), None, dtype=object)
        #: When it arrived (NaN: never).
        self.heard_at: NDArray[np.float64] = np.full((n, n), np.nan)
        #: The order in which the receiver first heard each sender (0, 1, ...; NEVER).
        self.first: NDArray[np.int32] = np.full((n, n), NEVER, dtype=np.int32)
        #: How many senders each receiver has heard.
        self.heard_count: NDArray[np.int64] = np.zeros(n, dtype=np.int64)
        #: Each of ``fields`` of the latest message (NaN: never heard).
        self.columns: dict[str, NDArray[np.float64]] = {f: np.full((n, n), np.nan) for f in fields}
        #: Which endpoints' messages are kept here (their subscription asked for it).
        self.keeps: NDArray[np.bool_] = np.zeros(n, dtype=np.bool_)

    def write(self, receiver: int, sender: int, message: Message, now: float) -> None:
        """``message`` from ``sender`` reached ``receiver`` at ``now``."""
        if self.first[receiver, sender] == NEVER:
            self.first[receiver, sender] = self.heard_count[receiver]
            self.heard_count[receiver] += 1
        self.message[receiver, sender] = message
        self.heard_at[receiver, sender] = now
        for field, column in self.columns.items():
            column[receiver, sender] = getattr(message, field)

    def write_step(
        self,
        messages: NDArray[np.object_],
        senders: NDArray[np.intp],
        receivers: NDArray[np.intp],
        received: NDArray[np.bool_],
        columns: Mapping[str, NDArray[np.float64]],
        now: float,
    ) -> None:
        """Messages delivered together at ``now``: ``received[m, c]`` says whether
        ``messages[m]`` (from ``senders[m]``) reached ``receivers[c]``; ``columns``: each
        field of every message. The same as :meth:`write` for each pair, message by
        message, when no sender has two messages here (the caller's to check).

        Receivers are written a block at a time (:func:`bounded_blocks`: they do not
        touch each other's entries)."""
        for block in bounded_blocks(len(receivers), len(senders)):
            self._write_block(messages, senders, receivers[block], received[:, block], columns, now)

    def _write_block(
        self,
        messages: NDArray[np.object_],
        senders: NDArray[np.intp],
        receivers: NDArray[np.intp],
        received: NDArray[np.bool_],
        columns: Mapping[str, NDArray[np.float64]],
        now: float,
    ) -> None:
        heard_by, heard = np.nonzero(received.T)  # receiver by receiver, messages in order
        if not len(heard):
            return
        n = len(self.members)
        at = receivers[heard_by] * n + senders[heard]  # flat [receiver, sender]
        first = self.first.reshape(-1)
        new = first[at] == NEVER
        if new.any():
            # A receiver's new senders are ranked after those it heard before, in the
            # order their messages reached it.
            new_at, new_by = at[new], heard_by[new]
            place = np.arange(len(new_by))
            starts = np.r_[True, new_by[1:] != new_by[:-1]]
            place -= np.maximum.accumulate(np.where(starts, place, 0))
            new_receivers = receivers[new_by]
            first[new_at] = self.heard_count[new_receivers] + place
            self.heard_count += np.bincount(new_receivers, minlength=n)
        self.message.reshape(-1)[at] = messages[heard]
        self.heard_at.reshape(-1)[at] = now
        for field, column in self.columns.items():
            column.reshape(-1)[at] = columns[field][heard]
