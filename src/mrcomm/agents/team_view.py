"""What a robot knows of its team mates, from the poses it received: each mate's last
pose, when it arrived (so its age can be asked), the role the mate announced and the
leader it follows. Collision avoidance and LF read mates from here.

A pose's age is counted from the time its sender stamped it (every member shares the
mission clock), so it includes the message's time in transit. :meth:`TeamView.known`
is the view a robot acts on: mates whose pose is too old left out, and the others moved
on along their last heading at their last speed for the pose's age (dead reckoning over
a short horizon: a robot at 0.26 m/s travels 5 cm per 0.2 s pose period, the size of
the localisation error, so a pose period or two of extrapolation corrects the lag of a
pose without inventing turns the mate may have made)."""

from __future__ import annotations

import math
from collections.abc import Collection, Iterator, Mapping, Sequence
from typing import Any, cast

import numpy as np
from numpy.typing import NDArray

from mrcomm.agents.collision import Mate, MateState
from mrcomm.compiled import KERNEL, compiled
from mrcomm.messaging.latest import NEVER, LatestMessages
from mrcomm.messaging.messages import PoseMsg


class _MateTable:
    """A receiver's row of the bus's store of latest poses (:class:`LatestMessages`):
    each mate's last pose message, position and when it was heard, as arrays indexed
    by the bus's endpoint numbers, and the order mates were first heard in (the order
    of :attr:`TeamView.poses`). The bus writes a step's poses for the whole team at
    once, so that hearing them and finding the mates near a point cost a few array
    operations, not a loop over the whole team (hearing ~1,000 poses a round into a
    dict per receiver was the O(N²) left in a team of 1,000). Read only."""

    def __init__(self, latest: LatestMessages, row: int) -> None:
        self._latest = latest
        self._row = row
        self.names = latest.members
        self.number = latest.index
        self.xs: NDArray[np.float64] = latest.columns["x"][row]  # (views of the rows)
        self.ys: NDArray[np.float64] = latest.columns["y"][row]
        #: When each member's last pose arrived (NaN: never).
        self.heard_at: NDArray[np.float64] = latest.heard_at[row]
        #: Each member's last pose message (None: never heard).
        self.pose: NDArray[np.object_] = latest.message[row]
        #: The order members were first heard in (NEVER: not yet).
        self.first: NDArray[np.int32] = latest.first[row]
        self._order: list[str] = []  # the mates' names in that order, as last asked

    @property
    def heard_count(self) -> int:
        """Mates heard so far."""
        return int(self._latest.heard_count[self._row])

    def order(self) -> list[str]:
        """The mates heard, in the order they were first heard."""
        if len(self._order) != self.heard_count:
            heard = np.flatnonzero(self.first != NEVER)
            self._order = self.names[heard[np.argsort(self.first[heard])]].tolist()
        return self._order

    def heard(self, mate: str) -> float | None:
        """When ``mate``'s last pose arrived (None: never)."""
        number = self.number.get(mate)
        if number is None or self.first[number] == NEVER:
            return None
        return float(self.heard_at[number])

    def near(self, x: float, y: float, reach: float) -> list[PoseMsg]:
        """The last pose messages of the mates whose last position is within ``reach``
        of (x, y) along both axes (the same test as ``-reach <= mate.x - x <= reach``,
        exactly), in the order they were first heard."""
        if KERNEL == "numba":
            found = np.empty(len(self.xs), dtype=np.intp)  # (per call: threads share tables' code)
            found = found[: near_numbers(self.xs, self.ys, self.first, x, y, reach, found)]
        else:
            found = near_numbers_numpy(self.xs, self.ys, self.first, x, y, reach)
        near: list[PoseMsg] = self.pose[found].tolist()
        return near


#: Found mates up to this many are put in order by insertion (the usual few), more by
#: a sort.
_INSERTION_UP_TO = 16


