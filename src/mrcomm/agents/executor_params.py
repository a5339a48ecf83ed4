"""The NB task executor's parameters (every behaviour built on it shares them): pose
rate, near-collision handling, what a robot makes of its mates' ages, navigation
retries, making way and arriving before a goal a mate holds. Each is settable with
``--set behaviour.<name>=...`` and listed by ``mrcomm variants``."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

from mrcomm.agents.collision import CollisionParams
from mrcomm.agents.occupied_goal import OccupiedGoalParams
from mrcomm.specs import parameter


class ExecutorParams(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")

    pose_period: float = parameter(0.2, "time between pose messages (5 Hz)", "s", gt=0)
    collision: CollisionParams = Field(
        default_factory=CollisionParams, description="near-collision detection"
    )
    judge_poses: Literal["every_step", "on_receipt"] = parameter(
        "every_step",
        "when a mate's pose is judged for a near collision and for the link threshold "
        "(SLT, SSD): every step, from the last pose received (every_step), or once, when "
        "it arrives (on_receipt: the original robots, which checked a pose in the "
        "callback that received it and applied thresholds to received messages)",
    )
    collision_pause: float = parameter(
        1.0, "both robots of a near collision pause at least this long", "s", ge=0
    )
    give_way_timeout: float = parameter(
        10.0, "the robot without right of way waits at most this long", "s", gt=0
    )
    clear_time: float = parameter(
        0.5, "a conflict must be gone this long before moving on", "s", ge=0
    )
    resume_grace: float = parameter(
        3.0, "no new conflict with the same mate right after resuming", "s", ge=0
    )
    max_grace: float = parameter(
        24.0, "the grace doubles with each repeat up to this (breaks livelock)", "s", ge=0
    )
    repeat_window: float = parameter(
        5.0, "near collisions with the same mate within this window are repeats", "s", ge=0
    )
    knot_pauses: int = parameter(
        4,
        "more pauses in a row than this, each soon after moving on, whoever the mate, "
        "make a knot: the grace doubles for each one beyond (agents/avoidance.py)",
        ge=1,
    )
    # What a robot knows of its mates ages: these two say how it treats an old pose.
    # The defaults are the original robots' (a mate's last pose is used however old).
    mate_max_age: float | None = parameter(
        None,
        "collision avoidance and making way ignore a mate whose last pose is older "
        "than this (none: a pose never expires)",
        "s",
        gt=0,
        allow_inf_nan=False,
    )
    mate_extrapolation: float = parameter(
        0.0,
        "a mate's pose is moved on along its heading at its speed for its age, "
        "at most this long (0: used where it was)",
        "s",
        ge=0,
    )
    nav_retry_delay: float = parameter(
        2.0, "wait after a navigation failure before choosing again", "s", ge=0
    )
    make_way_radius: float = parameter(
        1.4, "a robot without a goal this close to a mate with one steps aside", "m", ge=0
    )
    make_way_step: float = parameter(1.5, "how far it steps aside", "m", gt=0)
    make_way_timeout: float = parameter(6.0, "it gives up stepping aside after", "s", gt=0)
    queue_distance: float = parameter(
        1.5,
        "at a one-lane passage (the scenario's one_lane_width) a robot waits this far "
        "before its entry while a mate comes the other way",
        "m",
        gt=0,
    )
    queue_timeout: float = parameter(
        90.0,
        "it drives on once the mates coming through a passage have stood still this long "
        "(longer than an LF group leader holds: group_hold_timeout)",
        "s",
        gt=0,
    )
    occupied_goal: OccupiedGoalParams = Field(
        default_factory=OccupiedGoalParams, description="arriving before a goal a mate holds"
    )
