"""ReportedBase: the read side of the Base port for a base whose robot reports its state
from elsewhere — the world process in live mode (``live.remote_base``), a ROS 2 robot
(``ros2.nav2_base``): the latest pose, odometer and speed as last taken, and
``make_plan`` with the same global planner as the base, on the robot's own copy of the
map from the latest pose (as move_base's ``make_plan`` service does on the robot);
without a planner it cannot tell (None); ``route``: the latest plan the robot reported
(Nav2's ``plan`` topic) from the segment nearest the latest pose on, while a goal is
active; empty when none was reported (live mode's world does not send its plans:
callers plan instead)."""

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
        #: The latest plan reported for the goal being driven to (empty: none, or no
        #: goal active: the subclass that follows goals clears it).
        self._plan: tuple[Point, ...] = ()

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

    @property
    def route(self) -> tuple[Point, ...]:
        plan = self._plan
        if len(plan) < 2:
            return ()
        x, y = self._pose.x, self._pose.y
        # The plan starts where the robot was when it was made: what lies ahead begins
        # after the segment the robot is nearest now.
        nearest = min(range(len(plan) - 1), key=lambda k: _to_segment(x, y, plan[k], plan[k + 1]))
        return plan[nearest + 1 :]


def _to_segment(x: float, y: float, a: Point, b: Point) -> float:
    """Squared distance from (x, y) to the segment a-b."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0.0 else max(0.0, min(1.0, ((x - a[0]) * dx + (y - a[1]) * dy) / length2))
    px, py = a[0] + t * dx - x, a[1] + t * dy - y
    return px * px + py * py
