"""serried — serried ranks: the team moves in close groups, each to its members' tasks in
turn.

The team splits into groups of ``group_size`` robots by the team-wide random order (the
order every robot draws from the mission's seed: the first ``group_size`` robots are
one group, the next the second, …), so every robot knows the groups without a message.
With ``group_size`` 0, or at least the team's size, the whole team is one group (the
original serried; S1's three robots are one group either way). In a group one robot
leads at a time: the robot of lowest rank among the group's members this robot believes
still have tasks. The leader drives to its own tasks one after another (the closest
available first, as NB), the others follow it; when its agenda is done it says so (its
AGENDA_COMPLETE status goes with AON, as its task statuses do, so every member learns
it) and the next robot of the group leads it to its tasks. A group whose agendas are all
done stays where it is, making way. The mission ends when every robot's agenda is done.
(One group of ten robots on S2 crawled from task to task: 1 of 20 tasks in 1,800 s.)

* A follower drives towards the leader's last known position and stops within
  ``follow_distance`` of it; it re-targets when the leader has moved more than 0.5 m
  (at most every ``refresh_period``).
* The leader holds (``holding``) while the link to any mate heard in the last
  ``lost_timeout`` is in warning, so the group keeps every robot within the warning
  threshold of the leader, and drives on when none is — or after ``hold_timeout``, and
  then drives that long before holding again (a signal-strength threshold may warn
  through a wall however close the follower gets; then a hold could never end).
* Robots may briefly disagree on who leads (the leader's AGENDA_COMPLETE has not reached
  everyone yet): a robot then follows the robot it believes leads, which follows the
  next; the two meet and AON settles it. No cycle outlives that: a robot follows only one
  it believes unfinished and of lower rank, or, when finished itself, the next one.

Near collisions are judged while leading (as NB), not while following: followers drive
into the leader's wake on purpose, and the base keeps them clear of it. A follower that
has stopped in the way of its leader, or of a robot of another group, with a goal steps
aside (NB's making way), then follows again.
"""

from __future__ import annotations

import math
from typing import Any

from mrcomm.agents.aon_statuses import AonStatuses
from mrcomm.agents.behaviour import AgentContext
from mrcomm.agents.executor import NB_STATES, NB_TRANSITIONS, TaskExecutor
from mrcomm.agents.executor_params import ExecutorParams
from mrcomm.messaging.messages import TaskState, TaskStatus
from mrcomm.metrics import labels as L
from mrcomm.ports import NavStatus
from mrcomm.specs import parameter


class SerriedParams(ExecutorParams):
    follow_distance: float = parameter(1.5, "a follower stops this close to the leader", "m", gt=0)
    refresh_period: float = parameter(
        1.0, "a follower re-targets the leader at most this often", "s", gt=0
    )
    lost_timeout: float = parameter(30.0, "a mate silent this long is not held for", "s", gt=0)
    hold_timeout: float = parameter(20.0, "the leader drives on after holding this long", "s", gt=0)
    aon_lease: float | None = parameter(
        60.0,
        "AON: a member silent this long is reported as left out of pending messages; "
        "null waits forever",
        "s",
        gt=0,
    )
    group_size: int = parameter(
        3,
        "robots per group: the team splits by its random order into groups of this many, "
        "each moving as one to its members' tasks (0: the whole team is one group)",
        ge=0,
    )


SERRIED_STATES = [*NB_STATES, "following", "holding"]
_TAKES_LEAD = ["following"]
SERRIED_TRANSITIONS: list[dict[str, Any]] = [
    *NB_TRANSITIONS,
    {
        "trigger": "follow",
        "source": ["unassigned", "idle", "waiting", "executing", "retrying"],
        "dest": "following",
    },
    # Idle with tasks left (back from making way) may take its turn at once.
    {"trigger": "go", "source": [*_TAKES_LEAD, "idle"], "dest": "navigating"},
    {"trigger": "wait", "source": [*_TAKES_LEAD, "idle"], "dest": "waiting"},
    {"trigger": "finish_agenda", "source": _TAKES_LEAD, "dest": "idle"},
    {"trigger": "make_way", "source": "following", "dest": "clearing"},
    {"trigger": "hold", "source": "navigating", "dest": "holding"},
    {"trigger": "release", "source": "holding", "dest": "navigating"},
]
_ACTIVITY = {"following": L.MOVING, "holding": L.LEADER_DISCONNECT}


class SerriedStatuses(AonStatuses):
    """Serried's statuses part: the end of each agenda goes with AON too."""

    AON_STATES = frozenset({TaskState.SUCCESS, TaskState.AGENDA_COMPLETE})


