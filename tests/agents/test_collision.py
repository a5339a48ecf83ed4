"""Near-collision geometry and right of way (SPEC §4)."""

import itertools
import math

from mrcomm.agents.collision import (
    DANGER_ZONE,
    EVENT_HORIZON,
    CollisionParams,
    MateState,
    classify,
    has_right_of_way,
)
from mrcomm.world.geometry import Pose

P = CollisionParams()
ME = Pose(0.0, 0.0, 0.0)  # facing +x


def mate(x: float, y: float, theta: float, v: float = 0.4, goal: float = 5.0) -> MateState:
    return MateState("m", x, y, theta, v, goal)


def test_head_on_mate_in_front_is_a_danger_zone_collision() -> None:
    assert classify(ME, mate(0.9, 0.0, math.pi), P) == DANGER_ZONE


def test_crossing_mate_in_front_is_a_danger_zone_collision() -> None:
    assert classify(ME, mate(0.7, 0.3, math.pi / 2), P) == DANGER_ZONE


def test_same_direction_ahead_or_alongside_is_not_a_collision() -> None:
    assert classify(ME, mate(0.8, 0.0, 0.1), P) is None
    assert classify(ME, mate(0.2, 0.7, -0.2), P) is None


def test_mate_behind_is_outside_the_semicircle() -> None:
    assert classify(ME, mate(-0.8, 0.0, 0.0 + math.pi), P) is None


def test_mate_beyond_the_danger_radius_is_ignored() -> None:
    assert classify(ME, mate(1.2, 0.0, math.pi), P) is None


def test_event_horizon_triggers_whatever_the_heading() -> None:
    assert classify(ME, mate(-0.3, 0.2, 0.0), P) == EVENT_HORIZON
    assert classify(ME, mate(0.4, 0.0, 0.0), P) == EVENT_HORIZON


def test_parked_mate_without_goal_is_left_to_the_planner() -> None:
    assert classify(ME, mate(0.8, 0.0, math.pi, v=0.0, goal=-1.0), P) is None


def test_right_of_way_goes_to_the_robot_closer_to_its_goal() -> None:
    assert has_right_of_way(2.0, 5.0, 0, 1)
    assert not has_right_of_way(5.0, 2.0, 0, 1)


def test_both_robots_agree_on_right_of_way_including_ties() -> None:
    for mine, theirs in [(2.0, 5.0), (3.0, 3.0), (4.0, -1.0)]:
        for rank_a, rank_b in [(0.0, 1.0), (1.0, 0.0)]:
            a = has_right_of_way(mine, theirs, rank_a, rank_b)
            b = has_right_of_way(theirs, mine, rank_b, rank_a)
            assert a != b, (mine, theirs, rank_a, rank_b)


def test_mate_without_goal_yields() -> None:
    assert has_right_of_way(8.0, -1.0, 1, 0)
    assert not has_right_of_way(-1.0, 8.0, 0, 1)


def test_right_of_way_cannot_cycle_among_three_or_more_robots() -> None:
    """With the same information every pair agrees, and the order is transitive: no
    three robots can each yield to the next (goal distances with ties and robots
    without a goal; ranks distinct, as the team-wide order gives them)."""
    goals = [-1.0, 1.0, 2.0, 2.0, 5.0]
    robots = [(g, float(r)) for r, g in enumerate(goals)]
    for a, b, c in itertools.permutations(robots, 3):
        a_b = has_right_of_way(a[0], b[0], a[1], b[1])
        b_c = has_right_of_way(b[0], c[0], b[1], c[1])
        c_a = has_right_of_way(c[0], a[0], c[1], a[1])
        assert not (a_b and b_c and c_a), (a, b, c)
        assert not (not a_b and not b_c and not c_a), (a, b, c)
