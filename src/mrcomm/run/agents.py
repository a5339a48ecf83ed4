"""The one assembly of a run's agents, for every mode.

:class:`AgentAssembly` builds each agent of a run from its configuration and scenario:
every robot's task executor (the chosen behaviour with its validated parameters, its
team-wide tie-break rank, its link sensor, what the scenario tells it), the task
assigner and the operator, and the named random stream each agent's receiver draws its
packet loss from. The simulation (``sim/mission.py``), each live agent process
(``live/agent.py``, the same for ``mrcomm agent`` on a real robot), the live operator
(``live/operator_host.py``), the console and the conformance kit all build their agents
here, so that what a run records as its settings is what every mode runs.

Settings that exist only in live mode (the AON lease) are :class:`AgentOverrides`,
validated against the behaviour's parameter model like ``--set`` values, before any
agent is built; nothing is patched into an agent after construction.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from mrcomm.agents.aon_statuses import lease_of
from mrcomm.agents.assigner import ASSIGNER_ID, TaskAssigner
from mrcomm.agents.behaviour import AgentContext
from mrcomm.agents.commands import OPERATOR_ID
from mrcomm.agents.executor import TaskExecutor
from mrcomm.agents.executor_params import ExecutorParams
from mrcomm.agents.operator import Operator
from mrcomm.errors import InputError
from mrcomm.ports import Base, Bus, LinkSensor
from mrcomm.run.config import RunConfig
from mrcomm.run.resources import ScenarioResources
from mrcomm.run.wiring import build_link_sensor
from mrcomm.seeding import stream

if TYPE_CHECKING:
    from mrcomm.metrics.timeline import Timeline


class AgentOverrides(BaseModel):
    """Live-only settings of a run's agents (``mrcomm live`` / ``mrcomm agent``
    options), applied to the behaviour's parameters when they are validated. A field a
    behaviour does not have is left out for it (NB has no AON lease)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    #: AON lease (simulated s): a member silent this long is reported left out.
    aon_lease: float | None = Field(default=None, gt=0)

    def updates(self) -> dict[str, Any]:
        """The behaviour parameters these overrides set (unset ones left out)."""
        return {k: v for k, v in self.model_dump().items() if v is not None}


class AgentAssembly:
    """Builds the agents of one run (see the module docstring). Made once per run and
    process; the behaviour's parameters are validated here once and shared by every
    executor it builds."""

    def __init__(
        self,
        config: RunConfig,
        resources: ScenarioResources,
        overrides: AgentOverrides | None = None,
    ) -> None:
        self.config = config
        self.resources = resources
        self.overrides = overrides or AgentOverrides()
        self.spec = config.spec("behaviour")
        executor_class = self.spec.load()
        if not (isinstance(executor_class, type) and issubclass(executor_class, TaskExecutor)):
            raise InputError(
                f"behaviour {self.spec.name!r} (from {self.spec.origin}) is not a "
                f"TaskExecutor subclass: {executor_class!r}",
                field="behaviour",
            )
        self.executor_class: type[TaskExecutor] = executor_class
        self.params: ExecutorParams = self._behaviour_params()
        self.robot_ids: tuple[str, ...] = tuple(r.id for r in resources.scenario.robots)
        order = stream(config.seed, "tie-break").permutation(len(self.robot_ids))
        #: Each robot's team-wide tie-break rank (a random order, the same in every process).
        self.ranks: dict[str, float] = {
            rid: float(order[i]) for i, rid in enumerate(self.robot_ids)
        }
        #: What every executor takes from the scenario (:func:`scenario_options`).
        self.options: dict[str, Any] = scenario_options(executor_class, resources)

    def _behaviour_params(self) -> ExecutorParams:
        """The behaviour's parameters: the run's ``behaviour`` section with the
        overrides the behaviour has, validated by its spec's model."""
        params = self.config.variant_params("behaviour")
        model = type(params)
        updates = {k: v for k, v in self.overrides.updates().items() if k in model.model_fields}
        if updates:  # validated as --set values are: limits and types of the model
            given = params.model_dump(exclude_defaults=True)
            params = self.spec.make_params({**given, **updates})
        if not isinstance(params, self.executor_class.Params):
            raise InputError(
                f"behaviour {self.spec.name!r}: its spec's parameter model "
                f"{type(params).__name__} is not its executor's "
                f"{self.executor_class.Params.__name__}",
                field="behaviour",
            )
        return params

    # -- what each agent is made of ------------------------------------------------------
    def rank_of(self, robot: str) -> float:
        """``robot``'s team-wide tie-break rank."""
        return self.ranks[robot]

    def loss_stream(self, agent: str) -> np.random.Generator:
        """The stream ``agent``'s receiver draws its packet loss from."""
        return stream(self.config.seed, "loss", agent)

    def loss_streams(self, agents: Sequence[str]) -> dict[str, np.random.Generator]:
        return {a: self.loss_stream(a) for a in agents}

    def link_sensor(self) -> LinkSensor:
        """A new link sensor for one robot's agent (each robot has its own)."""
        return build_link_sensor(self.config, self.resources)

    # -- the agents ----------------------------------------------------------------------
    def executor(
        self,
        bus: Bus,
        base: Base,
        timeline: Timeline,
        *,
        link_sensor: LinkSensor,
        incarnation: int = 1,
    ) -> TaskExecutor:
        """The task executor of the robot that owns ``bus``."""
        context = AgentContext(
            bus=bus,
            base=base,
            timeline=timeline,
            tie_break_rank=self.rank_of,
            link_sensor=link_sensor,
            incarnation=incarnation,
            **self.options,
        )
        return self.executor_class(context, self.params)

    def assigner(self, bus: Bus, *, incarnation: int = 1) -> TaskAssigner:
        """The task assigner (on ``bus``, owned by ``ASSIGNER_ID``); with AON it
        leaves out silent members after the team's lease (the behaviour's
        ``aon_lease``, as its robots do)."""
        assert bus.owner == ASSIGNER_ID, bus.owner
        return TaskAssigner(
            bus,
            self.robot_ids,
            self.resources.scenario.tasks,
            incarnation=incarnation,
            use_aon=self.spec.uses_aon,
            aon_lease=lease_of(self.params),
        )

    def operator(self, bus: Bus, *, incarnation: int = 1) -> Operator:
        """The operator (on ``bus``, owned by ``OPERATOR_ID``)."""
        assert bus.owner == OPERATOR_ID, bus.owner
        return Operator(
            bus,
            self.robot_ids,
            self.resources.scenario.tasks,
            incarnation=incarnation,
            reassignable=self.spec.accepts_reassignment,
        )


def scenario_options(cls: type[TaskExecutor], resources: ScenarioResources) -> dict[str, Any]:
    """What an executor takes from the scenario beyond the common arguments: the map's
    one-lane passages, and where the task assigner is, for one whose statuses go with
    AON — its spec, and for one on a robot that robot's start (its home)."""
    options: dict[str, Any] = {"passages": resources.passages}
    if cls.uses_aon:
        scenario = resources.scenario
        host = scenario.assigner.host
        home = next(((r.pose.x, r.pose.y) for r in scenario.robots if r.id == host), None)
        options.update(assigner=scenario.assigner, assigner_home=home)
    return options
