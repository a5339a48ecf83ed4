"""The two ports every agent acts through, so the same agent runs in every mode.

* :class:`Bus` — publish/subscribe of typed messages (in-process bus in simulation,
  Zenoh in live mode). Each agent holds its own endpoint; perturbations are applied by
  the receiving endpoint.
* :class:`Base` — the robot's motion layer, like ROS move_base: ``navigate_to(goal)``,
  ``cancel()``, ``status``, ``pose``, odometry.

A bus that delivers in steps may hand a :class:`BatchHandler` each receiver's messages
of a step at once (:class:`Received`, a share of a :class:`StepBatch`), and may keep
the latest messages of a :class:`KeepLatest` subscriber itself.

Agents are stepped with ``step(now)``: they never sleep, block or read a global clock.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping, Sequence
from enum import Enum
from typing import Protocol, overload

import numpy as np
from numpy.typing import NDArray

from mrcomm.messaging.latest import LatestMessages
from mrcomm.messaging.messages import Message
from mrcomm.world.geometry import Pose

Handler = Callable[[Message], None]


class BatchHandler:
    """A handler a bus may also give several messages of one topic at once, in the order
    they reached the agent: ``handler.many(messages)`` does what ``handler(m)`` for each
    would. Only for handlers that touch nothing but their own agent's state and publish
    nothing (a team mate's pose), so taking one receiver's messages together changes no
    result. The in-process bus hands a large team's poses over this way (one call per
    receiver and step instead of one per pose); a bus that delivers one message at a
    time calls it like any handler."""

    __slots__ = ("many",)

    def __init__(self, many: Callable[[Sequence[Message]], None]) -> None:
        self.many = many

    def __call__(self, message: Message) -> None:
        self.many((message,))


class KeepLatest(BatchHandler):
    """A batch handler whose receiver keeps only each sender's latest message and when it
    arrived (a mate's pose). A bus that keeps a topic's latest messages for its
    receivers itself (the in-process bus, for a large team: see
    :mod:`mrcomm.messaging.latest`) hands the receiver its row of that store instead
    (``attach(store, row)``, once, when subscribing) and writes there, never calling the
    handler; any other bus calls it as a :class:`BatchHandler`. ``fields``: the float
    fields of a message the receiver reads as columns."""

    __slots__ = ("attach", "fields")

    def __init__(
        self,
        many: Callable[[Sequence[Message]], None],
        attach: Callable[[LatestMessages, int], None],
        fields: tuple[str, ...],
    ) -> None:
        super().__init__(many)
        self.attach = attach
        self.fields = fields


class Addressed:
    """A handler of messages addressed to one agent by a field of theirs (an
    assignment's ``robot``): it acts on those whose ``field`` is ``to`` and ignores the
    rest, so a bus may leave it uncalled for the rest. The in-process bus does when
    every plain handler of a topic is one (10,000 robots' assignments reaching 10,000
    robots were 100 million calls that returned at once)."""

    __slots__ = ("field", "handler", "to")

    def __init__(self, handler: Handler, field: str, to: str) -> None:
        self.handler = handler
        self.field = field
        self.to = to

    def __call__(self, message: Message) -> None:
        if getattr(message, self.field) == self.to:
            self.handler(message)


#: A receiver's share of at least this many messages is picked from the batch as an
#: array (one call), a smaller one message by message (cheaper than numpy's overhead).
PICK_FROM = 64


class StepBatch:
    """Messages of one topic delivered together in one step, as a bus that delivers in
    steps (the in-process bus) hands them to :class:`BatchHandler` s: the messages, each
    one's sender as the bus numbers the team's endpoints (its place in ``members``, the
    same every step), and columns of a message field as arrays, made once for all
    receivers of the batch. A receiver gets its share as :class:`Received`."""

    __slots__ = (
        "_columns",
        "_distinct",
        "_objects",
        "index",
        "members",
        "messages",
        "senders",
    )

    def __init__(
        self,
        messages: Sequence[Message],
        senders: NDArray[np.intp],
        members: NDArray[np.object_],
        index: Mapping[str, int],
    ) -> None:
        self.messages = messages
        self.senders = senders
        #: The team's endpoints (agent ids) by number, and each one's number (the bus's,
        #: shared by all its batches).
        self.members = members
        self.index = index
        self._distinct: bool | None = None
        self._objects: NDArray[np.object_] | None = None
        self._columns: dict[str, NDArray[np.float64]] = {}

    @property
    def distinct(self) -> bool:
        """No sender has two messages in the batch (found when first asked)."""
        if self._distinct is None:
            self._distinct = len(set(self.senders.tolist())) == len(self.senders)
        return self._distinct

    def objects(self) -> NDArray[np.object_]:
        """The messages as an array (picking a receiver's share is then one call)."""
        if self._objects is None:
            objects = np.empty(len(self.messages), dtype=object)
            objects[:] = self.messages
            self._objects = objects
        return self._objects

    def column(self, field: str) -> NDArray[np.float64]:
        """A float field of every message, in order."""
        values = self._columns.get(field)
        if values is None:
            values = np.fromiter(
                (getattr(m, field) for m in self.messages), np.float64, len(self.messages)
            )
            self._columns[field] = values
        return values


class Received(Sequence[Message]):
    """One receiver's share of a :class:`StepBatch`: the messages at ``rows`` (in the
    order they reached it). Reads as the sequence of those messages."""

    __slots__ = ("batch", "rows")

    def __init__(self, batch: StepBatch, rows: NDArray[np.intp]) -> None:
        self.batch = batch
        self.rows = rows

    def __len__(self) -> int:
        return len(self.rows)

    @overload
    def __getitem__(self, index: int) -> Message: ...
    @overload
    def __getitem__(self, index: slice) -> Sequence[Message]: ...
    def __getitem__(self, index: int | slice) -> Message | Sequence[Message]:
        if isinstance(index, slice):
            return self.messages()[index]
        return self.batch.messages[int(self.rows[index])]

    def __iter__(self) -> Iterator[Message]:
        return iter(self.messages())

    def messages(self) -> list[Message]:
        """The messages, as a list."""
        if len(self.rows) < PICK_FROM:
            messages = self.batch.messages
            return [messages[row] for row in self.rows.tolist()]
        picked: list[Message] = self.batch.objects()[self.rows].tolist()
        return picked


class Bus(Protocol):
    """One agent's endpoint on the team's publish/subscribe network."""

    @property
    def owner(self) -> str:
        """Id of the agent this endpoint belongs to."""
        ...

    def publish(self, topic: str, message: Message) -> None:
        """Send a message to every subscriber of ``topic`` (best effort)."""
        ...

    def subscribe(self, topic: str, handler: Handler) -> None:
        """Call ``handler(message)`` for each message on ``topic`` that reaches us."""
        ...


class NavStatus(Enum):
    """State of the current navigation goal, as move_base reports it."""

    IDLE = "idle"
    ACTIVE = "active"
    SUCCEEDED = "succeeded"
    ABORTED = "aborted"


class Base(Protocol):
    """A robot's navigation stack."""

    def navigate_to(self, x: float, y: float) -> None:
        """Start driving to a goal (replaces any current goal)."""
        ...

    def cancel(self) -> None:
        """Stop and drop the current goal (status becomes IDLE)."""
        ...

    @property
    def status(self) -> NavStatus: ...

    @property
    def pose(self) -> Pose:
        """Localised pose estimate in the map frame."""
        ...

    @property
    def odometry_distance(self) -> float:
        """Distance travelled so far according to wheel odometry (m)."""
        ...

    @property
    def speed(self) -> float:
        """Current forward speed (m/s)."""
        ...

    def make_plan(self, x: float, y: float) -> tuple[tuple[float, float], ...] | None:
        """The route the navigation would take to (x, y) from the current pose, as
        waypoints (like move_base's ``make_plan`` service); None when there is none or
        the base cannot tell."""
        ...

    @property
    def route(self) -> tuple[tuple[float, float], ...]:
        """The waypoints still ahead on the route being driven, ending at the current
        goal (what Nav2 publishes on ``/plan``); empty when not driving one or the base
        cannot tell. Costs no search, unlike :meth:`make_plan`."""
        ...


class LinkSensor(Protocol):
    """How an agent judges its link to a team mate (SLT distance, SSD predicted RSSI,
    ESD measured RSSI). Evaluated from the robot's own pose and the mate's last known
    position, as the original did."""

    #: Whether the sensor judges from positions (SLT, SSD), not measurements (ESD).
    positional: bool

    def warning(self, peer: str, own: Pose, peer_x: float, peer_y: float, now: float) -> bool:
        """True when the link to ``peer`` has crossed the warning threshold."""
        ...

    def rssi(self, peer: str, own: Pose, peer_x: float, peer_y: float, now: float) -> float | None:
        """Signal strength estimate (dBm), where the sensor has one."""
        ...

    def warning_between(self, ax: float, ay: float, bx: float, by: float) -> bool | None:
        """Whether a link between two other positions (two mates) would be in warning,
        judged by the same rule; None when the sensor judges only the robot's own links
        (a measured RSSI exists only for them)."""
        ...
