"""What a robot knows of its mates ages: a pose older than ``mate_max_age`` is not acted
on, and ``mate_extrapolation`` moves a pose on for its age."""

from __future__ import annotations

import math

import msgspec
import pytest

from mrcomm.agents.executor import TaskExecutor
from mrcomm.agents.executor_params import ExecutorParams
from mrcomm.agents.team_view import TeamView
from mrcomm.metrics import labels as L
from mrcomm.world.geometry import Pose

from .fakes import Harness, pose_of, task


def _near_collisions(h: Harness) -> list[str]:
    return [str(e.data["mate"]) for e in h.timeline.events if e.label == L.NEAR_COLLISION]


def _drive_onto_a_stale_pose(params: ExecutorParams) -> Harness:
    """A mate's pose, heading at us, arrives once and then no more; 3 s later our robot
    stands where the old pose put it (less than the event horizon away)."""
    h = Harness(TaskExecutor, params=params)
    h.assign([task("t", 10.0, 0.0)])
    h.step()
    h.hear(pose_of("robot_2", 6.0, 0.0, math.pi, v=0.3, goal_dist=4.0))
    h.step(times=30)  # 3 s: nothing heard since
    assert h.agent.state == "navigating"
    h.base.pose = Pose(5.8, 0.0, 0.0)
    h.step()
    return h


def test_a_pose_older_than_the_limit_causes_no_near_collision() -> None:
    stale = _drive_onto_a_stale_pose(ExecutorParams(mate_max_age=1.0))
    assert stale.agent.state == "navigating"
    assert _near_collisions(stale) == []


def test_without_a_limit_the_stale_pose_is_a_near_collision() -> None:
    # The original robots' view: the last pose stays where it was, however old.
    original = _drive_onto_a_stale_pose(ExecutorParams())
    assert original.agent.state == "avoiding"
    assert _near_collisions(original) == ["robot_2"]


def test_a_fresh_pose_within_the_limit_is_still_acted_on() -> None:
    h = Harness(TaskExecutor, params=ExecutorParams(mate_max_age=1.0))
    h.assign([task("t", 10.0, 0.0)])
    h.step()
    h.now = 0.5
    h.hear(pose_of("robot_2", 0.8, 0.0, math.pi, v=0.3, goal_dist=1.0))  # stamped at 0
    assert h.step() == "avoiding"
    assert _near_collisions(h) == ["robot_2"]


def test_extrapolation_moves_an_approaching_mate_into_the_danger_zone() -> None:
    # Sent at 0 from 2.5 m ahead, heading at us at 1 m/s; judged 1.8 s later.
    def judged(extrapolation: float) -> list[str]:
        h = Harness(TaskExecutor, params=ExecutorParams(mate_extrapolation=extrapolation))
        h.assign([task("t", 10.0, 0.0)])
        h.step()
        h.hear(pose_of("robot_2", 2.5, 0.0, math.pi, v=1.0, goal_dist=4.0))
        h.now = 1.8
        h.step()
        return _near_collisions(h)

    assert judged(0.0) == []  # 2.5 m away as it was sent
    assert judged(2.0) == ["robot_2"]  # 0.7 m away where it should be now
    assert judged(0.5) == []  # moved 0.5 m only: still 2 m away


def test_the_team_view_ages_poses_from_their_stamp_and_caps_the_extrapolation() -> None:
    view = TeamView()
    message = msgspec.structs.replace(pose_of("robot_2", 1.0, 0.0, math.pi / 2, v=0.5), stamp=2.0)
    view.hear(message, now=2.3)  # 0.3 s in transit
    assert view.known(4.0, None, 0.0) is view.poses  # defaults: the view as received
    assert view.known(4.0, 2.1, 0.0) == {"robot_2": view.poses["robot_2"]}
    assert view.known(4.0, 1.9, 0.0) == {}  # sent 2 s ago, though it arrived 1.7 s ago
    moved = view.known(4.0, None, 10.0)["robot_2"]
    assert (moved.x, moved.y) == pytest.approx((1.0, 1.0))  # 2 s at 0.5 m/s north
    capped = view.known(4.0, None, 0.4)["robot_2"]
    assert (capped.x, capped.y) == pytest.approx((1.0, 0.2))


def test_the_limit_must_be_positive_and_finite() -> None:
    for bad in (0.0, -1.0, math.inf, math.nan):
        with pytest.raises(ValueError, match="mate_max_age"):
            ExecutorParams(mate_max_age=bad)
    with pytest.raises(ValueError, match="mate_extrapolation"):
        ExecutorParams(mate_extrapolation=-0.1)


def test_poses_heard_together_read_as_heard_one_by_one() -> None:
    """A step's poses given at once (the in-process bus's batches) leave the view as
    hearing them one by one would: the last of a mate's poses wins, mates keep the order
    they were first heard in (collision avoidance takes the first in conflict), and the
    robot's own pose is left out."""
    first = [pose_of("robot_3", 1.0, 0.0), pose_of("robot_2", 2.0, 0.0)]
    later = [
        pose_of("robot_4", 0.0, 4.0),
        pose_of("robot_1", 9.0, 9.0),
        pose_of("robot_2", 2.5, 0.0),
        pose_of("robot_4", 0.0, 4.5),
    ]
    together, one_by_one = TeamView(), TeamView()
    together.hear_all(first, 1.0, "robot_1")
    together.hear_all(later, 2.0, "robot_1")
    for now, batch in ((1.0, first), (2.0, later)):
        for message in batch:
            if message.sender != "robot_1":
                one_by_one.hear(message, now)
    assert list(together.poses.items()) == list(one_by_one.poses.items())
    assert together.heard == one_by_one.heard == {"robot_3": 1.0, "robot_2": 2.0, "robot_4": 2.0}
    assert list(together.poses) == ["robot_3", "robot_2", "robot_4"]
    assert (together.poses["robot_4"].y, together.poses["robot_2"].x) == (4.5, 2.5)
