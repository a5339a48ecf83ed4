"""Queueing at one-lane passages: a robot about to enter a door waits while a mate
comes through it the other way, or is about to from the far side and nearer; it
follows a mate going its way; of two robots meeting at a door exactly one waits; the
wait has a time-out. Then the NB executor queueing on a fake base."""

from __future__ import annotations

import math
import random

import pytest

from mrcomm.agents.collision import MateState
from mrcomm.agents.executor import TaskExecutor
from mrcomm.agents.passage_queue import ROUTE_LOOKAHEAD, PassageQueue
from mrcomm.metrics import labels as L
from mrcomm.world.geometry import Pose
from mrcomm.world.passages import Passages, find_passages
from tests.world.test_passages import two_rooms

from .fakes import Harness, pose_of, task

GOAL = (8.0, 3.0)  # beyond the door (x = 5, y = 2.55..3.5) from the west room
EAST, WEST = 0.0, math.pi


@pytest.fixture(scope="module")
def door() -> Passages:
    return find_passages(two_rooms(0.9), max_width=1.3)


def mate(
    robot: str, x: float, theta: float, v: float = 0.4, y: float = 3.0, stamp: float = 0.0
) -> MateState:
    return MateState(robot, x, y, theta, v, goal_dist=3.0 if v > 0 else -1.0, stamp=stamp)


class Plans:
    """A base that plans a straight line to the goal (counted) and drives ``route``."""

    def __init__(
        self, start: tuple[float, float], route: tuple[tuple[float, float], ...] = ()
    ) -> None:
        self.start = start
        self.route = route
        self.calls = 0

    def make_plan(self, x: float, y: float) -> tuple[tuple[float, float], ...]:
        return self(x, y)

    def __call__(self, x: float, y: float) -> tuple[tuple[float, float], ...]:
        self.calls += 1
        return (self.start, (x, y))


def queue_of(door: Passages, robot: str = "robot_1") -> PassageQueue:
    ranks = {"robot_1": 0.0, "robot_2": 1.0}
    return PassageQueue(door, 1.5, 30.0, 0.05, ranks.__getitem__, robot)  # 30 s time-out


def waits(
    q: PassageQueue, x: float, mates: list[MateState], goal=GOAL, now: float = 0.0, theta=EAST
) -> str | None:
    found = q.wait_for(Pose(x, 3.0, theta), goal, lambda *_: mates, now, Plans((x, 3.0)))
    return None if found is None else found[1].robot


def test_waits_for_a_mate_coming_through_the_door_not_for_one_going_its_way(
    door: Passages,
) -> None:
    assert waits(queue_of(door), 3.7, [mate("robot_2", 5.07, WEST)]) == "robot_2"
    assert waits(queue_of(door), 3.7, [mate("robot_2", 5.07, EAST)]) is None
    # standing in the door facing this way, without a goal (a leader holding for its
    # followers): it blocks the door all the same
    assert waits(queue_of(door), 3.7, [mate("robot_2", 5.07, WEST, v=0.0)]) == "robot_2"
    # standing before the door on the far side without a goal: not coming through
    assert waits(queue_of(door), 3.7, [mate("robot_2", 5.8, WEST, v=0.0)]) is None


def test_waits_only_near_the_entry_and_only_when_its_route_goes_through(
    door: Passages,
) -> None:
    coming = [mate("robot_2", 5.07, WEST)]
    assert waits(queue_of(door), 2.5, coming) is None  # 2.5 m before the door: drives on
    assert waits(queue_of(door), 5.07, coming) is None  # inside already: goes through
    q = queue_of(door)
    plans = Plans((3.7, 3.0))
    pose = Pose(3.7, 3.0, EAST)
    for _ in range(3):  # its goal lies in its own room: the route does not enter
        assert q.wait_for(pose, (3.0, 1.0), lambda *_: coming, 0.0, plans) is None
    assert plans.calls == 1  # planned once per passage and goal


