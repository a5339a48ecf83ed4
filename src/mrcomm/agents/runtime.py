"""The runtime every behaviour rides on: what a task executor is besides its policy.

:class:`ExecutorRuntime` holds the robot's ports and its knowledge of the team, and does
what every behaviour does alike: it validates the executor's parameters, builds its
state machine from the class's tables (``states`` / ``transitions``, handlers checked
when the class is defined), subscribes to the team's topics (assignment, poses, task
statuses, heartbeats and the operator's commands), keeps the team view, publishes the
robot's pose at the behaviour's rate, sends its statuses (plainly, or with the
behaviour's AON part, ``Statuses``), and steps: the commands, the choice of the next
task while ``unassigned``, the pose, the AON part, the behaviour's
``before_state_step`` and the handler of its state. The NB policy is
:class:`~mrcomm.agents.executor.TaskExecutor`; the contract a behaviour may rely on is
``agents/behaviour.py``.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping, Sequence
from typing import Any, ClassVar, cast

from transitions import Machine

from mrcomm.agents.aon_statuses import AonStatuses
from mrcomm.agents.behaviour import AgentContext, require_params
from mrcomm.agents.collision import Mate
from mrcomm.agents.commands import CommandInbox, command_team
from mrcomm.agents.executor_params import ExecutorParams
from mrcomm.agents.machine_table import StateEntry, build_table, quiet_rebinding
from mrcomm.agents.mates import Mates
from mrcomm.agents.team_view import TeamView
from mrcomm.messaging.aon import AonEndpoint
from mrcomm.messaging.messages import (
    TOPIC_ASSIGNMENT,
    TOPIC_HEARTBEAT,
    TOPIC_POSE,
    TOPIC_TASK_STATUS,
    Assignment,
    Message,
    OperatorCommand,
    PoseMsg,
    TaskSpec,
    TaskState,
    TaskStatus,
)
from mrcomm.metrics import labels as L
from mrcomm.metrics.timeline import ACTIVITY
from mrcomm.ports import Addressed, BatchHandler, KeepLatest, LinkSensor
from mrcomm.world.geometry import Pose


class ExecutorRuntime:
    """The runtime of one robot's executor (see the module docstring)."""

    #: The part that sends the behaviour's statuses with AON (None: plain
    #: publications); the runtime makes one per executor (``statuses``).
    Statuses: ClassVar[type[AonStatuses] | None] = None
    #: Whether task statuses travel with AON (the assigner then listens with AON too):
    #: whether the class has a ``Statuses`` part.
    uses_aon: ClassVar[bool] = False
    #: The behaviour's machine as data (a behaviour sets them).
    states: ClassVar[list[Any]] = []
    transitions: ClassVar[list[dict[str, Any]]] = []
    initial = ""
    machine_class: type[Machine] = Machine
    Params: ClassVar[type[ExecutorParams]] = ExecutorParams
    #: Leaf states stepped by no handler.
    PASSIVE_STATES: ClassVar[frozenset[str]] = frozenset()
    #: Each leaf state's entry (handler, leaf, top), built and checked per class.
    STATE_TABLE: ClassVar[dict[str, StateEntry]] = {}

    state: str
    trigger: Callable[..., bool]

    def __init__(self, context: AgentContext, params: ExecutorParams) -> None:
        """``context``: the robot's ports and what the scenario tells it; ``params``:
        the behaviour's validated parameters, of type ``Params`` (anything else is
        refused: a behaviour never runs on parameters it was not given)."""
        require_params(type(self), params)
        bus = context.bus
        self.bus = bus
        self.base = context.base
        self.timeline = context.timeline
        self.params = params
        self.link_sensor: LinkSensor = context.link_sensor
        #: judge_poses "on_receipt": (question, mate) -> (when the mate's pose arrived,
        #: the answer from it); see judged_on_receipt.
        self._verdicts: dict[tuple[str, str], tuple[float, bool]] | None = (
            {} if params.judge_poses == "on_receipt" else None
        )
        self.incarnation = context.incarnation
        self._rank = context.tie_break_rank
        self.robot_id = bus.owner
        #: The part sending statuses with AON (a behaviour's ``Statuses``), or None.
        self.statuses: AonStatuses | None = (
            self.Statuses(self, context) if self.Statuses is not None else None
        )
        self.team: Sequence[str] = ()
        self.agenda: list[TaskSpec] = []
        self.completed: list[str] = []
        self.known_done: set[str] = set()  # task ids any robot reported complete
        self.team_view = TeamView()
        self.goal: TaskSpec | None = None
        self._now = 0.0
        self._t0: float | None = None  # assignment received: mission start for this robot
        self._seq = 0
        self._next_pose = 0.0
        with quiet_rebinding():
            self.machine = self.machine_class(
                model=self,
                states=self.states,
                transitions=self.transitions,
                initial=self.initial,
                auto_transitions=False,
                after_state_change="_after_state_change",
            )
        # Every robot's assignment reaches every robot: it acts on its own only.
        bus.subscribe(TOPIC_ASSIGNMENT, Addressed(self._on_assignment, "robot", self.robot_id))
        # A mate's latest pose is all the view keeps: a bus may keep it for the view.
        view = self.team_view
        bus.subscribe(TOPIC_POSE, KeepLatest(self._on_poses, view.attach, ("x", "y")))
        if self.statuses is not None:
            bus.subscribe(TOPIC_POSE, BatchHandler(self.statuses.heard))  # AON's lease
        bus.subscribe(TOPIC_TASK_STATUS, self._on_status)
        self.paused = False  # by the operator
        self._new_tasks = False  # the operator gave tasks: plan again once idle
        self._assigner_id = ""
        self.commands = CommandInbox(bus, self.incarnation, self._command_team, self.on_command)
        if self.statuses is not None:
            bus.subscribe(TOPIC_HEARTBEAT, self._on_heartbeat)  # signs of life for AON

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls.uses_aon = cls.Statuses is not None
        cls.STATE_TABLE = build_table(cls, cls.states, cls.PASSIVE_STATES)

    @property
    def mates(self) -> Mapping[str, PoseMsg]:
        """Each mate's last received pose (:attr:`TeamView.poses`)."""
        return self.team_view.poses

    def leaf(self) -> str:
        """Innermost state name (``na_navigating`` -> ``navigating``)."""
        return self.STATE_TABLE[self.state].leaf

    @property
    def aon_statuses(self) -> AonStatuses:
        """The AON part of a behaviour that has one (``Statuses``; an error otherwise)."""
        if self.statuses is None:
            raise TypeError(f"{type(self).__name__} sends no statuses with AON")
        return self.statuses

    @property
    def aon(self) -> AonEndpoint | None:
        """The AON endpoint of the statuses part (None: no part, or not opened yet)."""
        return self.statuses.aon if self.statuses is not None else None

    @property
    def assigner_id(self) -> str:
        """Who sent this robot its assignment: the task assigner ("" before)."""
        return self._assigner_id

    def rank(self, robot: str) -> float:
        """``robot``'s place in the team-wide tie-break order."""
        return self._rank(robot)

    @property
    def now(self) -> float:
        """The agent's current time (simulated s since the mission began)."""
        return self._now

    def set_time(self, now: float) -> None:
        """The time of the coming delivery and step: messages handled before ``step``
        are stamped with it (the runtime calls this first)."""
        self._now = now

    def mate_presence(self, mate: str, present: bool) -> None:
        """The runtime says a mate's process has gone (its liveliness vanished) or is
        back (live mode). A behaviour treats a departed mate as gone: LF's followers
        of a departed leader dissolve the group and carry on."""
        if present:
            self.team_view.departed.discard(mate)
        else:
            self.team_view.departed.add(mate)

    def step(self, now: float) -> None:
        self._now = now
        if self._t0 is None:
            return
        self.commands.step(now)
        if self.leaf() == "unassigned" and not self.paused:
            self._select_next()
        if now >= self._next_pose:
            self._publish_pose()
            self._next_pose = max(self._next_pose + self.params.pose_period, now)
        if self.paused:
            return  # stopped by the operator: shares its pose, decides nothing
        if self.statuses is not None:
            self.statuses.step(now)  # AON first, then the behaviour
        self.before_state_step()
        # A behaviour may handle a nested state itself (``_step_leader_holding``);
        # otherwise the NB handler of the innermost state runs (see machine_table).
        handler = self.STATE_TABLE[self.state].handler
        if handler is not None:
            handler(self)

    def before_state_step(self) -> None:
        """Hook run every step before the state handler (LF monitors links here)."""

    # -- state handlers --------------------------------------------------------------
    def mate_link_warns(self, mate: str, pose: Pose, x: float, y: float) -> bool:
        """Whether the link to ``mate``, at (x, y), is in warning for this robot at
        ``pose``; with ``judge_poses`` "on_receipt" as :meth:`judged_on_receipt` says, for a
        threshold judged from positions (SLT, SSD). A measured signal (ESD) is read as it
        comes."""
        sensor = self.link_sensor
        if self._verdicts is None or not sensor.positional:  # (no closure per question)
            return sensor.warning(mate, pose, x, y, self._now)
        return self.judged_on_receipt(
            "link", mate, lambda: sensor.warning(mate, pose, x, y, self._now)
        )

    def judged_on_receipt(self, question: str, mate: str, judge: Callable[[], bool]) -> bool:
        """``judge()``: a question about ``mate`` answered from its last pose. With
        ``judge_poses`` "every_step" it is answered anew each time; with "on_receipt" once
        per pose of the mate, at the first time it is asked after the pose arrived, and
        that answer holds until the next pose arrives (the original applied its
        thresholds to received messages: thesis lines 1201, 1531)."""
        verdicts = self._verdicts
        if verdicts is None:
            return judge()
        heard = self.team_view.heard.get(mate)
        cached = verdicts.get((question, mate))
        if cached is not None and heard is not None and cached[0] == heard:
            return cached[1]
        verdict = judge()
        if heard is not None:
            verdicts[question, mate] = (heard, verdict)
        return verdict

    def known_mates(self) -> Mapping[str, Mate]:
        """The mates as collision avoidance and making way see them now: fresh enough,
        and moved on for their age (:meth:`TeamView.known`)."""
        params = self.params
        return self.team_view.known(self._now, params.mate_max_age, params.mate_extrapolation)

    def _mates_near(self, pose: Pose, reach: float) -> Collection[Mate]:
        """The mates of :meth:`known_mates` that may lie within ``reach`` of ``pose``
        along both axes, in the same order (:meth:`TeamView.near`: without a loop over
        the whole team when it is large); the caller tests each one."""
        return self._mates_near_point(pose.x, pose.y, reach)

    def _mates_near_point(self, x: float, y: float, reach: float) -> Collection[Mate]:
        """:meth:`_mates_near` of a point (the passage queue asks about its passages)."""
        params = self.params
        return self.team_view.near(
            x, y, reach, self._now, params.mate_max_age, params.mate_extrapolation
        )

    def rejoined(self) -> None:
        """Back after being away (live mode: its process was stopped and its links
        dropped): statuses published around then may never have left. Report every
        completed task again — the assigner counts a task once. Behaviours that send
        statuses with AON need not: AON re-sends by itself."""
        if self.statuses is not None:
            return
        for task_id in self.completed:
            self.send_status(task_id, TaskState.SUCCESS)

    def send_status(self, task_id: str, state: TaskState) -> None:
        """NB: publish once, no acknowledgement; a behaviour with a ``Statuses`` part
        sends with it (AON)."""
        if self.statuses is not None:
            self.statuses.send(task_id, state)
            return
        self.bus.publish(TOPIC_TASK_STATUS, self.status_message(task_id, state))

    def status_message(self, task_id: str, state: TaskState) -> TaskStatus:
        """A new status message of this robot (the next sequence number, now)."""
        self._seq += 1
        return TaskStatus(
            sender=self.robot_id,
            incarnation=self.incarnation,
            seq=self._seq,
            stamp=self._now,
            robot=self.robot_id,
            task_id=task_id,
            state=state,
        )

    def _publish_pose(self) -> None:
        pose = self.base.pose
        self._seq += 1
        self.bus.publish(
            TOPIC_POSE,
            PoseMsg(
                sender=self.robot_id,
                incarnation=self.incarnation,
                seq=self._seq,
                stamp=self._now,
                x=pose.x,
                y=pose.y,
                theta=pose.theta,
                v=self.base.speed,
                goal_dist=self._goal_distance(),
                role=self.current_role(),
                leader=self.current_leader(),
            ),
        )

    def current_role(self) -> str:
        """Team role shared in pose messages (NB has none)."""
        return ""

    def current_leader(self) -> str:
        """The robot this one follows, shared in pose messages (NB: nobody)."""
        return ""

    def _on_assignment(self, message: Message) -> None:
        assert isinstance(message, Assignment)
        if message.robot != self.robot_id or self._t0 is not None:
            return
        self.agenda = list(message.tasks)
        self.team = Mates(message.team, self.robot_id)
        self._assigner_id = message.sender
        self._t0 = self._now
        self.timeline.event(L.ASSIGNMENT_RECEIVED, self._now, tasks=len(self.agenda))
        self.timeline.set_state(ACTIVITY, L.INIT, self._now)
        if self.statuses is not None:
            self.statuses.assigned(message)

    def _on_poses(self, messages: Sequence[Message]) -> None:
        """Mates' poses that reached the robot, in order (one, or a step's batch)."""
        self.team_view.hear_all(cast("Sequence[PoseMsg]", messages), self._now, self.robot_id)

    def _on_heartbeat(self, message: Message) -> None:
        if self.statuses is not None:
            self.statuses.heard((message,))

    def _on_status(self, message: Message) -> None:
        assert isinstance(message, TaskStatus)
        self.on_team_status(message)

    def on_team_status(self, status: TaskStatus) -> None:
        """A team mate's status reached us (by whatever layer)."""
        if status.state is TaskState.SUCCESS:
            self.known_done.add(status.task_id)

    # -- the operator's commands (agents/commands.py) --------------------------------
    def _command_team(self) -> tuple[str, ...] | None:
        team = (*self.team, self.robot_id)  # AON orders members itself
        return None if self._t0 is None else command_team(team, self._assigner_id)

    def on_state_change(self) -> None:
        """Hook after every state change (LF records roles here)."""

    # -- what the behaviour decides (NB: agents/executor.py) --------------------------
    def _select_next(self) -> None:
        """Choose what to do next (called while ``unassigned``)."""
        raise NotImplementedError

    def _goal_distance(self) -> float:
        """Distance to where the robot drives, shared in its poses (-1: nowhere)."""
        return -1.0

    def _after_state_change(self) -> None:
        """After every transition (the machine calls it by name)."""

    def on_command(self, command: OperatorCommand) -> None:
        """An operator's command for this robot arrived (agents/commands.py)."""
