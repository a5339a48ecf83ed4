"""The operator as a live team member: a process (``mrcomm agent --robot operator
--operator FILE``; ``mrcomm live --operator FILE`` starts it) whose agent is the
:class:`~mrcomm.agents.operator.Operator`, stepped on the world's clock like every
agent, sending the file's commands at their times with AON over Zenoh.

It sits with the task assigner (``placement: base``): the receivers judge its links
from the assigner's position (its host robot, or its base station). Its commands and
what became of them are journalled at the end (``operator``) and merged into the
run's result by the collection.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from mrcomm.agents.assigner import ASSIGNER_ID
from mrcomm.agents.commands import OPERATOR_ID
from mrcomm.errors import InputError
from mrcomm.live.journal import Journal
from mrcomm.net.zenoh_bus import PositionBook, ZenohBus
from mrcomm.run.agents import AgentAssembly
from mrcomm.run.operator_plan import BASE, OperatorPlan, ScriptedOperator, load_operator_plan
from mrcomm.world.scenario import Scenario


def place_operator(positions: PositionBook, scenario: Scenario) -> None:
    """Every process judges the operator's links from the task assigner's position."""
    spec = scenario.assigner
    if spec.kind == "robot" and spec.host is not None:
        positions.aliases[OPERATOR_ID] = spec.host
    elif spec.kind == "base_station" and spec.position is not None:
        positions.fixed[OPERATOR_ID] = (spec.position[0], spec.position[1])


class OperatorHost:
    """The operator agent of a live process and its scripted commands."""

    def __init__(
        self,
        bus: ZenohBus,
        agents: AgentAssembly,
        incarnation: int,
        plan_path: Path | None,
    ) -> None:
        scenario = agents.resources.scenario
        reassignable = agents.spec.accepts_reassignment
        plan = (
            load_operator_plan(plan_path, scenario, reassignable=reassignable)
            if plan_path is not None
            else OperatorPlan()
        )
        if plan.placement != BASE:
            raise InputError(
                "live mode places the operator with the task assigner (placement: base)",
                field="--operator",
            )
        endpoint = bus.endpoint(OPERATOR_ID, agents.loss_stream(OPERATOR_ID))
        self.operator = agents.operator(endpoint, incarnation=incarnation)
        self.script = ScriptedOperator(self.operator, plan)
        #: Called at each step before the operator steps (a console applies the
        #: commands its page queued, and takes its snapshot).
        self.on_step: Callable[[float], None] | None = None

    def step(self, now: float) -> None:
        self.operator.set_time(now)
        if self.on_step is not None:
            self.on_step(now)
        self.script.step(now)
        self.operator.step(now)

    @property
    def done(self) -> bool:
        return self.script.done

    @property
    def settled(self) -> bool:
        return self.operator.settled

    def journal(self, journal: Journal, now: float) -> None:
        journal.write("operator", time=now, summary=self.operator.summary())


__all__ = ["ASSIGNER_ID", "OperatorHost", "place_operator"]
