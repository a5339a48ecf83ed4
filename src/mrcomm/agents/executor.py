"""Task executor agent with the NB behaviour.

One per robot. Receives its agenda, repeatedly drives to the closest available task,
executes it, publishes its status once (plain publish-subscribe: no acknowledgement, no
re-send), shares its pose at 5 Hz, avoids near collisions with team mates and records
its own timeline. A navigation failure leaves the task in the agenda (a task never fails
because the robot could not reach it; it fails only if its status is not communicated).
Empty agenda -> idle until the mission ends.

The behaviour is a state machine (``transitions``) described as data in
:data:`NB_STATES` / :data:`NB_TRANSITIONS`, so diagrams come from the machine itself.
Communication-aware behaviours subclass this executor (LF encloses NB).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Collection, Mapping, Sequence
from typing import Any, ClassVar, cast

from transitions import Machine

from mrcomm.agents import agenda
from mrcomm.agents.avoidance import Avoidance
from mrcomm.agents.behaviour import AgentContext, require_params
from mrcomm.agents.collision import Mate
from mrcomm.agents.commands import CommandInbox, command_team
from mrcomm.agents.executor_params import ExecutorParams
from mrcomm.agents.machine_table import StateEntry, build_table, quiet_rebinding
from mrcomm.agents.making_way import aside_goals, in_way
from mrcomm.agents.occupied_goal import OccupiedGoal
from mrcomm.agents.passage_queue import PassageQueue
from mrcomm.agents.team_view import TeamView
from mrcomm.messaging.messages import (
    TOPIC_ASSIGNMENT,
    TOPIC_POSE,
    TOPIC_TASK_STATUS,
    Assignment,
    CommandKind,
    Message,
    OperatorCommand,
    PoseMsg,
    TaskSpec,
    TaskState,
    TaskStatus,
)
from mrcomm.metrics import labels as L
from mrcomm.metrics.timeline import ACTIVITY
from mrcomm.ports import BatchHandler, LinkSensor, NavStatus
from mrcomm.world.geometry import Pose

NB_STATES = [
    "unassigned",
    "navigating",
    "avoiding",
    "executing",
    "waiting",
    "retrying",
    "idle",
    "clearing",
]
_PLANNING_SOURCES = ["unassigned", "executing", "waiting", "retrying"]
NB_TRANSITIONS: list[dict[str, Any]] = [
    {"trigger": "go", "source": _PLANNING_SOURCES, "dest": "navigating"},
    {"trigger": "wait", "source": _PLANNING_SOURCES, "dest": "waiting"},
    {"trigger": "finish_agenda", "source": _PLANNING_SOURCES, "dest": "idle"},
    {"trigger": "arrive", "source": "navigating", "dest": "executing"},
    {"trigger": "nav_fail", "source": "navigating", "dest": "retrying"},
    {"trigger": "conflict", "source": "navigating", "dest": "avoiding"},
    {"trigger": "resume", "source": "avoiding", "dest": "navigating"},
    {"trigger": "make_way", "source": "idle", "dest": "clearing"},
    {"trigger": "cleared", "source": "clearing", "dest": "idle"},
    # An operator gave an idle robot tasks: it plans again.
    {"trigger": "new_tasks", "source": "idle", "dest": "unassigned"},
]

#: Timeline activity recorded while in each state.
_ACTIVITY_OF_STATE = {
    "navigating": L.MOVING,
    "avoiding": L.DELAY,
    "executing": L.TASK,
    "waiting": L.WAITING,
    "retrying": L.WAITING,
    "idle": L.IDLE,
    "clearing": L.MOVING,
}


class TaskExecutor:
    """NB task executor: a stepped state machine acting through the Bus and Base ports."""

    #: Whether task statuses travel with AON (the assigner then listens with AON too).
    uses_aon = False

    states: list[Any] = NB_STATES
    transitions: list[dict[str, Any]] = NB_TRANSITIONS
    initial = "unassigned"
    machine_class: type[Machine] = Machine
    Params: ClassVar[type[ExecutorParams]] = ExecutorParams
    #: Leaf states stepped by no handler (``unassigned``: the step chooses a task).
    PASSIVE_STATES: ClassVar[frozenset[str]] = frozenset({"unassigned"})
    #: Each leaf state's entry (handler, leaf, top), built and checked per class.
    STATE_TABLE: ClassVar[dict[str, StateEntry]] = {}

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls.STATE_TABLE = build_table(cls, cls.states, cls.PASSIVE_STATES)

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
        self.incarnation = context.incarnation
        tie_break_rank = context.tie_break_rank
        self._rank = tie_break_rank
        self.robot_id = bus.owner
        self.team: tuple[str, ...] = ()
        self.agenda: list[TaskSpec] = []
        self.completed: list[str] = []
        self.known_done: set[str] = set()  # task ids any robot reported complete
        self.team_view = TeamView()
        self.goal: TaskSpec | None = None
        self._now = 0.0
        self._t0: float | None = None  # assignment received: mission start for this robot
        self._seq = 0
        self._next_pose = 0.0
        self._moved_once = False
        self._state_since = 0.0
        self.avoidance = Avoidance(self.robot_id, self.params, tie_break_rank)
        self.queue: PassageQueue | None = None
        passages = context.passages
        if passages is not None and len(passages):
            p = self.params
            self.queue = PassageQueue(
                passages, p.queue_distance, p.queue_timeout, p.collision.moving_speed,
                tie_break_rank, self.robot_id,
            )  # fmt: skip
        self._clearing_goals: list[tuple[float, float]] = []
        self._occupied = OccupiedGoal(self.params.occupied_goal)
        self._execute_until = 0.0
        self._agenda_reported = False
        with quiet_rebinding():
            self.machine = self.machine_class(
                model=self,
                states=self.states,
                transitions=self.transitions,
                initial=self.initial,
                auto_transitions=False,
                after_state_change="_after_state_change",
            )
        bus.subscribe(TOPIC_ASSIGNMENT, self._on_assignment)
        bus.subscribe(TOPIC_POSE, BatchHandler(self._on_poses))
        bus.subscribe(TOPIC_TASK_STATUS, self._on_status)
        self.paused = False  # by the operator
        self._new_tasks = False  # the operator gave tasks: plan again once idle
        self._assigner_id = ""
        self.commands = CommandInbox(bus, self.incarnation, self._command_team, self.on_command)

    # -- the agent's life ----------------------------------------------------------
    @property
    def mates(self) -> Mapping[str, PoseMsg]:
        """Each mate's last received pose (:attr:`TeamView.poses`)."""
        return self.team_view.poses

    @property
    def done(self) -> bool:
        """Nothing left to do: agenda complete and nothing left to communicate."""
        return self._t0 is not None and not self.agenda and self.leaf() == "idle"

    def leaf(self) -> str:
        """Innermost state name (``na_navigating`` -> ``navigating``)."""
        return self.STATE_TABLE[self.state].leaf

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
        self.before_state_step()
        # A behaviour may handle a nested state itself (``_step_leader_holding``);
        # otherwise the NB handler of the innermost state runs (see machine_table).
        handler = self.STATE_TABLE[self.state].handler
        if handler is not None:
            handler(self)

    def before_state_step(self) -> None:
        """Hook run every step before the state handler (LF monitors links here)."""

    # -- state handlers --------------------------------------------------------------
    def _step_navigating(self) -> None:
        if self.goal is not None and self.goal not in self.agenda:
            self.drop_goal()  # the operator reassigned the task it was driving to
            return
        status = self.base.status
        if not self._moved_once and self.base.speed > 1e-3:
            self._moved_once = True
            self.timeline.event(L.STARTED_MOVING, self._now)
            self.timeline.set_state(ACTIVITY, L.MOVING, self._now)
        standing = self.base.speed < self.params.collision.moving_speed
        if status is NavStatus.ACTIVE and standing and self._goal_occupied():
            self.base.cancel()
            status = NavStatus.SUCCEEDED
        if status is NavStatus.SUCCEEDED:
            assert self.goal is not None
            self.timeline.event(L.ARRIVED, self._now, task_id=self.goal.task_id)
            self._execute_until = self._now + self.goal.duration
            self.trigger("arrive")
            self._step_executing()  # a zero-duration task completes right away
        elif status is NavStatus.ABORTED:
            self.timeline.event(L.NAV_ABORTED, self._now)
            self.trigger("nav_fail")
        else:
            self._check_collisions()

    def _goal_occupied(self) -> bool:
        """A mate has stood on the goal, this robot standing before it, too long."""
        goal, pose = self.goal, self.base.pose
        assert goal is not None
        params = self.params.occupied_goal
        near = self._mates_near(pose, params.reach + params.radius)
        taker = self._occupied.check(self._now, pose, (goal.x, goal.y), near)
        if taker is not None:
            self.timeline.event(L.GOAL_OCCUPIED, self._now, task_id=goal.task_id, mate=taker.robot)
        return taker is not None

    def _step_executing(self) -> None:
        if self._now + 1e-9 < self._execute_until:
            return
        task = self.goal
        assert task is not None
        if task not in self.agenda:  # reassigned by the operator on the way
            self.goal = None
            self.timeline.event(L.TASK_DROPPED, self._now, task_id=task.task_id)
            self.after_task_completed()
            return
        self.agenda.remove(task)
        self.completed.append(task.task_id)
        self.known_done.add(task.task_id)
        self.goal = None
        self.send_status(task.task_id, TaskState.SUCCESS)
        self.timeline.event(L.TASK_COMPLETED, self._now, task_id=task.task_id)
        self.after_task_completed()

    def after_task_completed(self) -> None:
        """What to do once a task is done and reported: NB picks the next one."""
        self._select_next()

    def _step_waiting(self) -> None:
        self._select_next()

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

    def _plan_new_tasks(self) -> None:
        self._new_tasks = False
        self.trigger("new_tasks")

    def _step_idle(self) -> None:
        if self._new_tasks and self.agenda:  # given tasks while making way, say
            self._plan_new_tasks()
            return
        # Only mates within the make-way radius can be in the way: those farther along
        # an axis are passed over here, without a call (in_way_of tests the rest).
        pose = self.base.pose
        radius = self.params.make_way_radius
        x, y = pose.x, pose.y
        for mate in self._mates_near(pose, radius):
            if abs(mate.x - x) > radius or abs(mate.y - y) > radius:
                continue
            if self.in_way_of(mate, pose):
                self.step_aside(mate)
                return

    # -- making way ------------------------------------------------------------------
    def in_way_of(self, mate: Mate, pose: Pose | None = None) -> bool:
        """This robot (without a goal of its own, or following) stands close to a mate
        that has a goal: ahead of it, or next to it while it is stuck. ``pose``: the
        robot's, when the caller has read it already (a loop over mates reads it once)."""
        params = self.params
        if pose is None:
            pose = self.base.pose
        speed = params.collision.moving_speed
        return in_way(pose, mate, params.make_way_radius, speed, self._now)

    def step_aside(self, mate: Mate) -> None:
        """Step aside of the mate's heading (left, right, then straight away from it);
        the base snaps each candidate to free space and aborts unreachable ones."""
        self._clearing_goals = aside_goals(self.base.pose, mate, self.params.make_way_step)
        self.timeline.event(L.MADE_WAY, self._now, mate=mate.robot)
        self.base.navigate_to(*self._clearing_goals.pop(0))
        self.trigger("make_way")

    def _step_clearing(self) -> None:
        status = self.base.status
        if status is NavStatus.ABORTED and self._clearing_goals:
            self.base.navigate_to(*self._clearing_goals.pop(0))
            return
        timed_out = self._now - self._state_since > self.params.make_way_timeout
        if status is NavStatus.ACTIVE and not timed_out:
            return  # finish the step aside
        self.base.cancel()
        self.trigger("cleared")

    def _step_retrying(self) -> None:
        if self._now - self._state_since >= self.params.nav_retry_delay:
            self._select_next()

    def _step_avoiding(self) -> None:
        if self.queue is not None and self.queue.waiting is not None:
            if self.queue.still_waiting(self.base.pose, self._mates_near_point, self._now):
                return
        # The pose is read only when needed: a base may draw noise for each reading.
        elif not self.avoidance.may_resume(
            self._current_pose, self.known_mates(), self._now, self._state_since
        ):
            return
        target = self.navigation_target()
        if target is not None:
            self.base.navigate_to(*target)
        self.trigger("resume")

    def _current_pose(self) -> Pose:
        return self.base.pose

    def navigation_target(self) -> tuple[float, float] | None:
        """Where the robot is driving (NB: its current task)."""
        return (self.goal.x, self.goal.y) if self.goal is not None else None

    # -- decisions -----------------------------------------------------------------
    def _select_next(self) -> None:
        """Greedy agenda: the closest task that is available now."""
        if not self.agenda:
            self.trigger("finish_agenda")
            return
        assert self._t0 is not None
        elapsed = self._now - self._t0
        ready = agenda.available(self.agenda, elapsed, self.known_done)
        if not ready:
            if self.leaf() != "waiting":
                self.trigger("wait")
            return
        task = agenda.closest(ready, self.base.pose)
        self.goal = task
        self.base.navigate_to(task.x, task.y)
        self.trigger("go")

    def _mates_near_point(self, x: float, y: float, reach: float) -> Collection[Mate]:
        """:meth:`_mates_near` of a point (the passage queue asks about its passages)."""
        params = self.params
        return self.team_view.near(
            x, y, reach, self._now, params.mate_max_age, params.mate_extrapolation
        )

    def _queued(self, pose: Pose) -> bool:
        """Whether the robot stops to queue at a one-lane passage ahead (then it is)."""
        assert self.queue is not None
        target = self.navigation_target()
        if target is None:
            return False
        queued = self.queue.wait_for(pose, target, self._mates_near_point, self._now, self.base)
        if queued is None:
            return False
        passage, mate = queued
        self.timeline.event(L.QUEUED, self._now, mate=mate.robot, passage=passage.index)
        self.base.navigate_to(*self.queue.hold_point(pose))  # out of the mouth
        self.trigger("conflict")
        return True

    def _check_collisions(self) -> None:
        pose = self.base.pose
        queue = self.queue  # (near no passage: one lookup, for every robot every step)
        if queue is not None and queue.near(pose.x, pose.y) and self._queued(pose):
            return
        # Only the mates near enough to be in conflict (detect tests it).
        near = self._mates_near(pose, self.avoidance.reach)
        conflict = self.avoidance.detect(pose, near, self._now, self._goal_distance)
        if conflict is None:
            return
        self.timeline.event(
            L.NEAR_COLLISION,
            self._now,
            mate=conflict.mate,
            kind=conflict.kind,
            repeat=conflict.repeat,
            x=round(pose.x, 3),
            y=round(pose.y, 3),
        )
        self.base.cancel()
        self.trigger("conflict")

    # -- communication ---------------------------------------------------------------
    def rejoined(self) -> None:
        """Back after being away (live mode: its process was stopped and its links
        dropped): statuses published around then may never have left. Report every
        completed task again — the assigner counts a task once. Behaviours that send
        statuses with AON need not: AON re-sends by itself."""
        for task_id in self.completed:
            self.send_status(task_id, TaskState.SUCCESS)

    def send_status(self, task_id: str, state: TaskState) -> None:
        """NB: publish once, no acknowledgement (communication-aware behaviours
        override this to send with AON)."""
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

    def _goal_distance(self) -> float:
        target = self.navigation_target()
        if target is None or self.leaf() not in ("navigating", "avoiding", "following"):
            return -1.0
        pose = self.base.pose
        return math.hypot(target[0] - pose.x, target[1] - pose.y)

    def _on_assignment(self, message: Message) -> None:
        assert isinstance(message, Assignment)
        if message.robot != self.robot_id or self._t0 is not None:
            return
        self.agenda = list(message.tasks)
        self.team = tuple(r for r in message.team if r != self.robot_id)
        self._assigner_id = message.sender
        self._t0 = self._now
        self.timeline.event(L.ASSIGNMENT_RECEIVED, self._now, tasks=len(self.agenda))
        self.timeline.set_state(ACTIVITY, L.INIT, self._now)

    def _on_poses(self, messages: Sequence[Message]) -> None:
        """Mates' poses that reached the robot, in order (one, or a step's batch)."""
        self.team_view.hear_all(cast("Sequence[PoseMsg]", messages), self._now, self.robot_id)

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

    def drop_goal(self) -> None:
        """Its goal was reassigned: stop and choose again (LF's leader dissolves)."""
        self.base.cancel()
        self.goal = None
        self.trigger("nav_fail")

    def on_command(self, command: OperatorCommand) -> None:
        """Act on the part of an operator's command that concerns this robot: a task taken
        away leaves the agenda (a robot driving to it chooses again), one given, added or
        to do again joins it (an idle robot plans again); pause stops it, resume goes on."""
        kind, task, me = command.command, command.task, self.robot_id
        if me not in (command.robot, command.former) and kind is not CommandKind.CONFIRM:
            return
        self.timeline.event(L.OPERATOR_COMMAND, self._now, command=str(kind))
        if kind is CommandKind.REASSIGN and task is not None and command.former == me:
            self.agenda = [t for t in self.agenda if t.task_id != task.task_id]
        elif kind in (CommandKind.REASSIGN, CommandKind.ADD, CommandKind.REDO) and task:
            if kind is CommandKind.REDO and task.task_id in self.completed:
                self.completed.remove(task.task_id)  # done again, reported again
            if task not in self.agenda and task.task_id not in self.completed:
                self.agenda.append(task)
                self._agenda_reported = False
                self._new_tasks = True  # an idle robot plans again (now or once idle)
                if self.leaf() == "idle":
                    self._plan_new_tasks()
        elif kind is CommandKind.CONFIRM and task is not None:
            self.known_done.add(task.task_id)  # its dependants may start
        elif kind is CommandKind.PAUSE and not self.paused:
            self.paused = True
            self.base.cancel()
        elif kind is CommandKind.RESUME and self.paused:
            self.paused = False
            target = self.navigation_target()
            if target is not None:
                self.base.navigate_to(*target)

    def activity_of(self, state: str) -> str | None:
        """Timeline activity recorded while in ``state`` (full state name)."""
        return _ACTIVITY_OF_STATE.get(self.STATE_TABLE[state].leaf)

    def _after_state_change(self) -> None:
        self._state_since = self._now
        if self.queue is not None and self.leaf() != "avoiding":
            self.queue.waiting = None  # a wait at a passage is over, however it ended
        activity = self.activity_of(self.state)
        if self.leaf() == "navigating" and not self._moved_once:
            activity = L.INIT  # assignment received, not yet moving
        if activity is not None:
            self.timeline.set_state(ACTIVITY, activity, self._now)
        # Idle with tasks left (back from making way in a behaviour that idles then) is
        # not the end of the agenda.
        if self.leaf() == "idle" and not self._agenda_reported and not self.agenda:
            self._agenda_reported = True
            self.timeline.event(L.AGENDA_COMPLETE, self._now)
            self.send_status("", TaskState.AGENDA_COMPLETE)
        self.on_state_change()

    def on_state_change(self) -> None:
        """Hook after every state change (LF records roles here)."""


TaskExecutor.STATE_TABLE = build_table(
    TaskExecutor, TaskExecutor.states, TaskExecutor.PASSIVE_STATES
)
