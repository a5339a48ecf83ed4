"""The deadlock breaker for a goal a mate stands on.

A robot's base holds in front of a mate that stands on its goal and waits for it to
leave. When that mate cannot leave — it is parked in a dead end past the goal, and the
only way out is past the robot waiting for it — neither ever moves: the mate's steps
aside all lead past the waiting robot, which holds for the mate. After
``occupied_goal_timeout`` s of standing within ``occupied_goal_reach`` of its goal while
a mate stands within ``occupied_goal_radius`` of it, the robot counts the task location
as reached (as close as it can get); it then executes the task and drives on, which
frees the mate. Nothing changes for a robot whose goal is free, or that is far from it.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

from pydantic import BaseModel, ConfigDict

from mrcomm.agents.collision import Mate
from mrcomm.specs import parameter
from mrcomm.world.geometry import Pose


class OccupiedGoalParams(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")

    radius: float = parameter(0.5, "a mate this close to a robot's goal stands on it", "m", ge=0)
    reach: float = parameter(
        1.2, "a robot this close to its goal, the goal taken, stands before it", "m", ge=0
    )
    timeout: float = parameter(
        10.0, "after standing before its taken goal this long, the robot has arrived", "s", gt=0
    )


class OccupiedGoal:
    """Watches one robot's approach to its goal; :meth:`check` says when to arrive."""

    def __init__(self, params: OccupiedGoalParams) -> None:
        self.radius = params.radius
        self.reach = params.reach
        self.timeout = params.timeout
        self._goal: tuple[float, float] | None = None
        self._since = 0.0  # when the goal was first seen taken (this approach)
        self._seen = -math.inf  # when it was last seen taken

    def check(
        self, now: float, pose: Pose, goal: tuple[float, float], mates: Iterable[Mate]
    ) -> Mate | None:
        """The mate on the goal when the robot has stood before it, the goal taken, for
        the timeout; else None. Called while the robot drives to ``goal``: a goal seen
        free, a new goal, or a pause longer than the timeout starts the count again."""
        gx, gy = goal
        if math.hypot(pose.x - gx, pose.y - gy) > self.reach:
            self._goal = None
            return None
        taker = next((m for m in mates if math.hypot(m.x - gx, m.y - gy) <= self.radius), None)
        if taker is None:
            self._goal = None
            return None
        if self._goal != goal or now - self._seen > self.timeout:
            self._goal, self._since = goal, now
        self._seen = now
        return taker if now - self._since >= self.timeout else None
