"""Route repair: a way round team mates (or back to the route after stepping out of
it) that rejoins the route a short distance ahead, instead of a new search of the whole
route to the goal.

On a campus of hundreds of metres a robot's route to its task is as long; the mates it
meets are within its sensing range (2 m). Searching the whole route again for each mate
met, and again when it resumes after giving way, was most of a 1,000-robot run's time
once the first routes were planned. A repair searches only from the robot to the point
``horizon`` metres along its current route, on the small window around the two, and
keeps the rest of the route as it was. It is the whole route's search when less than
``horizon`` of the route is left, and falls back to it when the window holds no way (a
crowd that fills a corridor: the way round may be another corridor).

A repaired route is not the shortest route from where the robot stands: the part kept
was the shortest from where the robot was when it was planned. It is off by default
(``RobotParams.repair_horizon`` 0); ``mrcomm scenario make`` turns it on for large maps.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from mrcomm.robot.follower import PathFollower
from mrcomm.robot.planner import GridPlanner, PlanMemo, PlannedPath
from mrcomm.world.geometry import polyline_length

Point = tuple[float, float]


def repaired_route(
    planner: GridPlanner,
    start: Point,
    route: PathFollower,
    horizon: float,
    obstacles: Sequence[Point],
    weights: NDArray[np.float32] | None,
    memo: PlanMemo | None,
) -> PlannedPath | None:
    """The way from ``start`` round ``obstacles`` to the point ``horizon`` m along
    ``route`` (measured as the route's follower measures what is left), then the rest of
    ``route`` to its goal; None when less than ``horizon`` is left or the small window
    around ``start`` and that point holds no way (plan the whole route then)."""
    rejoin = route.ahead(start[0], start[1], horizon)
    if rejoin is None:
        return None
    point, rest = rejoin
    way = planner.plan(start, point, obstacles, weights=weights, memo=memo, local=True)
    if way is None:
        return None
    kept = rest[1:] if rest and rest[0] == way.goal else rest
    waypoints = (*way.waypoints, *kept)
    return PlannedPath(waypoints, polyline_length(waypoints))
