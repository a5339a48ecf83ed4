"""Robot parameters: the physical robot (Turtlebot 2 size and limits), its sensor noise,
and the tuning of its planner, path follower, re-planning and stuck recovery.

One frozen :class:`RobotParams` is shared by every robot of a run. Every field has a
default; :meth:`RobotParams.from_mapping` builds one from a configuration
mapping and rejects unknown keys and bad values with a one-line
:class:`~mrcomm.errors.InputError`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mrcomm.errors import InputError, did_you_mean


@dataclass(frozen=True)
class RobotParams:
    """Everything that shapes how a simulated robot moves, senses and navigates."""

    # --- body and limits (Turtlebot 2 / Kobuki) ---
    radius: float = 0.18  # footprint radius (m)
    max_v: float = 0.5  # forward speed limit (m/s)
    max_w: float = 1.5  # turn rate limit (rad/s)
    max_accel: float = 1.0  # |dv/dt| limit (m/s^2)
    max_ang_accel: float = 3.0  # |dw/dt| limit (rad/s^2)

    # --- sensing noise ---
    odom_distance_noise: float = 0.02  # multiplicative sigma on each distance increment
    odom_heading_noise: float = 0.02  # multiplicative sigma on each heading increment
    loc_position_noise: float = 0.02  # sigma (m) of the localisation error, per axis
    loc_heading_noise: float = 0.01  # sigma (rad) of the localisation heading error
    loc_noise_time_constant: float = 2.0  # correlation time (s) of the localisation error
    sensing_range: float = 2.0  # team mates closer than this are seen as obstacles (m)

    # --- global planner ---
    planner_resolution: float = 0.1  # cell size (m) of the coarse planning grid
    inflation_margin: float = 0.05  # clearance kept beyond the footprint radius (m)
    wall_cost_range: float = 0.3  # distance (m) beyond the inflation where walls cost extra
    wall_cost_weight: float = 4.0  # extra cost per cell at the inflation edge
    max_snap: float = 0.6  # start/goal in the inflated zone move at most this far (m)

    # --- path following ---
    goal_tolerance: float = 0.15  # SUCCEEDED within this distance of the goal (m)
    lookahead: float = 0.35  # carrot distance along the path (m)
    corner_angle: float = 0.6  # a waypoint turning more than this (rad) is a corner
    corner_switch: float = 0.08  # switch to the next segment this close to a corner (m)
    rotate_threshold: float = 0.8  # heading error (rad) above which the robot turns in place
    heading_gain: float = 2.5  # turn rate per radian of heading error (1/s)
    min_approach_speed: float = 0.05  # speed floor when slowing for a corner or goal (m/s)

    # --- team mates ---
    block_margin: float = 0.1  # a mate this close to our swept path blocks it (m, beyond 2r)
    hold_distance: float = 0.65  # wait when a blocking mate's centre is this close (m)
    replan_interval: float = 1.0  # at most one re-plan around mates per interval (s)
    max_detour_ratio: float = 3.0  # reject a re-planned path longer than this x current
    # Re-plans around mates, and a route resumed for the same goal, search only to the
    # point this far (m) along the route and keep the rest (robot/repair.py); 0: search
    # the whole route again.
    repair_horizon: float = 0.0

    # --- stuck recovery ---
    stuck_timeout: float = 5.0  # ACTIVE and not moving for this long means stuck (s)
    stuck_distance: float = 0.05  # "not moving": net displacement below this (m)
    reverse_distance: float = 0.5  # back off this far, by odometry (m)
    reverse_speed: float = 0.15  # reversing speed (m/s)
    max_recoveries: int = 3  # recoveries in a row without progress before ABORTED
    progress_reset: float = 1.0  # travelling this far clears the recovery count (m)

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise InputError(f"must be a number, got {value!r}", field=f.name)
            if not math.isfinite(value) or value < 0:
                raise InputError(f"must be a finite number >= 0, got {value!r}", field=f.name)
        for name in (
            "radius",
            "max_v",
            "max_w",
            "max_accel",
            "max_ang_accel",
            "planner_resolution",
            "goal_tolerance",
            "lookahead",
            "loc_noise_time_constant",
            "reverse_speed",
            "stuck_timeout",
            "replan_interval",
        ):
            if getattr(self, name) <= 0:
                raise InputError(f"must be > 0, got {getattr(self, name)!r}", field=name)
        if self.max_detour_ratio < 1:
            raise InputError("must be >= 1", field="max_detour_ratio")
        if self.hold_distance < 2 * self.radius:
            raise InputError("must be at least twice the radius", field="hold_distance")

    @property
    def inflation_radius(self) -> float:
        """Distance (m) the robot's centre keeps from obstacles when planning."""
        return self.radius + self.inflation_margin

    @classmethod
    def from_mapping(
        cls, data: Mapping[str, Any], *, file: str | Path | None = None, section: str = ""
    ) -> RobotParams:
        """Build parameters from a config mapping (missing keys keep their defaults);
        errors name the field as ``<section>.<key>`` when ``section`` is given."""
        known = [f.name for f in dataclasses.fields(cls)]
        prefix = f"{section}." if section else ""
        kwargs: dict[str, Any] = {}
        for key, value in data.items():
            if key not in known:
                raise InputError(
                    f"unknown robot parameter '{key}'{did_you_mean(str(key), known)}",
                    file=file,
                    field=f"{prefix}{key}",
                )
            kwargs[key] = value
        try:
            return cls(**kwargs)
        except InputError as err:
            raise InputError(err.message, file=file, field=f"{prefix}{err.field}") from None
