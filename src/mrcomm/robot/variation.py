"""Run-to-run variation of the simulated robots: the ``robot.*`` parameters of a run
(``--set robot.variation=realistic``) and what each robot draws from them once per run.

Real robots on the same mission differ from run to run far more than noise-free
simulated ones: AMCL's estimate wanders by a few centimetres and a degree or two, drifts
in heading and now and then jumps when the particle cloud re-converges; two Turtlebots
of one model do not drive equally fast (battery charge, wheel and gearbox wear); nodes
come up a few seconds apart; and a planner's choice between equally long routes depends
on tiny differences in its costmap. This module declares those effects as documented
parameters and draws each robot's share of them from its own seeded streams.

Profiles (``robot.variation``):

* ``none`` (the default): exactly the robots of earlier versions — the small
  localisation error of :class:`~mrcomm.robot.params.RobotParams`, nothing else. No
  extra random number is drawn, so every earlier result is reproduced bit for bit.
* ``realistic``: every mechanism below at the values of its parameters; the
  recommended profile for new studies.

Seeding: every draw comes from ``seeding.stream(seed, "robot", <id>, <purpose>)`` (one
stream per robot and purpose: adding a robot or a mechanism changes no other robot's
draws) except the planner's tie-break field, one per run
(``stream(seed, "planner", "tie-break")``), shared by the run's robots like the map.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict

from mrcomm.robot.planner import GridPlanner
from mrcomm.seeding import stream
from mrcomm.specs import parameter

Profile = Literal["none", "realistic"]


class VariationParams(BaseModel):
    """The ``robot.*`` run parameters. Each mechanism acts only in the ``realistic``
    profile; its value there is the parameter's (defaults: typical Turtlebot 2 with
    AMCL in an office, see ``docs/ROBOT.md``)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    variation: Profile = parameter(
        "none",
        "run-to-run variation of the robots: 'none' (the deterministic robots of earlier "
        "versions, the default) or 'realistic' (every mechanism below; recommended for "
        "new studies)",
    )
    # --- localisation (AMCL on a Turtlebot: typically 2-5 cm, 1-3 degrees) ---
    loc_position_sigma: float = parameter(
        0.03,
        "standard deviation of the localisation error per axis (replaces the base's "
        "0.02 m); AMCL on a Turtlebot: 2-5 cm",
        "m",
        ge=0.0,
        le=1.0,
    )
    loc_heading_sigma: float = parameter(
        0.02,
        "standard deviation of the fast heading error (replaces the base's 0.01 rad); "
        "AMCL: 1-3 degrees together with the drift",
        "rad",
        ge=0.0,
        le=0.5,
    )
    loc_time_constant: float = parameter(
        3.0,
        "correlation time of the localisation error, counted while the robot moves "
        "(AMCL corrects on motion)",
        "s",
        gt=0.0,
        le=600.0,
    )
    heading_drift_sigma: float = parameter(
        0.03,
        "standard deviation of a slow heading drift added to the heading error "
        "(scan matching corrects heading slowly in long corridors)",
        "rad",
        ge=0.0,
        le=0.5,
    )
    heading_drift_time_constant: float = parameter(
        30.0, "correlation time of the heading drift, while moving", "s", gt=0.0, le=3600.0
    )
    jump_rate: float = parameter(
        0.01,
        "re-localisation jumps per second of driving (a Poisson process): AMCL's estimate "
        "snaps when its particle cloud re-converges, about once in a few minutes",
        "1/s",
        ge=0.0,
        le=10.0,
    )
    jump_sigma: float = parameter(
        0.15,
        "standard deviation per axis of a jump's position offset (it then fades with "
        "the localisation time constant)",
        "m",
        ge=0.0,
        le=5.0,
    )
    jump_heading_sigma: float = parameter(
        0.05, "standard deviation of a jump's heading offset", "rad", ge=0.0, le=3.2
    )
    # --- speed (battery charge, wheel and gearbox wear, firmware limits) ---
    speed_sigma: float = parameter(
        0.07,
        "each robot's top speed is scaled by a factor drawn once per run from "
        "N(1, speed_sigma), clipped to [speed_min, speed_max]; Kobuki bases of one "
        "fleet differ by several per cent (battery voltage, wheel wear)",
        ge=0.0,
        le=1.0,
    )
    speed_min: float = parameter(0.8, "lowest speed factor", gt=0.0, le=1.0)
    speed_max: float = parameter(1.2, "highest speed factor", ge=1.0, le=2.0)
    # --- start-up ---
    start_delay_max: float = parameter(
        4.0,
        "each robot starts moving after a delay drawn once per run, uniform in "
        "[0, start_delay_max] (launch files, AMCL initialisation, an operator starting "
        "robots one by one)",
        "s",
        ge=0.0,
        le=600.0,
    )
    # --- planner ---
    planner_tie_noise: float = parameter(
        0.02,
        "relative amplitude of a seeded perturbation of the planner's cell costs "
        "(uniform in [0, planner_tie_noise]): equally long routes are chosen differently "
        "per seed, as a real costmap's small differences do",
        ge=0.0,
        le=1.0,
    )

    @property
    def active(self) -> bool:
        """Whether any variation applies (profile ``realistic``)."""
        return self.variation != "none"


@dataclass(frozen=True)
class RobotDraws:
    """What one robot draws once per run from its ``variation`` stream."""

    speed_factor: float  #: multiplies the robot's top speed
    start_delay: float  #: s before the robot first moves


def draw_robot(params: VariationParams, seed: int, robot_id: str) -> RobotDraws:
    """One robot's per-run draws (its own stream: other robots do not change them)."""
    rng = stream(seed, "robot", robot_id, "variation")
    factor = 1.0 + params.speed_sigma * float(rng.standard_normal())
    factor = min(max(factor, params.speed_min), params.speed_max)
    delay = params.start_delay_max * float(rng.random())
    return RobotDraws(speed_factor=factor, start_delay=delay)


def localisation_rng(seed: int, robot_id: str) -> np.random.Generator:
    """The stream of a robot's heading drift and re-localisation jumps."""
    return stream(seed, "robot", robot_id, "amcl")


def tie_break_rng(seed: int) -> np.random.Generator:
    """The stream of a run's planner tie-break field."""
    return stream(seed, "planner", "tie-break")


@dataclass(frozen=True)
class RobotVariation:
    """Everything one robot's base needs of the run's variation (``realistic`` only)."""

    params: VariationParams
    draws: RobotDraws
    #: the robot's drift-and-jump stream (:class:`~mrcomm.robot.noise.AmclError`)
    loc_rng: np.random.Generator
    #: the run's tie-break cell costs (shared by its robots; None: the planner's own)
    weights: NDArray[np.float32] | None


def robot_variations(
    params: VariationParams, seed: int, robot_ids: Sequence[str], planner: GridPlanner
) -> dict[str, RobotVariation | None]:
    """Each robot's variation for a run (all None for the ``none`` profile: then no
    random number is drawn and the robots are those of earlier versions)."""
    if not params.active:
        return dict.fromkeys(robot_ids)
    weights = None
    if params.planner_tie_noise > 0.0:
        weights = planner.tie_break_weights(tie_break_rng(seed), params.planner_tie_noise)
    return {
        r: RobotVariation(params, draw_robot(params, seed, r), localisation_rng(seed, r), weights)
        for r in robot_ids
    }
