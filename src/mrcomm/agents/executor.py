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
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any, ClassVar

from mrcomm.agents import agenda
from mrcomm.agents.avoidance import Avoidance
from mrcomm.agents.behaviour import AgentContext, BehaviourView
from mrcomm.agents.collision import Mate
from mrcomm.agents.executor_params import ExecutorParams
from mrcomm.agents.making_way import aside_goals, in_way
from mrcomm.agents.occupied_goal import OccupiedGoal
from mrcomm.agents.passage_queue import PassageQueue
from mrcomm.agents.runtime import ExecutorRuntime
from mrcomm.messaging.messages import (
    CommandKind,
    OperatorCommand,
    TaskState,
)
from mrcomm.metrics import labels as L
from mrcomm.metrics.timeline import ACTIVITY
from mrcomm.ports import NavStatus
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


class TaskExecutor(ExecutorRuntime):
    """NB: the behaviour every other builds on, on the runtime every behaviour rides on
    (:class:`~mrcomm.agents.runtime.ExecutorRuntime`)."""

    states: ClassVar[list[Any]] = NB_STATES
    transitions: ClassVar[list[dict[str, Any]]] = NB_TRANSITIONS
    initial = "unassigned"
    #: Leaf states stepped by no handler (``unassigned``: the step chooses a task).
    PASSIVE_STATES: ClassVar[frozenset[str]] = frozenset({"unassigned"})

    def __init__(self, context: AgentContext, params: ExecutorParams) -> None:
        """NB's parts besides the runtime's: collision avoidance with right of way,
        queueing at one-lane passages, making way, the occupied-goal breaker."""
        super().__init__(context, params)
        p = self.params
        self.avoidance = Avoidance(self.robot_id, p, context.tie_break_rank)
        self.queue: PassageQueue | None = None
        passages = context.passages
        if passages is not None and len(passages):
            self.queue = PassageQueue(
                passages, p.queue_distance, p.queue_timeout, p.collision.moving_speed,
                context.tie_break_rank, self.robot_id,
            )  # fmt: skip
        self._clearing_goals: list[tuple[float, float]] = []
        self._occupied = OccupiedGoal(p.occupied_goal)
        self._execute_until = 0.0
        self._moved_once = False  # the robot has started to move
        self._state_since = 0.0  # when the machine entered its state
        self._agenda_reported = False  # its agenda's end was reported

    @property
    def done(self) -> bool:
        """Nothing left to do: agenda complete and nothing left to communicate."""
        return self._t0 is not None and not self.agenda and self.leaf() == "idle"

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
        near: Iterable[Mate]
        if self.avoidance.on_receipt:
            # Every mate, near or far: a pose judged when it arrived is not judged again
            # when the robot comes near where it was (detect marks each one judged).
            near = self.known_mates().values()
        else:
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
    def _goal_distance(self) -> float:
        target = self.navigation_target()
        if target is None or self.leaf() not in ("navigating", "avoiding", "following"):
            return -1.0
        pose = self.base.pose
        return math.hypot(target[0] - pose.x, target[1] - pose.y)

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


if TYPE_CHECKING:  # mypy holds NB (and so every behaviour) to the contract it documents

    def _reads_as_documented(executor: TaskExecutor) -> BehaviourView:
        return executor
