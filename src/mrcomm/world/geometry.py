"""Small geometric value types shared by every layer."""

from __future__ import annotations

import math
from typing import NamedTuple


class Pose(NamedTuple):
    """A planar pose in metres and radians (map frame)."""

    x: float
    y: float
    theta: float = 0.0

    def distance_to(self, x: float, y: float) -> float:
        return math.hypot(self.x - x, self.y - y)


def wrap_angle(angle: float) -> float:
    """Wrap an angle to (-pi, pi]."""
    return math.atan2(math.sin(angle), math.cos(angle))
