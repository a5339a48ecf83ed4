"""rps — rendezvous point: robots disperse to their tasks and regroup at a meeting
point now and then to share what they have learnt.

Each robot works as NB does (its closest available task next; statuses published once,
without acknowledgement) and goes to the meeting point:

* after every ``every_tasks`` tasks it completed, or when ``every_seconds`` have passed
  since it last left the meeting point while it drives to a task (the task stays in its
  agenda); either rule can be switched off with 0;
* once more when its agenda is done (the final rendezvous), before it idles there.

At the meeting point (state ``gathering``) it publishes again, every ``reshare_period``,
every task status it knows of — its own and those it heard from its mates (with its own
name as sender and the robot that did the task as the status's ``robot``, so the task
assigner counts each task once whoever passes it on) — and waits until every team mate
has been heard within ``gather_radius`` of the point in the last second, or
``gather_timeout`` has passed, and it has published its statuses ``min_reshares``
times (without acknowledgements, repetition is what gets them through loss: at SPL 50
six copies all fail 1.6 % of the time). Then it disperses again. A robot that
finished its agenda stays at the point, so later arrivals find it there: each mate that
comes within the gather radius gets its statuses ``min_reshares`` times, every
``reshare_period`` (a mate that leaves and comes back gets them again). Without that, a
robot that finished early and met nobody took its statuses with it: the task assigner,
hosted on a robot that came later, never heard them.

The meeting point, by ``meeting``:

* ``start`` (default): the centroid of where the team started — this robot's start and
  the first position heard from each mate (robots are still at their starts when their
  first poses go out, so every robot computes the same point to within centimetres);
* ``fixed``: (``meeting_x``, ``meeting_y``) in the map frame.

The base snaps the point to free space. While driving to the point the robot does not
judge near collisions (its base still keeps clear of mates); it stops once within half
the gather radius, so robots already there need not make way.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, Literal

import msgspec

from mrcomm.agents.behaviour import AgentContext
from mrcomm.agents.executor import NB_STATES, NB_TRANSITIONS, TaskExecutor
from mrcomm.agents.executor_params import ExecutorParams
from mrcomm.messaging.messages import (
    TOPIC_TASK_STATUS,
    Assignment,
    Message,
    PoseMsg,
    TaskState,
    TaskStatus,
)
from mrcomm.messaging.topics import TOPIC_POSE
from mrcomm.metrics import labels as L
from mrcomm.ports import BatchHandler, NavStatus
from mrcomm.specs import parameter


class RpsParams(ExecutorParams):
    every_tasks: int = parameter(
        2, "go to the meeting point after this many completed tasks (0: never)", ge=0
    )
    every_seconds: float = parameter(
        0.0,
        "... or when this long has passed since the last rendezvous, while driving to a "
        "task (0: never)",
        "s",
        ge=0,
    )
    meeting: Literal["start", "fixed"] = parameter(
        "start", "the meeting point: the team's start centroid, or meeting_x, meeting_y"
    )
    meeting_x: float = parameter(0.0, "x of a fixed meeting point (map frame)", "m")
    meeting_y: float = parameter(0.0, "y of a fixed meeting point (map frame)", "m")
    gather_radius: float = parameter(
        3.0, "a mate this close to the meeting point is there", "m", gt=0
    )
    gather_timeout: float = parameter(
        30.0, "a robot waits at most this long at the meeting point", "s", gt=0
    )
    reshare_period: float = parameter(
        5.0, "statuses are published again this often at the meeting point", "s", gt=0
    )
    min_reshares: int = parameter(
        6,
        "a robot leaves the meeting point only after publishing its statuses this many "
        "times (without acknowledgements, repetition is what gets them through loss)",
        ge=1,
    )


RPS_STATES = [*NB_STATES, "meeting", "gathering"]
RPS_TRANSITIONS: list[dict[str, Any]] = [
    *NB_TRANSITIONS,
    {
        "trigger": "rendezvous",
        "source": ["navigating", "executing"],
        "dest": "meeting",
    },
    {"trigger": "gather", "source": "meeting", "dest": "gathering"},
    {"trigger": "go", "source": "gathering", "dest": "navigating"},
    {"trigger": "wait", "source": "gathering", "dest": "waiting"},
    {"trigger": "finish_agenda", "source": "gathering", "dest": "idle"},
]
_ACTIVITY = {"meeting": L.MOVING, "gathering": L.RENDEZVOUS}


class RendezvousExecutor(TaskExecutor):
    """NB with periodic rendezvous (see the module docstring)."""

    states = RPS_STATES
    transitions = RPS_TRANSITIONS
    Params = RpsParams

    def __init__(self, context: AgentContext, params: ExecutorParams) -> None:
        #: Where each mate was first heard, and this robot's own start.
        self._first_heard: dict[str, tuple[float, float]] = {}
        self._start: tuple[float, float] | None = None
        self._point: tuple[float, float] | None = None
        #: (task, robot) of every completion this robot knows of.
        self._statuses: set[tuple[str, str]] = set()
        self._since_rendezvous = 0
        self._left_point = 0.0
        self._final_done = False
        self._next_reshare = 0.0
        self._reshares = 0
        #: Idle at the point: how often each mate now there has been given the statuses.
        self._shared_with: dict[str, int] = {}
        super().__init__(context, params)
        # Where each mate was first heard: more than the team view keeps (its latest).
        self.bus.subscribe(TOPIC_POSE, BatchHandler(self._note_first_heard))

    @property
    def rps(self) -> RpsParams:
        assert isinstance(self.params, RpsParams)
        return self.params

    def activity_of(self, state: str) -> str | None:
        return _ACTIVITY.get(state) or super().activity_of(state)

    # -- what it learns ------------------------------------------------------------------
    def _on_assignment(self, message: Message) -> None:
        first = self._t0 is None
        super()._on_assignment(message)
        if first and self._t0 is not None:
            assert isinstance(message, Assignment)
            pose = self.base.pose
            self._start = (pose.x, pose.y)
            self._left_point = self._now

    def _note_first_heard(self, messages: Sequence[Message]) -> None:
        for message in messages:
            assert isinstance(message, PoseMsg)
            if message.sender != self.robot_id:
                self._first_heard.setdefault(message.sender, (message.x, message.y))

    def on_team_status(self, status: TaskStatus) -> None:
        super().on_team_status(status)
        if status.state is TaskState.SUCCESS:
            self._statuses.add((status.task_id, status.robot))

    def meeting_point(self) -> tuple[float, float]:
        """The meeting point (see the module docstring); fixed at its first use."""
        if self._point is None:
            params = self.rps
            if params.meeting == "fixed":
                self._point = (params.meeting_x, params.meeting_y)
            else:
                points = [p for p in (self._start,) if p is not None]
                points += [self._first_heard[m] for m in self.team if m in self._first_heard]
                xs, ys = zip(*points, strict=True) if points else ((0.0,), (0.0,))
                self._point = (sum(xs) / len(xs), sum(ys) / len(ys))
        return self._point

    # -- when to meet ----------------------------------------------------------------
    def before_state_step(self) -> None:
        every = self.rps.every_seconds
        if every > 0 and self.leaf() == "navigating" and self._now - self._left_point >= every:
            self.base.cancel()  # the task stays in the agenda
            self.goal = None
            self._go_to_point()

    def after_task_completed(self) -> None:
        self._statuses.add((self.completed[-1], self.robot_id))
        self._since_rendezvous += 1
        every = self.rps.every_tasks
        if not self.agenda and not self._final_done:
            self._final_done = True
            self._go_to_point()
        elif every and self._since_rendezvous >= every:
            self._go_to_point()
        else:
            super().after_task_completed()

    def _go_to_point(self) -> None:
        self._since_rendezvous = 0
        self.timeline.event(L.RENDEZVOUS_START, self._now)
        self.base.navigate_to(*self.meeting_point())
        self.trigger("rendezvous")

    def navigation_target(self) -> tuple[float, float] | None:
        if self.leaf() in ("meeting", "gathering"):
            return self.meeting_point()
        return super().navigation_target()

    # -- at the meeting point ------------------------------------------------------------
    def _step_meeting(self) -> None:
        point = self.meeting_point()
        pose = self.base.pose
        close = math.hypot(point[0] - pose.x, point[1] - pose.y) <= self.rps.gather_radius / 2
        status = self.base.status
        if close or status in (NavStatus.SUCCEEDED, NavStatus.ABORTED):
            self.base.cancel()
            self._next_reshare = self._now
            self._reshares = 0
            self.trigger("gather")

    def _step_gathering(self) -> None:
        if self._now >= self._next_reshare:
            self._reshare()
            self._reshares += 1
            self._next_reshare = self._now + self.rps.reshare_period
        waited = self._now - self._state_since
        enough = self._reshares >= self.rps.min_reshares
        if enough and (self._team_here() or waited >= self.rps.gather_timeout):
            self.timeline.event(L.RENDEZVOUS_END, self._now, waited=round(waited, 3))
            self._left_point = self._now
            self._select_next()

    def _step_idle(self) -> None:
        super()._step_idle()
        if self.leaf() != "idle" or not self._final_done or self._now < self._next_reshare:
            return
        here = set(self._mates_at_point())
        # A mate that left forgets it was told: when it comes back it is told again.
        self._shared_with = {m: n for m, n in self._shared_with.items() if m in here}
        if any(self._shared_with.get(m, 0) < self.rps.min_reshares for m in here):
            self._reshare()
            for mate in here:
                self._shared_with[mate] = self._shared_with.get(mate, 0) + 1
        self._next_reshare = self._now + self.rps.reshare_period

    def _mates_at_point(self) -> list[str]:
        """The mates heard within the last second within the gather radius of the point."""
        point = self.meeting_point()
        radius = self.rps.gather_radius
        found = []
        for mate in self.team:
            known = self.mates.get(mate)
            if known is None or self.team_view.age(mate, self._now) > 1.0:
                continue
            if math.hypot(known.x - point[0], known.y - point[1]) <= radius:
                found.append(mate)
        return found

    def _team_here(self) -> bool:
        """Every mate heard within the last second within the gather radius."""
        return len(self._mates_at_point()) == len(self.team)

    def _reshare(self) -> None:
        """Publish every completion this robot knows of again (the assigner counts a
        task once)."""
        for task_id, robot in sorted(self._statuses):
            message = self.status_message(task_id, TaskState.SUCCESS)
            self.bus.publish(TOPIC_TASK_STATUS, msgspec.structs.replace(message, robot=robot))
        self.timeline.event(L.STATUSES_RESHARED, self._now, count=len(self._statuses))