@compiled
def near_numbers(
    xs: Any, ys: Any, first: Any, x: float, y: float, reach: float, out: Any
) -> int:  # fmt: skip
    """Into ``out``: the numbers k whose (xs[k], ys[k]) lie within ``reach`` of (x, y)
    along both axes (NaN never does), ordered by ``first[k]``; how many. One pass, where
    numpy's expression (:func:`near_numbers_numpy`) makes six arrays: ~1 µs a query for
    100 mates instead of ~3.6 (S4 asks ~100 times a step)."""
    count = 0
    for k in range(xs.shape[0]):
        if abs(xs[k] - x) <= reach and abs(ys[k] - y) <= reach:
            out[count] = k
            count += 1
    if count > _INSERTION_UP_TO:
        found = out[:count].copy()
        order = np.argsort(first[found])
        for j in range(count):
            out[j] = found[order[j]]
        return count
    for i in range(1, count):
        k = out[i]
        rank = first[k]
        j = i
        while j > 0 and first[out[j - 1]] > rank:
            out[j] = out[j - 1]
            j -= 1
        out[j] = k
    return count


def near_numbers_numpy(
    xs: NDArray[np.float64],
    ys: NDArray[np.float64],
    first: NDArray[np.int32],
    x: float,
    y: float,
    reach: float,
) -> NDArray[np.intp]:
    """:func:`near_numbers` as numpy expressions: what runs without numba (a loop in
    Python would cost more)."""
    inside = np.abs(xs - x) <= reach
    inside &= np.abs(ys - y) <= reach
    found = inside.nonzero()[0]  # np.flatnonzero's work, without its wrappers' 1 µs
    if len(found) > 1:
        found = found[first[found].argsort()]
    return found


class _TablePoses(Mapping[str, PoseMsg]):
    """:attr:`TeamView.poses` read from a :class:`_MateTable`: each mate's last pose
    message, mates in the order they were first heard (as the dict it stands for)."""

    __slots__ = ("_table",)

    def __init__(self, table: _MateTable) -> None:
        self._table = table

    def __getitem__(self, mate: str) -> PoseMsg:
        pose = self.get(mate)
        if pose is None:
            raise KeyError(mate)
        return pose

    # get and `in` directly: Mapping's own go through __getitem__ and catch its
    # KeyError, which costs microseconds a mate never heard (LF asks ~1 M times an
    # S4 mission).
    def get(self, mate: str, default: Any = None) -> Any:
        number = self._table.number.get(mate)
        pose = None if number is None else self._table.pose[number]
        return default if pose is None else cast("PoseMsg", pose)

    def __contains__(self, mate: object) -> bool:
        return self.get(mate) is not None  # type: ignore[arg-type]

    def __iter__(self) -> Iterator[str]:
        return iter(self._table.order())

    def __len__(self) -> int:
        return self._table.heard_count


class _HeardTimes(Mapping[str, float]):
    """:attr:`TeamView.heard` read from a :class:`_MateTable`: when each mate's last
    pose arrived, mates in the order they were first heard (that of the poses)."""

    __slots__ = ("_table",)

    def __init__(self, table: _MateTable) -> None:
        self._table = table

    def __getitem__(self, mate: str) -> float:
        heard = self._table.heard(mate)
        if heard is None:
            raise KeyError(mate)
        return heard

    def get(self, mate: str, default: Any = None) -> Any:  # (see _TablePoses.get)
        heard = self._table.heard(mate)
        return default if heard is None else heard

    def __contains__(self, mate: object) -> bool:
        return self._table.heard(mate) is not None  # type: ignore[arg-type]

    def __iter__(self) -> Iterator[str]:
        return iter(self._table.order())

    def __len__(self) -> int:
        return self._table.heard_count


