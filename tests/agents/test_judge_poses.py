"""``behaviour.judge_poses``: when a mate's pose is judged for the link threshold.

Every step (the default), the link to a mate is judged from the mate's last received
pose and the robot's position now, so a robot driving away from a mate whose poses are
lost finds the link in warning although nothing new was heard. On receipt (the original
robots, whose thresholds were applied to received messages: thesis lines 1201, 1531),
the verdict is the one the pose had when it arrived, until the next pose arrives; a
measured signal (ESD) is read as it comes either way."""

from __future__ import annotations

from mrcomm.agents.executor import TaskExecutor
from mrcomm.agents.executor_params import ExecutorParams
from mrcomm.net.link_sensors import DistanceSensor, MeasuredSensor
from mrcomm.world.geometry import Pose

from .fakes import Harness, pose_of


def _robot(judge: str, sensor: DistanceSensor | MeasuredSensor | None = None) -> Harness:
    params = ExecutorParams(judge_poses=judge)
    return Harness(TaskExecutor, params=params, link_sensor=sensor or DistanceSensor(4.0))


def test_every_step_a_robot_moving_away_finds_the_link_in_warning() -> None:
    h = _robot("every_step")
    h.hear(pose_of("robot_2", 3.0, 0.0))
    agent = h.agent
    assert not agent.mate_link_warns("robot_2", Pose(0.0, 0.0, 0.0), 3.0, 0.0)
    # 2 m further away, nothing new heard: 5 m from where the mate was last heard.
    assert agent.mate_link_warns("robot_2", Pose(-2.0, 0.0, 0.0), 3.0, 0.0)


def test_on_receipt_the_verdict_is_the_one_the_pose_had_when_it_arrived() -> None:
    h = _robot("on_receipt")
    h.hear(pose_of("robot_2", 3.0, 0.0))
    agent = h.agent
    assert not agent.mate_link_warns("robot_2", Pose(0.0, 0.0, 0.0), 3.0, 0.0)
    assert not agent.mate_link_warns("robot_2", Pose(-2.0, 0.0, 0.0), 3.0, 0.0)
    # The next pose of the mate arrives: judged anew, from where the robot is now.
    h.now = 1.0
    h.hear(pose_of("robot_2", 3.0, 0.0, seq=2, stamp=1.0))
    assert agent.mate_link_warns("robot_2", Pose(-2.0, 0.0, 0.0), 3.0, 0.0)
    assert agent.mate_link_warns("robot_2", Pose(0.0, 0.0, 0.0), 3.0, 0.0)  # held until news


def test_on_receipt_a_measured_signal_is_read_as_it_comes() -> None:
    sensor = MeasuredSensor(warning_dbm=-60.0)
    h = _robot("on_receipt", sensor)
    h.hear(pose_of("robot_2", 3.0, 0.0))
    agent = h.agent
    sensor.update("robot_2", -50.0, 0.0)
    assert not agent.mate_link_warns("robot_2", Pose(0.0, 0.0, 0.0), 3.0, 0.0)
    sensor.update("robot_2", -70.0, 0.0)
    assert agent.mate_link_warns("robot_2", Pose(0.0, 0.0, 0.0), 3.0, 0.0)
