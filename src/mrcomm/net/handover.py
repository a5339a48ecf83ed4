"""Handing a batch of messages on one topic to its receivers, once the bus has decided
who got which (:class:`~mrcomm.net.inprocess.InProcessNetwork`): the same calls, in the
same order, as one message at a time would make, with less work for a large team.

* A :class:`~mrcomm.ports.KeepLatest` receiver's messages are written into the bus's
  store of latest messages (:mod:`mrcomm.messaging.latest`) for all such receivers at
  once; its handler is never called.
* A :class:`~mrcomm.ports.BatchHandler` gets each receiver's share of the batch in one
  call (receiver-local, publishing nothing), receivers a block at a time.
* The other handlers, which may publish, are called message by message, in order; when
  every one is :class:`~mrcomm.ports.Addressed`, only where a message names them.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mrcomm.messaging.latest import LatestMessages, bounded_blocks
from mrcomm.messaging.messages import Message
from mrcomm.ports import Addressed, BatchHandler, Handler, Received, StepBatch


@dataclass(frozen=True)
class Takers:
    """A topic's receivers split by how they take a batch (made once, again after each
    subscription): batch handlers get a receiver's messages in one call, the others one
    message at a time."""

    targets: list[int]  # receiver indices, in subscription order
    many: list[list[Callable[[Sequence[Message]], None]]]  # each receiver's batch handlers
    batched: bool  # any receiver has one
    plain_columns: list[int]  # columns (of targets) of receivers with other handlers
    plain: list[list[Handler]]  # those receivers' other handlers
    kept_columns: NDArray[np.intp]  # columns of receivers whose latest messages the bus keeps
    #: When every plain handler is an Addressed one, on one field, each receiver's to one
    #: addressee: that field, and the plain columns of each addressee (a message then
    #: acts only at the columns it names).
    addressed_by: str | None
    addressed: dict[str, list[int]] | None

    @classmethod
    def of(cls, receivers: dict[int, list[Handler]], latest: LatestMessages | None) -> Takers:
        many = [[h.many for h in hs if isinstance(h, BatchHandler)] for hs in receivers.values()]
        others = [[h for h in hs if not isinstance(h, BatchHandler)] for hs in receivers.values()]
        columns = [column for column, hs in enumerate(others) if hs]
        plain = [others[column] for column in columns]
        targets = list(receivers)
        kept = [] if latest is None else np.flatnonzero(latest.keeps[targets]).tolist()
        # Addressed handlers only, on one field, one addressee per receiver: by addressee.
        fields = {h.field if isinstance(h, Addressed) else None for hs in plain for h in hs}
        addressees = [{h.to for h in hs if isinstance(h, Addressed)} for hs in plain]
        addressed: dict[str, list[int]] | None = None
        if len(fields) == 1 and None not in fields and all(len(to) == 1 for to in addressees):
            addressed = {}
            for k, to in enumerate(addressees):
                addressed.setdefault(to.pop(), []).append(k)
        kept_columns = np.array(kept, dtype=np.intp)
        field = fields.pop() if addressed is not None else None
        return cls(targets, many, any(many), columns, plain, kept_columns, field, addressed)


def hand_over(
    takers: Takers,
    batch: StepBatch,
    received: NDArray[np.bool_],
    received_n: list[int] | None,
    latest: LatestMessages | None,
    now: float,
) -> None:
    """Call the handlers of a batch's receivers: ``received[m, c]`` says whether the
    receiver of column c (of ``takers.targets``) got message m of ``batch``;
    ``received_n``: how many each got (None: counted here); ``latest``: the topic's
    store of latest messages (None: not kept); ``now``: when they arrived."""
    messages, rows = batch.messages, batch.senders
    if latest is not None and len(takers.kept_columns):
        keep_latest(latest, batch, takers, received, now)
    if takers.batched:
        if received_n is None:
            received_n = received.sum(axis=0).tolist()
        for block in bounded_blocks(len(takers.targets), len(rows)):
            by_receiver = np.nonzero(received[:, block].T)[1]  # receiver by receiver
            end = 0
            for column in range(block.start, block.stop):
                start, end = end, end + received_n[column]
                takes = takers.many[column]
                if takes and end > start:
                    heard = Received(batch, by_receiver[start:end])
                    for take in takes:
                        take(heard)
    handlers = takers.plain
    if not handlers:
        return
    if len(handlers) < len(takers.targets):
        received = received[:, takers.plain_columns]
    field, addressed = takers.addressed_by, takers.addressed
    if field is not None and addressed is not None:
        # Each message acts only at the receivers it names: the other calls would
        # return at once. The calls that act come in the same order.
        for row, message in enumerate(messages):
            for column in addressed.get(getattr(message, field), ()):
                if received[row, column]:
                    for handler in handlers[column]:
                        handler(message)
        return
    for block in bounded_blocks(len(messages), len(handlers)):  # messages, a block
        heard_rows, heard_columns = np.nonzero(received[block])  # message by message
        for row, column in zip(heard_rows.tolist(), heard_columns.tolist(), strict=True):
            message = messages[block.start + row]
            for handler in handlers[column]:
                handler(message)


def keep_latest(
    latest: LatestMessages,
    batch: StepBatch,
    takers: Takers,
    received: NDArray[np.bool_],
    now: float,
) -> None:
    """Write a batch into the store of latest messages for the receivers kept there:
    at once, or (a sender with two messages in the batch) message by message."""
    kept = takers.kept_columns
    receivers = np.array(takers.targets, dtype=np.intp)[kept]
    received = received[:, kept]
    if batch.distinct:
        columns = {field: batch.column(field) for field in latest.fields}
        latest.write_step(batch.objects(), batch.senders, receivers, received, columns, now)
        return
    senders = batch.senders.tolist()
    for row, column in zip(*np.nonzero(received), strict=True):
        latest.write(int(receivers[column]), senders[row], batch.messages[row], now)
