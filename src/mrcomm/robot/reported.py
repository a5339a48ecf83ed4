"""ReportedBase: the read side of the Base port for a base whose robot reports its state
from elsewhere — the world process in live mode (``live.remote_base``), a ROS 2 robot
(``ros2.nav2_base``): the latest pose, odometer and speed as last taken, and
``make_plan`` with the same global planner as the base, on the robot's own copy of the
map from the latest pose (as move_base's ``make_plan`` service does on the robot);
without a planner it cannot tell (None)."""

from __future__ import annotations

from mrcomm.robot.planner import GridPlanner
from mrcomm.world.geometry import Pose

Point = tuple[float, float]


class ReportedBase:
    """Pose, odometer and speed as last reported; planning from that pose."""

    def __init__(self, start: Pose, planner: GridPlanner | None = None) -> None:
        self._planner = planner
        self._pose = start
        self._odometry = 0.0
        self._speed = 0.0

    @property
    def pose(self) -> Pose:
        return self._pose

    @property
    def odometry_distance(self) -> float:
        return self._odometry

    @property
    def speed(self) -> float:
        return self._speed

    def make_plan(self, x: float, y: float) -> tuple[Point, ...] | None:
        if self._planner is None:
            return None
        pose = self._pose
        path = self._planner.plan((pose.x, pose.y), (float(x), float(y)))
        return None if path is None else path.waypoints