class TeamView:
    """Each mate's last received pose, with the time it was received.

    The pose message itself is kept: it carries everything a robot reads of a mate
    (position, heading, speed, goal distance, stamp, role, leader), and in a large team
    storing one reference per received pose, rather than a state built from it, is
    what keeps hearing a pose cheap (most of a large team's work)."""

    def __init__(self) -> None:
        #: Each mate's last pose message (a :class:`Mate` as collision avoidance reads
        #: it), mates in the order they were first heard; read-only (a dict, or read
        #: from the bus's store once attached).
        self._poses: dict[str, PoseMsg] = {}
        self.poses: Mapping[str, PoseMsg] = self._poses
        self._heard: dict[str, float] = {}
        #: When each mate's last pose arrived (the receiver's clock); read-only.
        self.heard: Mapping[str, float] = self._heard
        #: Mates whose process has gone, as the transport's liveliness says (live mode;
        #: always empty in simulation, where no process dies).
        self.departed: set[str] = set()
        #: In a large team simulated in one process, the receiver's row of the bus's
        #: store of latest poses (:meth:`attach`); None otherwise (then the heard times
        #: are a dict and :meth:`near` loops over the mates).
        self._table: _MateTable | None = None

    def attach(self, latest: LatestMessages, row: int) -> None:
        """From now on the poses are those the bus keeps in ``latest`` for the
        receiver of ``row`` (:class:`~mrcomm.ports.KeepLatest`): read, never heard here."""
        self._table = _MateTable(latest, row)
        self.poses = _TablePoses(self._table)
        self.heard = _HeardTimes(self._table)

    def hear(self, message: PoseMsg, now: float) -> None:
        """A mate's pose arrived at ``now``."""
        self.hear_all((message,), now, "")

    def hear_all(self, messages: Sequence[PoseMsg], now: float, own: str) -> None:
        """Poses that arrived together, in order (the robot's own, ``own``, left out):
        the same as hearing each in turn (the last of a mate's wins; mates keep the order
        they were first heard in): two dict updates."""
        if self._table is not None:
            raise RuntimeError("this view reads the poses the bus keeps: none is heard here")
        latest = {message.sender: message for message in messages}
        latest.pop(own, None)
        self._poses.update(latest)
        self._heard.update(dict.fromkeys(latest, now))

    def role(self, mate: str) -> str | None:
        """The role ``mate`` announced in its last pose (None if never heard)."""
        message = self.poses.get(mate)
        return None if message is None else message.role

    def leader(self, mate: str) -> str | None:
        """The robot ``mate`` said it follows ("" when none; None if never heard)."""
        message = self.poses.get(mate)
        return None if message is None else message.leader

    def age(self, mate: str, now: float) -> float:
        """Seconds since ``mate``'s last pose arrived (inf if never heard)."""
        heard = self.heard.get(mate)
        return math.inf if heard is None else now - heard

    def known(self, now: float, max_age: float | None, extrapolation: float) -> Mapping[str, Mate]:
        """Each mate as a robot should act on it at ``now``: left out when its pose is
        older than ``max_age`` (None: never), moved on for its age (at most
        ``extrapolation`` s) along its heading at its speed."""
        if max_age is None and extrapolation <= 0:
            return self.poses  # the original robots' view: every last pose, as it came
        out: dict[str, Mate] = {}
        for mate, pose in self.poses.items():
            age = max(0.0, now - pose.stamp)
            if max_age is not None and age > max_age:
                continue
            ahead = min(age, extrapolation) * pose.v
            if ahead == 0.0:
                out[mate] = pose
                continue
            out[mate] = MateState(
                pose.sender,
                pose.x + ahead * math.cos(pose.theta),
                pose.y + ahead * math.sin(pose.theta),
                pose.theta,
                pose.v,
                pose.goal_dist,
                pose.stamp,
            )
        return out

    def near(
        self,
        x: float,
        y: float,
        reach: float,
        now: float,
        max_age: float | None,
        extrapolation: float,
    ) -> Collection[Mate]:
        """The mates of :meth:`known` (same arguments) that may lie within ``reach`` of
        (x, y) along both axes, in the same order: attached to the bus's store exactly
        those (one compiled pass), else all of them (a loop would cost as much as the
        caller's own). Callers test each mate themselves, so the answer is the same
        either way."""
        table = self._table
        if table is not None and max_age is None and extrapolation <= 0:
            return table.near(x, y, reach)  # known() is the poses themselves here
        return self.known(now, max_age, extrapolation).values()

    def heard_within(self, seconds: float, now: float) -> bool:
        """Whether any mate's pose arrived less than ``seconds`` ago."""
        if self._table is not None:
            return bool(np.any(now - self._table.heard_at < seconds))  # NaN: never heard
        return any(now - t < seconds for t in self._heard.values())