def test_the_route_being_driven_to_the_goal_is_asked_before_any_plan(door: Passages) -> None:
    coming = [mate("robot_2", 5.07, WEST)]
    pose = Pose(3.7, 3.0, EAST)
    # driving to the goal along a route that turns away before the door: no wait, and
    # no search (the straight plan would enter the door)
    away = Plans((3.7, 3.0), route=((3.7, 1.0), (4.0, 1.0), GOAL))
    assert queue_of(door).wait_for(pose, GOAL, lambda *_: coming, 0.0, away) is None
    assert away.calls == 0
    # driving through the door: waits, still without a search
    through = Plans((3.7, 3.0), route=((5.0, 3.0), GOAL))
    found = queue_of(door).wait_for(pose, GOAL, lambda *_: coming, 0.0, through)
    assert found is not None and found[1].robot == "robot_2" and through.calls == 0
    # the route being driven goes elsewhere (an older goal): the base plans
    elsewhere = Plans((3.7, 3.0), route=((3.7, 1.0), (3.0, 1.0)))
    found = queue_of(door).wait_for(pose, GOAL, lambda *_: coming, 0.0, elsewhere)
    assert found is not None and elsewhere.calls == 1


def test_the_robot_waits_beside_the_mouth_on_its_own_side(door: Passages) -> None:
    q = queue_of(door)
    assert waits(q, 3.7, [mate("robot_2", 5.07, WEST)]) == "robot_2"
    x, y = q.hold_point(Pose(3.7, 3.2, EAST))
    passage = door.passages[0]
    assert x == pytest.approx(passage.cx - passage.half_length - 1.0, abs=0.01)
    assert y == pytest.approx(passage.cy + passage.half_width + 0.8, abs=0.01)
    assert q.hold_point(Pose(3.7, 2.8, EAST))[1] < passage.cy - passage.half_width


def test_of_two_robots_meeting_at_a_door_the_nearer_goes_and_the_other_waits(
    door: Passages,
) -> None:
    # robot_1 1.1 m before the door from the west, robot_2 0.5 m before it from the east
    west = queue_of(door, "robot_1")
    east = queue_of(door, "robot_2")
    r1, r2 = mate("robot_1", 3.9, EAST), mate("robot_2", 5.8, WEST)
    assert waits(west, 3.9, [r2]) == "robot_2"
    assert waits(east, 5.8, [r1], goal=(1.0, 3.0), theta=WEST) is None
    # both queued, standing: still the nearer goes first and only the other waits
    r1, r2 = r1._replace(v=0.0), r2._replace(v=0.0)
    assert waits(east, 5.8, [r1], goal=(1.0, 3.0), theta=WEST) is None
    assert waits(west, 3.9, [r2]) == "robot_2"
    # a mate farther from its side of the door than the robot is from its own waits
    assert waits(queue_of(door), 3.9, [mate("robot_2", 6.8, WEST)]) is None


def test_the_wait_ends_when_the_door_is_clear_or_after_the_time_out(door: Passages) -> None:
    q = queue_of(door)
    pose = Pose(3.7, 3.0, EAST)

    def coming(now: float, v: float = 0.4) -> list[MateState]:
        # v = 0: stuck in the door (with a goal still)
        return [mate("robot_2", 5.07, WEST, stamp=now - 0.2)._replace(v=v, goal_dist=2.0)]

    assert waits(q, 3.7, coming(0.0), now=0.0) == "robot_2"
    assert q.still_waiting(pose, lambda *_: coming(10.0), 10.0)
    assert not q.still_waiting(pose, lambda *_: [], 11.0)  # it came through: go on
    assert q.waiting is None
    assert waits(q, 3.7, coming(12.0), now=12.0) == "robot_2"
    # mates coming through, moving, keep it waiting past the time-out
    assert q.still_waiting(pose, lambda *_: coming(50.0), 50.0)
    # one stuck in the door holds it for 30 s, then it drives on
    assert q.still_waiting(pose, lambda *_: coming(79.9, v=0.0), 79.9)
    assert not q.still_waiting(pose, lambda *_: coming(80.0, v=0.0), 80.0)
    assert waits(q, 3.7, coming(90.0), now=90.0) is None  # and no queueing there for 30 s
    assert waits(q, 3.7, coming(110.1), now=110.1) == "robot_2"


def test_a_pose_heard_more_than_a_second_ago_says_nothing_of_who_is_in_the_door(
    door: Passages,
) -> None:
    assert waits(queue_of(door), 3.7, [mate("robot_2", 5.07, WEST, stamp=-1.0)]) == "robot_2"
    assert waits(queue_of(door), 3.7, [mate("robot_2", 5.07, WEST, stamp=-1.1)]) is None
    no_stamp = mate("robot_2", 5.07, WEST)._replace(stamp=math.nan)
    assert waits(queue_of(door), 3.7, [no_stamp]) is None


