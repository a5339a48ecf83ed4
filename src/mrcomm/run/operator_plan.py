"""A scripted operator (``--operator FILE``): where the operator sits and the commands
it sends, at given mission times — an operator in the loop that every repetition of a
study reproduces exactly.

The file::

    placement: base          # with the task assigner (its base station), a robot id, or
                             # virtual (no position: never out of range)
    commands:
      - {at: 60, command: reassign, task: "4", robot: robot_2}
      - {at: 90, command: pause, robot: robot_3}
      - {at: 120, command: resume, robot: robot_3}
      - {at: 150, command: add, task: extra, x: 3.0, y: 4.5, robot: robot_1}
      - {at: 400, command: redo, task: "2"}   # its owner does it again

Every command is checked before the run against the scenario and the commands before
it (tasks and robots known, a reassignment to a new owner, an added task on free space):
a bad file is one line naming the file and the command, and nothing runs.
"""

from __future__ import annotations

from pathlib import Path

import pydantic
from pydantic import BaseModel, ConfigDict, Field

from mrcomm.agents.operator import Operator, Ownership
from mrcomm.errors import InputError
from mrcomm.world.scenario import Scenario
from mrcomm.world.yamlfile import read_yaml, validation_error

#: Where the operator sits when the file says ``base``: with the task assigner.
BASE = "base"
#: An operator with no position: never out of range (simulation).
VIRTUAL = "virtual"


class PlannedCommand(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)

    at: float = Field(ge=0.0, allow_inf_nan=False, description="mission time, s")
    command: str
    robot: str = ""
    task: str = ""
    x: float | None = Field(None, allow_inf_nan=False)
    y: float | None = Field(None, allow_inf_nan=False)

    def where(self) -> tuple[float, float] | None:
        return (self.x, self.y) if self.x is not None and self.y is not None else None


class OperatorPlan(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)

    placement: str = BASE
    commands: tuple[PlannedCommand, ...] = ()

    def in_order(self) -> list[PlannedCommand]:
        return sorted(self.commands, key=lambda c: c.at)  # stable: file order at ties


def load_operator_plan(
    path: Path, scenario: Scenario, *, reassignable: bool = True
) -> OperatorPlan:
    """Read and check an operator file against ``scenario`` and the behaviour
    (``reassignable``: its spec's ``accepts_reassignment``); one-line InputError."""
    raw = read_yaml(path)
    if not isinstance(raw, dict):
        raise InputError("must be a mapping (placement, commands)", file=path)
    try:
        plan = OperatorPlan.model_validate(raw)
    except pydantic.ValidationError as err:
        raise validation_error(err, file=path, root=OperatorPlan) from None
    robots = tuple(r.id for r in scenario.robots)
    if plan.placement not in (BASE, VIRTUAL) and plan.placement not in robots:
        choices = ", ".join((BASE, VIRTUAL, *robots))
        raise InputError(f"must be one of {choices}", file=path, field="placement")
    ownership = Ownership.initial(robots, scenario.tasks, reassignable)
    order = sorted(range(len(plan.commands)), key=lambda i: plan.commands[i].at)
    for i in order:
        planned = plan.commands[i]
        field = f"commands[{i}]"
        where = planned.where()
        if where is not None and not scenario.grid.is_free(*where):
            raise InputError(f"({where[0]}, {where[1]}) is not free space", file=path, field=field)
        try:
            ownership.resolve(planned.command, planned.robot, planned.task, where)
        except ValueError as err:
            raise InputError(str(err), file=path, field=field) from None
    return plan


class ScriptedOperator:
    """Sends an operator plan's commands through the operator agent at their times."""

    def __init__(self, operator: Operator, plan: OperatorPlan) -> None:
        self.operator = operator
        self._queue = plan.in_order()

    @property
    def done(self) -> bool:
        """Every command sent."""
        return not self._queue

    def step(self, now: float) -> None:
        while self._queue and self._queue[0].at <= now + 1e-9:
            planned = self._queue.pop(0)
            self.operator.command(planned.command, planned.robot, planned.task, planned.where())
