"""The occupied-goal deadlock breaker's clock (agents/occupied_goal.py): it counts only
while the robot stands before its goal and a mate stands on it, and starts again on a
free goal, a new goal or a long pause."""

from __future__ import annotations

from mrcomm.agents.collision import MateState
from mrcomm.agents.occupied_goal import OccupiedGoal, OccupiedGoalParams
from mrcomm.world.geometry import Pose

GOAL = (10.0, 5.0)
BEFORE = Pose(9.4, 5.0, 0.0)  # 0.6 m before the goal
ON_GOAL = MateState("robot_2", 10.2, 5.1, 3.1, 0.0, -1.0, 0.0)
NEARBY = MateState("robot_2", 11.0, 5.0, 3.1, 0.0, -1.0, 0.0)  # 1 m past the goal


def watcher() -> OccupiedGoal:
    return OccupiedGoal(OccupiedGoalParams(radius=0.5, reach=1.2, timeout=10.0))


def test_arrives_after_the_timeout_before_a_taken_goal() -> None:
    occupied = watcher()
    seen = [occupied.check(t / 10, BEFORE, GOAL, [ON_GOAL]) for t in range(0, 101)]
    assert all(taker is None for taker in seen[:100])  # 0 .. 9.9 s
    assert seen[100] is ON_GOAL  # 10 s


def test_a_free_goal_or_a_far_robot_never_arrives() -> None:
    occupied = watcher()
    assert all(occupied.check(t / 10, BEFORE, GOAL, [NEARBY]) is None for t in range(300))
    far = Pose(8.0, 5.0, 0.0)  # 2 m before the goal
    assert all(occupied.check(t / 10, far, GOAL, [ON_GOAL]) is None for t in range(300))


def test_the_count_starts_again_when_the_goal_is_seen_free() -> None:
    occupied = watcher()
    for t in range(90):
        assert occupied.check(t / 10, BEFORE, GOAL, [ON_GOAL]) is None
    assert occupied.check(9.0, BEFORE, GOAL, [NEARBY]) is None  # the mate left a moment
    for t in range(91, 190):
        assert occupied.check(t / 10, BEFORE, GOAL, [ON_GOAL]) is None
    assert occupied.check(19.1, BEFORE, GOAL, [ON_GOAL]) is ON_GOAL


def test_short_pauses_count_but_a_new_goal_or_a_long_pause_starts_again() -> None:
    occupied = watcher()
    assert occupied.check(0.0, BEFORE, GOAL, [ON_GOAL]) is None
    # Not asked for 4 s (pausing for a near collision, say): the count goes on.
    assert occupied.check(4.0, BEFORE, GOAL, [ON_GOAL]) is None
    assert occupied.check(10.0, BEFORE, GOAL, [ON_GOAL]) is ON_GOAL
    fresh = watcher()
    assert fresh.check(0.0, BEFORE, GOAL, [ON_GOAL]) is None
    assert fresh.check(20.0, BEFORE, GOAL, [ON_GOAL]) is None  # 20 s unasked: again
    assert fresh.check(29.9, BEFORE, GOAL, [ON_GOAL]) is None
    assert fresh.check(30.0, BEFORE, GOAL, [ON_GOAL]) is ON_GOAL
    other = (9.9, 5.5)
    assert fresh.check(30.1, BEFORE, other, [MateState("robot_2", 9.9, 5.6, 0, 0, -1, 0)]) is None
