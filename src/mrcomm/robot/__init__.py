"""Robot layer: differential-drive kinematics, odometry and localisation noise, the
global planner, path following, re-planning around team mates and stuck recovery;
:class:`SimBase` implements the Base port (ports.py) for simulation."""

from __future__ import annotations

from mrcomm.robot.base import SimBase
from mrcomm.robot.params import RobotParams
from mrcomm.robot.planner import GridPlanner, PlannedPath

__all__ = ["GridPlanner", "PlannedPath", "RobotParams", "SimBase"]
