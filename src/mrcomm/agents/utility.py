"""Utility functions of LF role assignment, registered by name.

The robot with the highest utility leads. The original's utility is
``u = d_score × n_incomplete × rec_complete`` with ``d_score = 1 / distance to the
current goal``, ``n_incomplete`` the robot's tasks not yet completed and
``rec_complete = 0.5`` right after completing a task (else 1.0). An idle robot (agenda
complete) always has utility 0, so it follows.

Each function is a registered variant (kind ``utility``), selected by LF's parameter
``behaviour.utility``; a plugin adds one with a spec whose entry is its function.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from mrcomm.messaging.messages import TaskSpec
from mrcomm.ports import Base
from mrcomm.specs import VariantSpec, get_spec, variant_names
from mrcomm.world.geometry import polyline_length


def _no_route() -> float | None:
    return None


@dataclass(frozen=True)
class UtilityInputs:
    goal_distance: float | None  # m to the current (or next) goal; None when none
    n_incomplete: int
    just_completed: bool
    #: Length (m) of the route the robot's planner finds to that goal, None when there
    #: is none; planned only when a utility asks (a plan costs far more than a distance).
    route_length: Callable[[], float | None] = field(default=_no_route)


UtilityFunction = Callable[[UtilityInputs], float]


def robot_inputs(
    base: Base, agenda: Sequence[TaskSpec], goal: TaskSpec | None, just_completed: bool
) -> UtilityInputs:
    """A robot's utility inputs: its target is its current goal, or else the task of its
    agenda closest in a straight line; the route to it is planned only when asked."""
    pose = base.pose
    target = goal
    if target is None and agenda:
        target = min(agenda, key=lambda t: math.hypot(t.x - pose.x, t.y - pose.y))

    def route_length() -> float | None:
        route = None if target is None else base.make_plan(target.x, target.y)
        return None if route is None else polyline_length(route)

    distance = None if target is None else math.hypot(target.x - pose.x, target.y - pose.y)
    return UtilityInputs(distance, len(agenda), just_completed, route_length=route_length)


def utility_function(name: str) -> UtilityFunction:
    function: UtilityFunction = get_spec("utility", name).load()
    return function


def utility_names() -> list[str]:
    return variant_names("utility")


def original_utility(inputs: UtilityInputs) -> float:
    """The original's product: closer goal, more work left, not just rewarded."""
    if inputs.n_incomplete == 0 or inputs.goal_distance is None:
        return 0.0
    d_score = 1.0 / max(inputs.goal_distance, 0.1)
    rec_complete = 0.5 if inputs.just_completed else 1.0
    return d_score * inputs.n_incomplete * rec_complete


def greedy_utility(inputs: UtilityInputs) -> float:
    """Whoever is closest to its goal leads, whatever its workload."""
    if inputs.n_incomplete == 0 or inputs.goal_distance is None:
        return 0.0
    return 1.0 / max(inputs.goal_distance, 0.1)


def path_utility(inputs: UtilityInputs) -> float:
    """The original's product with the planned route's length in place of the straight
    distance: a robot close to its goal across a wall does not lead a team that must
    drive round. A robot with no route to its goal has utility 0 (it follows)."""
    if inputs.n_incomplete == 0 or inputs.goal_distance is None:
        return 0.0
    length = inputs.route_length()
    if length is None:
        return 0.0
    rec_complete = 0.5 if inputs.just_completed else 1.0
    return inputs.n_incomplete * rec_complete / max(length, 0.1)


ORIGINAL_SPEC = VariantSpec(
    kind="utility",
    name="original",
    entry=original_utility,
    summary="the original study's d_score x n_incomplete x rec_complete",
)
GREEDY_SPEC = VariantSpec(
    kind="utility",
    name="greedy",
    entry=greedy_utility,
    summary="1 / distance to the current goal: the closest robot leads",
)
PATH_SPEC = VariantSpec(
    kind="utility",
    name="path",
    entry=path_utility,
    summary="the original's product over the planned route's length, not the straight distance",
)
