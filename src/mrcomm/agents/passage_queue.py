"""Queueing at one-lane passages, as one part of an executor: one direction at a time
through a door or corridor too narrow for two robots to pass each other.

A robot whose route enters a passage (the route its base drives, or, when the base
cannot tell, its plan; asked once per passage and goal) stops ``queue_distance``
before the entry while a mate comes the other way:

* the mate is inside the passage, heading towards the robot's side (driving, or
  standing there: a leader holding for its followers); or
* no mate inside goes the robot's way, and the mate is outside on the far side,
  driving into the passage or standing before it with a goal (queued there itself),
  nearer to it than the robot (equal: the team-wide rank decides, as right of way
  does).

Robots at both ends judge the same positions by the same rule, so one end goes first.
A mate going the robot's way is followed through, and while one is inside the far side
waits: a group crosses together.

The queued robot waits beside the mouth, out of the way of the mates coming out
(:meth:`PassageQueue.hold_point`), and drives on once no mate comes the other way, or
once the mates coming have stood still for ``queue_timeout`` (then it does not queue at
that passage again for as long: a mate stuck inside must not hold it for good). Mates
coming through keep it waiting: driving in among them would jam the passage. Only poses
heard in the last ``FRESH`` s count: who is in a passage is news.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Collection
from dataclasses import dataclass

from mrcomm.agents.collision import Mate
from mrcomm.ports import Base
from mrcomm.world.geometry import Pose
from mrcomm.world.passages import PER_M, Passage, Passages

Point = tuple[float, float]
#: How far along its route a robot looks for the entry of a passage (m).
ROUTE_LOOKAHEAD = 6.0
#: A mate heading within this angle of a direction is going that way (cosine, 60°).
HEADING_COS = 0.5
#: Goals within this distance share one route answer (m).
GOAL_QUANTUM = 0.5
#: Where a queued robot waits: this far out from the passage's mouth, and this far to
#: the side of its axis beyond the passage's half width (m): out of the way of the
#: mates coming out, who would otherwise find the waiting robot in the mouth.
HOLD_OUT = 1.0
HOLD_SIDE = 0.8
#: A mate's pose older than this (s) says nothing of who is in a passage now: poses
#: come at 5 Hz, and one last heard in a door before the mate left range would hold
#: the robot there until the time-out, every time.
FRESH = 1.0
#: A mate on the far side counts as about to enter when it is this much farther out
#: than ``queue_distance`` at most (m).
ENTRY_SLACK = 0.5


@dataclass(frozen=True)
class _Tail:
    """What a route's segments after its first waypoint say about one passage:
    ``first``, the first waypoint in the passage's frame (along, across); ``hit``, the
    first sample inside the passage among those segments within the look-ahead (None:
    none); ``lengths``, the lengths of the segments before the one with the hit."""

    first: tuple[float, float]
    lengths: tuple[float, ...]
    hit: Point | None


class PassageQueue:
    """One robot's queueing at the one-lane passages of its map."""

    def __init__(
        self,
        passages: Passages,
        queue_distance: float,
        timeout: float,
        moving_speed: float,
        rank: Callable[[str], float],
        robot: str,
    ) -> None:
        self.passages = passages
        self.queue_distance = queue_distance
        self.timeout = timeout
        self.moving_speed = moving_speed
        self._rank = rank
        self.robot = robot
        #: (passage, goal cell) -> where the route enters the passage (None: it does not).
        self._entries: dict[tuple[int, int, int], Point | None] = {}
        self._skip_until: dict[int, float] = {}
        #: The route being driven when last asked, and per passage what it says beyond
        #: its first waypoint (:meth:`_driven_tail`).
        self._tail_route: tuple[Point, ...] = ()
        self._tails: dict[int, _Tail] = {}
        #: The passages near a point, by cell (Passages.lookup, for queue_distance).
        self._near = passages.lookup(queue_distance)
        #: The passage queued for, and since when the mates coming through it have
        #: stood still (the last time one moved); None while not queueing.
        self.waiting: tuple[Passage, float] | None = None

    def wait_for(
        self,
        pose: Pose,
        goal: Point,
        mates_near: Callable[[float, float, float], Collection[Mate]],
        now: float,
        base: Base,
    ) -> tuple[Passage, Mate] | None:
        """The passage ahead to queue at and the mate coming the other way, or None.
        ``mates_near(x, y, reach)``: the known mates that may lie within ``reach``;
        ``base``: the robot's base, asked for its route to ``goal``."""
        x, y = pose.x, pose.y
        candidates = self.near(x, y)
        if not candidates or self.passages.at(x, y) is not None:
            return None  # no passage near, or inside one already: go on through
        route: tuple[Point, ...] | None = None  # the route driven to the goal, when asked
        for index in candidates:
            if self._skip_until.get(index, -math.inf) > now:
                continue
            passage = self.passages.passages[index]
            # Cheapest first: near the passage, then the route driven (no search; most
            # robots near a door pass it by), a mate coming, then a planned route (a
            # search, only once a mate comes).
            along = passage.along(x, y)
            if abs(along) - passage.half_length > self.queue_distance:
                continue
            across = passage.across(x, y)
            if abs(across) - passage.half_width > self.queue_distance:
                continue
            if route is None:
                route = self._route_to(goal, base)
            if route:
                tail = self._driven_tail(passage, route)
                entry = self._first_inside(passage, x, y, along, across, route, tail)
                if not self._enters_soon(entry, x, y):
                    continue
            mate = self._oncoming(passage, x, y, mates_near, now)
            if mate is None:
                continue
            if not route and not self._enters_soon(
                self._planned_entry(index, pose, goal, base), x, y
            ):
                continue
            self.waiting = (passage, now)
            return passage, mate
        return None

    def near(self, x: float, y: float) -> tuple[int, ...]:
        """The passages a robot at (x, y) may be within ``queue_distance`` of (asked for
        every navigating robot at every step: one lookup, no division)."""
        return self._near.get((math.floor(x * PER_M), math.floor(y * PER_M)), ())

    def _enters_soon(self, entry: Point | None, x: float, y: float) -> bool:
        """Whether the route's entry into the passage lies within ``queue_distance``."""
        return entry is not None and math.hypot(entry[0] - x, entry[1] - y) <= self.queue_distance

    @staticmethod
    def _route_to(goal: Point, base: Base) -> tuple[Point, ...]:
        """The route the base drives when it drives to ``goal`` (as it is now: a detour
        round a mate may come and go); empty when it drives elsewhere or cannot tell."""
        route = base.route
        return route if route and math.dist(route[-1], goal) <= GOAL_QUANTUM else ()

    def hold_point(self, pose: Pose) -> Point:
        """Where the queued robot waits: out of the passage's mouth on its side, to the
        side of the axis it stands on (the base snaps it to free space)."""
        assert self.waiting is not None
        passage = self.waiting[0]
        side = 1.0 if passage.along(pose.x, pose.y) >= 0 else -1.0
        lateral = 1.0 if passage.across(pose.x, pose.y) >= 0 else -1.0
        out = side * (passage.half_length + HOLD_OUT)
        off = lateral * (passage.half_width + HOLD_SIDE)
        return (
            passage.cx + passage.ax * out - passage.ay * off,
            passage.cy + passage.ay * out + passage.ax * off,
        )

    def still_waiting(
        self, pose: Pose, mates_near: Callable[[float, float, float], Collection[Mate]], now: float
    ) -> bool:
        """Whether the queued robot keeps waiting: a mate still comes the other way, and
        the mates coming have not stood still for ``timeout`` (a stream of mates coming
        through keeps it waiting; driving in among them would jam the passage). Ends
        the wait when it returns False."""
        assert self.waiting is not None
        passage, stalled_since = self.waiting
        mate = self._oncoming(passage, pose.x, pose.y, mates_near, now)
        if mate is not None and mate.v >= self.moving_speed:
            self.waiting = (passage, now)  # they come: no time-out yet
            return True
        if mate is not None and now - stalled_since < self.timeout:
            return True
        if mate is not None:  # stuck for the time-out: drive on, and do not queue there
            self._skip_until[passage.index] = now + self.timeout  # again for as long
        self.waiting = None
        return False

    def _planned_entry(self, index: int, pose: Pose, goal: Point, base: Base) -> Point | None:
        """Where the base's plan to ``goal`` enters passage ``index`` within the look
        ahead (a search of the whole route, ~30 ms on a 300 m map: asked once per
        passage and goal)."""
        key = (index, round(goal[0] / GOAL_QUANTUM), round(goal[1] / GOAL_QUANTUM))
        if key in self._entries:
            return self._entries[key]
        if len(self._entries) > 256:
            self._entries.clear()  # goals long past
        plan = base.make_plan(*goal)
        passage = self.passages.passages[index]
        x, y = pose.x, pose.y
        entry = None
        if plan:
            frame = passage.along(x, y), passage.across(x, y)
            entry = self._first_inside(passage, x, y, *frame, plan, self._tail(passage, plan))
        self._entries[key] = entry
        return entry

    def _first_inside(
        self,
        passage: Passage,
        x: float,
        y: float,
        along: float,
        across: float,
        route: tuple[Point, ...],
        tail: _Tail,
    ) -> Point | None:
        """The first point of the route from (x, y) (sampled every half cell) inside the
        passage, within :data:`ROUTE_LOOKAHEAD` of travel. ``along``, ``across``: (x, y)
        in the passage's frame; ``tail``: what :meth:`_tail` says of the route."""
        bx, by = route[0]
        hit = self._segment_hit(passage, x, y, along, across, bx, by, *tail.first)
        if hit is not None:
            return hit
        # The same sums in the same order as walking the route segment by segment.
        travelled = math.hypot(bx - x, by - y)
        if travelled > ROUTE_LOOKAHEAD or tail.hit is None:
            return None
        for length in tail.lengths:
            travelled += length
            if travelled > ROUTE_LOOKAHEAD:
                return None
        return tail.hit

    def _driven_tail(self, passage: Passage, route: tuple[Point, ...]) -> _Tail:
        """:meth:`_tail` of the route being driven, remembered per passage until the
        route changes (the robot passes a waypoint, or drives another route), as the
        robot asks at every step near a passage."""
        if route != self._tail_route:
            self._tail_route = route
            self._tails.clear()
        tail = self._tails.get(passage.index)
        if tail is None:
            tail = self._tails[passage.index] = self._tail(passage, route)
        return tail

    def _tail(self, passage: Passage, route: tuple[Point, ...]) -> _Tail:
        """What the route's segments after its first waypoint say about ``passage``
        (see :class:`_Tail`). A segment is looked at only while their lengths add up
        to at most :data:`ROUTE_LOOKAHEAD`: with the first segment's length added first,
        the sum is no less (rounding is monotonic), so farther entries are never used."""
        ax, ay = route[0]
        a_along, a_across = passage.along(ax, ay), passage.across(ax, ay)
        first = (a_along, a_across)
        lengths: list[float] = []
        travelled = 0.0
        for bx, by in route[1:]:
            b_along, b_across = passage.along(bx, by), passage.across(bx, by)
            hit = self._segment_hit(passage, ax, ay, a_along, a_across, bx, by, b_along, b_across)
            if hit is not None:
                return _Tail(first, tuple(lengths), hit)
            length = math.hypot(bx - ax, by - ay)
            lengths.append(length)
            travelled += length
            if travelled > ROUTE_LOOKAHEAD:
                break
            ax, ay, a_along, a_across = bx, by, b_along, b_across
        return _Tail(first, (), None)

    def _segment_hit(
        self,
        passage: Passage,
        ax: float,
        ay: float,
        a_along: float,
        a_across: float,
        bx: float,
        by: float,
        b_along: float,
        b_across: float,
    ) -> Point | None:
        """The first sample (every half cell, from after a to b) of the segment from a
        to b inside the passage; ``*_along``, ``*_across``: the ends in its frame."""
        res = self.passages.resolution
        # Every point of the passage's cells lies within this box round its centre (a
        # cell more than its cell centres): a segment wholly beyond one side of it has
        # no sample inside, and is not sampled.
        hl = passage.half_length + res
        hw = passage.half_width + res
        if (
            min(a_along, b_along) > hl
            or max(a_along, b_along) < -hl
            or min(a_across, b_across) > hw
            or max(a_across, b_across) < -hw
        ):
            return None
        n = max(1, math.ceil(math.hypot(bx - ax, by - ay) / (res / 2)))
        at = self.passages.at
        for i in range(1, n + 1):
            px, py = ax + (bx - ax) * i / n, ay + (by - ay) * i / n
            if at(px, py) == passage.index:
                return px, py
        return None

    def _oncoming(
        self,
        passage: Passage,
        x: float,
        y: float,
        mates_near: Callable[[float, float, float], Collection[Mate]],
        now: float,
    ) -> Mate | None:
        """A mate coming through the passage towards the robot's side (at ``x, y``),
        or, while no mate goes through it the robot's way, one about to enter it from
        the far side before the robot."""
        along = passage.along(x, y)
        side = 1.0 if along >= 0 else -1.0
        own_gap = abs(along) - passage.half_length  # how far before the passage
        reach = passage.half_length + passage.half_width + self.queue_distance + 1.0
        # Beyond these a mate is neither inside (its cells' points lie within a cell of
        # the half length and width) nor about to enter (_enters_first): skipped before
        # the cell lookup, which most mates near a door would otherwise cost.
        res = self.passages.resolution
        along_reach = passage.half_length + max(res, self.queue_distance + ENTRY_SLACK)
        across_reach = passage.half_width + max(res, self.queue_distance)
        first: Mate | None = None  # the far side's, to enter before the robot
        convoy = False  # a mate inside goes the robot's way
        for mate in mates_near(passage.cx, passage.cy, reach):
            if not now - mate.stamp <= FRESH:
                continue  # old news (or none: a NaN stamp)
            mate_along = passage.along(mate.x, mate.y)
            mate_across = passage.across(mate.x, mate.y)
            if abs(mate_along) > along_reach or abs(mate_across) > across_reach:
                continue
            towards = (math.cos(mate.theta) * passage.ax + math.sin(mate.theta) * passage.ay) * side
            if self.passages.at(mate.x, mate.y) == passage.index:
                # Coming this way, driving or not: one holding inside (a leader waiting
                # for its followers) blocks the lane as much as one driving through.
                if towards > 0:
                    return mate
                convoy = True
                continue
            if first is None and self._enters_first(
                passage, side, own_gap, mate, towards, mate_along, mate_across
            ):
                first = mate
        # Behind a mate going its way the robot follows it through: the far side waits
        # for them both. (Yielding to the far side then would split a group at the
        # lane: its leader inside holding for the follower, the follower for the far
        # side, the far side for the leader.)
        return None if convoy else first

    def _enters_first(
        self,
        passage: Passage,
        side: float,
        own_gap: float,
        mate: Mate,
        towards: float,
        mate_along: float,
        mate_across: float,
    ) -> bool:
        """Whether ``mate``, outside the passage, is on the far side about to enter it
        before the robot: driving into it or standing before it with a goal (queued
        there itself), nearer to it (equal: the team-wide rank decides). ``towards``: how
        much its heading points to the robot's side along the axis (a cosine);
        ``mate_along``, ``mate_across``: its position in the passage's frame."""
        if mate.goal_dist < 0 and mate.v < self.moving_speed:
            return False  # standing without a goal: not coming through
        if mate_along * side >= 0:
            return False  # on this side
        if mate.v >= self.moving_speed and towards < HEADING_COS:
            return False  # driving, not into the passage
        gap = abs(mate_along) - passage.half_length
        if gap > self.queue_distance + ENTRY_SLACK:
            return False
        if abs(mate_across) > passage.half_width + self.queue_distance:
            return False
        ahead = self._rank(mate.robot) < self._rank(self.robot)
        return gap < own_gap or (gap == own_gap and ahead)
