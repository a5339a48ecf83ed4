"""The behaviour contract: what a task executor is given, what it may read, and the
hooks a behaviour implements.

A behaviour is a :class:`~mrcomm.agents.executor.TaskExecutor` (NB, the policy every
behaviour builds on) subclass with its own parameter model (``Params``, a subclass of
``ExecutorParams``); both ride on the runtime every behaviour shares
(:class:`~mrcomm.agents.runtime.ExecutorRuntime`). A behaviour whose statuses must
reach every member holds an AON part (``Statuses = AonStatuses``,
``agents/aon_statuses.py``) instead of publishing them plainly. Every executor is made
by the run's agent assembly (``run/agents.py``) as ``cls(context, params)``: the
:class:`AgentContext` (the robot's ports and what the scenario tells it) and the
behaviour's validated parameters, of type ``cls.Params`` — anything else is refused
when the executor is made, so a behaviour never runs on parameters it was not given.

**What a behaviour may read** (all read-only; :class:`BehaviourView` lists them with
their types): ``now`` (simulated s since the mission began; the runtime sets it, a
behaviour never reads a clock), ``robot_id``, ``rank(mate)`` (the team-wide tie-break
order), ``params``, ``team`` (the members named by the assignment), ``team_view`` (each
mate's last pose message and when it arrived; ``known_mates()``: the mates whose poses
the behaviour acts on, old ones left out or moved on as the parameters say),
``agenda`` (tasks still to do), ``completed`` (tasks this robot completed),
``known_done`` (tasks any robot reported complete), ``goal`` (the task being driven
to), ``link_sensor`` (its judgement of the link to a mate: RSSI and warning), ``base``
(the Base port: pose, status, navigate, cancel, plan, route), ``bus`` (the Bus port:
publish, subscribe), ``timeline`` (where its intervals and events are recorded).

**The hooks a behaviour implements** (each has NB's meaning by default):

* ``send_status(task_id, state)`` — how a task status is communicated (NB: one plain
  publish, or with the AON part when the behaviour holds one; ``status_message`` makes
  the message).
* ``before_state_step()`` — every step, before the state's handler.
* ``_step_<state>()`` — the handler of each state the behaviour adds to ``states`` /
  ``transitions`` (a ``transitions`` machine as data; checked when the class is
  defined: a state without a handler, or a handler without a state, is an error).
* ``after_task_completed()``, ``on_team_status(status)``, ``on_command(command)``,
  ``mate_presence(mate, present)``, ``rejoined()``, ``on_state_change()`` — events.
* ``done`` — nothing left to do (NB: agenda complete and idle).
* ``current_role()`` / ``current_leader()`` — what its poses announce.

Everything else of ``TaskExecutor`` (names beginning with ``_``) is the runtime's and
may change without notice.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from mrcomm.agents.collision import Mate
    from mrcomm.agents.executor_params import ExecutorParams
    from mrcomm.agents.team_view import TeamView
    from mrcomm.messaging.messages import TaskSpec
    from mrcomm.metrics.timeline import Timeline
    from mrcomm.ports import Base, Bus, LinkSensor
    from mrcomm.world.passages import Passages
    from mrcomm.world.scenario import AssignerSpec


@dataclass(frozen=True)
class AgentContext:
    """What one robot's executor is made with besides its parameters: its ports, its
    rank, its link sensor, and what the scenario tells it."""

    #: The robot's endpoint; its owner is the robot's id.
    bus: Bus
    #: The robot's motion layer.
    base: Base
    #: Where the executor records its intervals and events.
    timeline: Timeline
    #: The team-wide tie-break order: a rank per robot id, the same in every process.
    tie_break_rank: Callable[[str], float]
    #: How the robot judges its link to a mate (SLT, SSD, ESD; NoSensor: none).
    link_sensor: LinkSensor
    #: Which life of this robot's process (1, then 2 after a restart, ...).
    incarnation: int = 1
    #: The map's one-lane passages, where the robot queues (None: it does not).
    passages: Passages | None = None
    #: Where the task assigner is (the scenario's), for a robot that brings it a
    #: status it missed; ``assigner_home``: the start of the robot hosting it.
    assigner: AssignerSpec | None = None
    assigner_home: tuple[float, float] | None = None


def require_params(cls: type, params: object) -> None:
    """Refuse parameters that are not of the executor class's ``Params`` type (the
    first thing every executor does: no fallback to defaults)."""
    wanted = cls.Params  # type: ignore[attr-defined]
    if not isinstance(params, wanted):
        raise TypeError(
            f"{cls.__name__} takes parameters of type {wanted.__name__}, "
            f"got {type(params).__name__}"
        )


class BehaviourView(Protocol):
    """What a behaviour may read of its executor (see the module docstring); a
    :class:`~mrcomm.agents.executor.TaskExecutor` is one."""

    @property
    def now(self) -> float: ...

    robot_id: str
    params: ExecutorParams
    team: Sequence[str]
    team_view: TeamView
    agenda: list[TaskSpec]
    completed: list[str]
    known_done: set[str]
    goal: TaskSpec | None
    link_sensor: LinkSensor
    base: Base
    bus: Bus
    timeline: Timeline

    def rank(self, robot: str) -> float: ...

    def known_mates(self) -> Mapping[str, Mate]: ...

    def leaf(self) -> str: ...
