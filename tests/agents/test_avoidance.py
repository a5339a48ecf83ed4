"""The avoidance part on its own: right of way, waiting until clear, and the grace
that doubles with each repeated conflict with the same mate."""

from __future__ import annotations

import math

from mrcomm.agents.avoidance import Avoidance
from mrcomm.agents.collision import MateState
from mrcomm.agents.executor import ExecutorParams
from mrcomm.world.geometry import Pose

HERE = Pose(0.0, 0.0, 0.0)
RANK = {"robot_1": 0.0, "robot_2": 1.0}.__getitem__


def coming(goal_dist: float) -> MateState:
    return MateState("robot_2", 0.8, 0.0, math.pi, 0.3, goal_dist)


def test_right_of_way_goes_to_the_robot_closer_to_its_goal() -> None:
    mine = Avoidance("robot_1", ExecutorParams(), RANK)
    conflict = mine.detect(HERE, [coming(goal_dist=9.0)], 0.0, lambda: 1.0)
    assert conflict is not None and conflict.mate == "robot_2" and not conflict.repeat
    assert mine.right_of_way  # 1 m to go against the mate's 9 m
    theirs = Avoidance("robot_1", ExecutorParams(), RANK)
    theirs.detect(HERE, [coming(goal_dist=0.5)], 0.0, lambda: 1.0)
    assert not theirs.right_of_way


def test_without_right_of_way_it_waits_until_the_mate_is_clear() -> None:
    params = ExecutorParams()
    avoidance = Avoidance("robot_1", params, RANK)
    mate = coming(goal_dist=0.5)
    avoidance.detect(HERE, [mate], 0.0, lambda: 5.0)
    mates = {"robot_2": mate}
    assert not avoidance.may_resume(lambda: HERE, mates, params.collision_pause + 0.1, 0.0)
    gone = {"robot_2": MateState("robot_2", 0.8, 3.0, math.pi / 2, 0.3, 0.5)}
    t = params.collision_pause + 0.2
    assert not avoidance.may_resume(lambda: HERE, gone, t, 0.0)  # clear only just now
    assert avoidance.may_resume(lambda: HERE, gone, t + params.clear_time, 0.0)


def test_the_grace_doubles_with_each_repeat() -> None:
    params = ExecutorParams()
    avoidance = Avoidance("robot_1", params, RANK)
    mate, now, graces = coming(goal_dist=9.0), 0.0, []
    for _ in range(3):
        conflict = avoidance.detect(HERE, [mate], now, lambda: 1.0)
        assert conflict is not None
        now += params.collision_pause
        assert avoidance.may_resume(lambda: HERE, {"robot_2": mate}, now, now - 1.0)
        # Within the grace the same mate is not a conflict again.
        assert avoidance.detect(HERE, [mate], now + 0.1, lambda: 1.0) is None
        graces.append(avoidance._grace_until["robot_2"] - now)
        now = avoidance._grace_until["robot_2"] + 0.1  # the next conflict, right after
    # 3 s, then doubled for a repeat within the 5 s window; the next comes after the
    # 6 s grace, outside the window: back to 3 s.
    assert graces == [params.resume_grace, 2 * params.resume_grace, params.resume_grace]


def test_a_pose_already_moved_on_from_does_not_stop_the_robot_again() -> None:
    """A mate last heard long ago stops the robot once; the same pose (nothing newer
    heard) never again, however often the grace runs out; news of it does."""
    params = ExecutorParams()
    avoidance = Avoidance("robot_1", params, RANK)
    ghost = coming(goal_dist=0.5)._replace(stamp=5.0)  # heard at 5 s, not since
    assert avoidance.detect(HERE, [ghost], 100.0, lambda: 9.0) is not None
    assert not avoidance.right_of_way
    mates = {"robot_2": ghost}
    moved_on = 100.0 + params.give_way_timeout
    assert avoidance.may_resume(lambda: HERE, mates, moved_on, 100.0)  # gave up waiting
    after_grace = moved_on + params.max_grace + 1.0
    assert avoidance.detect(HERE, [ghost], after_grace, lambda: 9.0) is None
    heard_again = ghost._replace(stamp=after_grace - 0.1)
    assert avoidance.detect(HERE, [heard_again], after_grace, lambda: 9.0) is not None


def test_a_pose_of_unknown_age_is_always_news() -> None:
    avoidance = Avoidance("robot_1", ExecutorParams(), RANK)
    mate = coming(goal_dist=9.0)  # no stamp
    assert avoidance.detect(HERE, [mate], 0.0, lambda: 1.0) is not None
    assert avoidance.may_resume(lambda: HERE, {"robot_2": mate}, 1.0, 0.0)
    assert avoidance.detect(HERE, [mate], 1.0 + 30.0, lambda: 1.0) is not None
