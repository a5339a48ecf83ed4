"""Making way: when a robot stands in a mate's way, and where it steps aside to.

Pure geometry on the robot's pose and the mate's last pose message; the executor
decides when to ask (an idle robot, a follower) and drives to the places given here.
"""

from __future__ import annotations

import math

from mrcomm.agents.collision import Mate
from mrcomm.world.geometry import Pose, wrap_angle

#: A point lies ahead of a robot within this angle of its heading.
AHEAD = math.radians(75)
#: A mate's pose older than this (s) puts no robot in its way. A mate within the make-way
#: radius is heard several times a second; one last heard longer ago has moved on (an
#: idle robot stepped aside every 0.4 s, to the time limit, for a pose 346 s old).
MAX_AGE = 10.0


def ahead_of(pose: Pose, mate: Mate) -> bool:
    """``pose`` lies ahead of the mate: within :data:`AHEAD` of its heading."""
    bearing = math.atan2(pose.y - mate.y, pose.x - mate.x)
    return abs(wrap_angle(bearing - mate.theta)) < AHEAD


def in_way(pose: Pose, mate: Mate, radius: float, moving_speed: float, now: float) -> bool:
    """A robot at ``pose`` is within ``radius`` of a mate that has a goal: ahead of it,
    or next to it while the mate stands (slower than ``moving_speed``), by a pose of
    the mate's heard within :data:`MAX_AGE` of ``now``."""
    if mate.goal_dist < 0 or now - mate.stamp > MAX_AGE:
        return False
    if math.hypot(pose.x - mate.x, pose.y - mate.y) > radius:
        return False
    return ahead_of(pose, mate) or mate.v < moving_speed


def aside_goals(pose: Pose, mate: Mate, step: float) -> list[tuple[float, float]]:
    """Where to step aside, in order of preference: ``step`` to the side of the mate's
    heading the robot is on, to the other side, then straight away from the mate."""
    away = math.atan2(pose.y - mate.y, pose.x - mate.x)
    side = 1.0 if wrap_angle(away - mate.theta) >= 0 else -1.0
    angles = [mate.theta + side * math.pi / 2, mate.theta - side * math.pi / 2, away]
    return [(pose.x + step * math.cos(a), pose.y + step * math.sin(a)) for a in angles]