class SerriedExecutor(TaskExecutor):
    """The team as one group, led by each robot in turn (see the module docstring)."""

    states = SERRIED_STATES
    transitions = SERRIED_TRANSITIONS
    Params = SerriedParams
    Statuses = SerriedStatuses

    def __init__(self, context: AgentContext, params: ExecutorParams) -> None:
        #: Robots whose agenda is done, as this robot knows.
        self.finished: set[str] = set()
        self._follow_target: tuple[float, float] | None = None
        self._next_refresh = 0.0
        self._no_hold_until = 0.0
        self._group: tuple[tuple[str, ...], tuple[str, ...]] | None = None  # (team, group)
        super().__init__(context, params)

    @property
    def serried(self) -> SerriedParams:
        assert isinstance(self.params, SerriedParams)
        return self.params

    @property
    def group(self) -> tuple[str, ...]:
        """The other members of this robot's group (see the module docstring)."""
        team = tuple(self.team)
        if self._group is None or self._group[0] != team:
            order = sorted([self.robot_id, *team], key=self._rank)
            size = self.serried.group_size or len(order)
            first = order.index(self.robot_id) // size * size
            members = tuple(m for m in order[first : first + size] if m != self.robot_id)
            self._group = (team, members)
        return self._group[1]

    @property
    def done(self) -> bool:
        """Nobody left to lead its group (every member's agenda done as far as this
        robot knows, or the member out of range: :meth:`group_leader`), it idles, and its
        statuses have reached everyone."""
        return (
            self.leaf() == "idle"
            and not self.agenda
            and self.group_leader() is None
            and self.aon_statuses.settled()
        )

    def activity_of(self, state: str) -> str | None:
        return _ACTIVITY.get(state) or super().activity_of(state)

    def on_team_status(self, status: TaskStatus) -> None:
        super().on_team_status(status)
        if status.state is TaskState.AGENDA_COMPLETE:
            self.finished.add(status.robot)

    # -- who leads ---------------------------------------------------------------------
    def group_leader(self) -> str | None:
        """The robot of lowest rank among the group's members believed to have tasks
        left (None: the whole group is done)."""
        mine = [self.robot_id] if self.agenda else []
        left = [*mine, *(m for m in self.group if m not in self.finished and self._within(m))]
        return min(left, key=self._rank) if left else None

    def _within(self, mate: str) -> bool:
        """Whether ``mate`` may lead this robot: heard within ``lost_timeout``, or never
        heard yet in the mission's first ``lost_timeout``. A member out of range for
        longer is passed over (the group goes on without it, and takes it back once it
        is heard again): a follower waiting for a leader it never hears waited for ever
        (S3: groups drawn by the random order may start far apart)."""
        timeout = self.serried.lost_timeout
        age = self.team_view.age(mate, self._now)
        if age == math.inf:
            return self._t0 is None or self._now - self._t0 < timeout
        return age <= timeout

    def current_role(self) -> str:
        if self._t0 is None:
            return ""
        return L.ROLE_LEADER if self.group_leader() == self.robot_id else L.ROLE_FOLLOWER

    def current_leader(self) -> str:
        leader = self.group_leader()
        return leader if leader not in (None, self.robot_id) else ""

    def _select_next(self) -> None:
        leader = self.group_leader()
        own_turn = leader is None or leader == self.robot_id
        # Its agenda just done: NB goes idle, which reports it (with AON); idle follows.
        reports_first = not self.agenda and self.leaf() != "idle"
        if own_turn or reports_first:
            super()._select_next()
            return
        if self.leaf() != "following":
            self._follow_target = None
            self._next_refresh = self._now
            self.trigger("follow")

    # -- leading ---------------------------------------------------------------------
    def _mate_out(self) -> bool:
        """A member of the group heard lately whose link (from its last pose) is in
        warning."""
        pose = self.base.pose
        for mate in self.group:
            known = self.mates.get(mate)
            if known is None or self.team_view.age(mate, self._now) > self.serried.lost_timeout:
                continue
            if self.mate_link_warns(mate, pose, known.x, known.y):
                return True
        return False

    def _step_navigating(self) -> None:
        may_hold = self._now >= self._no_hold_until
        if may_hold and self.base.status is NavStatus.ACTIVE and self._mate_out():
            self.base.cancel()
            self.trigger("hold")
            return
        super()._step_navigating()

    def _step_holding(self) -> None:
        # A hold no follower can end (it cannot get closer) gives way after hold_timeout.
        timed_out = self._now - self._state_since >= self.serried.hold_timeout
        if timed_out:
            # ... and drives as long before holding again, so the group moves on.
            self._no_hold_until = self._now + self.serried.hold_timeout
        if timed_out or not self._mate_out():
            assert self.goal is not None
            self.base.navigate_to(self.goal.x, self.goal.y)
            self.trigger("release")

    def _step_idle(self) -> None:
        leader = self.group_leader()
        if self.agenda or (leader is not None and leader != self.robot_id):
            self._select_next()  # its turn, or follow the group to the others' tasks
            return
        super()._step_idle()  # everyone done: stay, making way when needed

    # -- following ---------------------------------------------------------------------
    def navigation_target(self) -> tuple[float, float] | None:
        if self.leaf() == "following":
            return self._follow_target
        return super().navigation_target()

    def _step_following(self) -> None:
        leader = self.group_leader()
        if leader is None or leader == self.robot_id:
            super()._select_next()  # its turn to lead (or everyone is done)
            return
        known = self.mates.get(leader)
        if known is None:
            return
        pose = self.base.pose
        if self.base.status is not NavStatus.ACTIVE:
            # Stopped in the way of a mate with a goal — its leader, or a robot of
            # another group: make room (NB's rule). Groups that met at one spot jammed
            # there, each group's followers closing in on the spot the others drove to.
            # (Not for its own group's followers: the group would come apart.)
            group = self.group
            strangers = (m for r, m in self.mates.items() if r not in group)
            for mate in (known, *strangers):
                if self.in_way_of(mate, pose):
                    self.step_aside(mate)
                    return
        close = math.hypot(known.x - pose.x, known.y - pose.y) <= self.serried.follow_distance
        # Close is not enough when its own link to the leader warns (a wall between
        # them, with a signal-strength threshold): it keeps closing in, or the leader
        # would hold for it for ever.
        if close and not self.mate_link_warns(leader, pose, known.x, known.y):
            if self.base.status is NavStatus.ACTIVE:
                self.base.cancel()
            return
        target = (known.x, known.y)
        moved = self._follow_target is None or math.dist(target, self._follow_target) > 0.5
        stalled = self.base.status is not NavStatus.ACTIVE
        if (moved or stalled) and self._now >= self._next_refresh:
            self._follow_target = target
            self._next_refresh = self._now + self.serried.refresh_period
            self.base.navigate_to(*target)
