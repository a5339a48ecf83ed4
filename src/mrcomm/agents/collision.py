"""Near-collision detection and right of way, as pure functions.

* Danger zone: a semicircle of radius ``danger_radius`` ahead of the robot. A team mate
  (from its last received pose) inside it that is heading towards the robot or across
  its path is a near collision; one travelling alongside, ahead or behind in the same
  direction is not, and neither is one standing still without a goal (a parked robot is
  an obstacle for the planner, not a collision partner).
* Event horizon: a small circle around the footprint; any team mate inside it, whatever
  its heading, is a near collision.
* Right of way: the robot closer to its own goal goes first; a mate without a goal
  yields; exact ties are broken by a team-wide random order. For the same information
  this is a strict total order of the team (goal distance, then rank), so it cannot
  cycle among three or more robots; robots that judge from different pose ages can
  still disagree, and a knot of robots that each yield to the next is undone by the
  growing grace of avoidance.py, not here.
"""

from __future__ import annotations

import math
from typing import NamedTuple, Protocol

from pydantic import BaseModel, ConfigDict

from mrcomm.specs import parameter
from mrcomm.world.geometry import Pose, wrap_angle

DANGER_ZONE = "danger_zone"
EVENT_HORIZON = "event_horizon"


class CollisionParams(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")

    danger_radius: float = parameter(
        1.0, "radius of the danger zone, a semicircle ahead of the robot", "m", gt=0
    )
    event_horizon: float = parameter(
        0.5, "any mate closer than this (centre to centre) is a near collision", "m", gt=0
    )
    same_direction_deg: float = parameter(
        45.0, "a mate heading within this of our heading travels alongside", "deg", ge=0
    )
    moving_speed: float = parameter(
        0.05, "below this speed a mate counts as standing still", "m/s", ge=0
    )


class Mate(Protocol):
    """A team mate as a robot reads it: the pose message it last received from the mate
    (``messaging.messages.PoseMsg``), or a :class:`MateState` made from one."""

    @property
    def robot(self) -> str: ...
    @property
    def x(self) -> float: ...
    @property
    def y(self) -> float: ...
    @property
    def theta(self) -> float: ...
    @property
    def v(self) -> float: ...
    @property
    def goal_dist(self) -> float: ...
    @property
    def stamp(self) -> float: ...


class MateState(NamedTuple):
    """A team mate's state that is not a received pose as it came: a pose moved on for
    its age (``TeamView.known``), or a mate made up by a test."""

    robot: str
    x: float
    y: float
    theta: float
    v: float
    goal_dist: float  # -1 when it has no goal
    #: When the mate sent this pose (mission clock); NaN when unknown (never equal to
    #: another stamp: such a pose always counts as news).
    stamp: float = math.nan


def classify(own: Pose, mate: Mate, params: CollisionParams) -> str | None:
    """Kind of near collision with ``mate`` (``EVENT_HORIZON``/``DANGER_ZONE``) or None."""
    dx = mate.x - own.x
    dy = mate.y - own.y
    distance = math.hypot(dx, dy)
    if distance <= params.event_horizon:
        return EVENT_HORIZON
    if distance > params.danger_radius:
        return None
    bearing = wrap_angle(math.atan2(dy, dx) - own.theta)
    if abs(bearing) > math.pi / 2:
        return None  # behind us: not in the semicircle ahead
    if mate.v < params.moving_speed and mate.goal_dist < 0:
        return None  # parked: the planner routes around it
    heading_difference = abs(wrap_angle(mate.theta - own.theta))
    if heading_difference < math.radians(params.same_direction_deg):
        return None  # same direction: alongside, ahead or behind us
    return DANGER_ZONE


def has_right_of_way(
    own_goal_dist: float,
    mate_goal_dist: float,
    own_rank: float,
    mate_rank: float,
) -> bool:
    """Whether this robot goes first. ``*_rank`` is the team-wide random tie-break order
    (both robots compute the same answer from the same ranks)."""
    if mate_goal_dist < 0:
        return True
    if own_goal_dist < 0:
        return False
    if own_goal_dist != mate_goal_dist:
        return own_goal_dist < mate_goal_dist
    return own_rank < mate_rank
