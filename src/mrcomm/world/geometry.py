"""Small geometric value types shared by every layer."""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
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


def polyline_length(points: Sequence[tuple[float, float]]) -> float:
    """Length of the polyline through ``points`` (m)."""
    return sum(math.hypot(b[0] - a[0], b[1] - a[1]) for a, b in itertools.pairwise(points))