def test_the_nb_executor_queues_before_the_door_and_drives_on_once_clear(
    door: Passages,
) -> None:
    h = Harness(TaskExecutor, passages=door)
    h.base.pose = Pose(3.7, 3.0, EAST)
    h.assign([task("t", *GOAL)])
    assert h.step() == "navigating"
    coming = dict(theta=WEST, v=0.4, goal_dist=4.0)
    h.hear(pose_of("robot_2", 5.07, 3.0, stamp=h.now, **coming))
    assert h.step() == "avoiding"
    hold = h.base.goal  # it waits out of the door's mouth, to the side of its axis
    assert hold is not None and hold[0] < 4.5 and abs(hold[1] - 3.0) > 1.0
    assert [e.data["mate"] for e in h.timeline.events if e.label == L.QUEUED] == ["robot_2"]
    for _ in range(20):  # still coming through (stuck in the door, say): keeps waiting
        h.hear(pose_of("robot_2", 5.07, 3.0, stamp=h.now, **coming))
        assert h.step() == "avoiding"
    h.hear(pose_of("robot_2", 4.0, 4.5, stamp=h.now, **coming))  # through, and by
    assert h.step() == "navigating"
    assert h.base.goal == GOAL


def test_a_wait_cut_short_is_over_and_a_later_near_collision_pauses_as_usual(
    door: Passages,
) -> None:
    """Queued, the robot is taken out of ``avoiding`` by something else (LF: a role
    round). The wait is over: a near collision later is judged by collision avoidance
    (a pause of at least ``collision_pause``), not ended at once as a finished wait."""
    h = Harness(TaskExecutor, passages=door)
    h.base.pose = Pose(3.7, 3.0, EAST)
    h.assign([task("t", *GOAL)])
    h.step()
    h.hear(pose_of("robot_2", 5.07, 3.0, WEST, stamp=h.now, v=0.4, goal_dist=4.0))
    assert h.step() == "avoiding" and h.agent.queue is not None
    assert h.agent.queue.waiting is not None
    h.agent.trigger("resume")  # taken out of the wait by something else
    assert h.agent.queue.waiting is None
    h.base.pose = Pose(1.0, 1.0, EAST)  # far from the door now
    h.hear(pose_of("robot_3", 1.3, 1.0, WEST, stamp=h.now, seq=2, v=0.3, goal_dist=2.0))
    assert h.step() == "avoiding"  # a near collision: within the event horizon
    assert h.step(times=5) == "avoiding"  # paused, not let go as a wait with nobody coming


def test_without_passages_the_executor_does_not_queue() -> None:
    h = Harness(TaskExecutor)
    h.base.pose = Pose(3.7, 3.0, EAST)
    h.assign([task("t", *GOAL)])
    h.step()
    h.hear(pose_of("robot_2", 5.07, 3.0, WEST, v=0.4, goal_dist=4.0))
    assert h.step() == "navigating"  # 1.4 m away: no near collision either


def walked_entry(passages: Passages, index: int, start, route) -> tuple[float, float] | None:
    """The route's first point inside the passage, walked afresh: every segment from
    the start sampled every half cell, until the look-ahead is travelled."""
    step = passages.resolution / 2
    travelled = 0.0
    ax, ay = start
    for bx, by in route:
        length = math.hypot(bx - ax, by - ay)
        n = max(1, math.ceil(length / step))
        for i in range(1, n + 1):
            px, py = ax + (bx - ax) * i / n, ay + (by - ay) * i / n
            if passages.at(px, py) == index:
                return px, py
        travelled += length
        if travelled > ROUTE_LOOKAHEAD:
            return None
        ax, ay = bx, by
    return None


def test_the_entry_of_the_route_being_driven_is_the_route_walked_afresh(door: Passages) -> None:
    """The queue remembers what a route says beyond its first waypoint while the robot
    drives it: as the robot moves, passes waypoints and gets new routes, every answer
    is the one walking the route from the robot would give."""
    rng = random.Random(7)
    q = queue_of(door)
    passage = door.passages[0]
    found = 0
    for _ in range(300):
        route = tuple(
            (rng.uniform(1.0, 9.0), rng.uniform(1.0, 5.0)) for _ in range(rng.randint(1, 5))
        )
        while route:
            x, y = rng.uniform(3.0, 7.0), rng.uniform(1.5, 4.5)
            frame = passage.along(x, y), passage.across(x, y)
            entry = q._first_inside(passage, x, y, *frame, route, q._driven_tail(passage, route))
            assert entry == walked_entry(door, 0, (x, y), route)
            found += entry is not None
            if rng.random() < 0.3:
                route = route[1:]  # a waypoint passed
    assert found > 50  # many routes enter the door (the answers are not all None)
