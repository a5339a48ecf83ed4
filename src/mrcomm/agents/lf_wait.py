"""lf-wait — Leader-Follower in which the leader waits for followers doing their own
tasks near the group.

In LF a follower does nothing of its own agenda until the roles dissolve, even when one
of its tasks lies a few metres away. In lf-wait:

* A follower (following or waiting at the leader) whose own available task is within
  ``detour_distance`` of it — and within the same distance of the leader's last known
  position, so the task is near the *group*, not just near a straggler — leaves to do
  it (``follower_detouring``), executes it (``follower_executing``), reports it with AON
  and rejoins (``follower_following``). While it is away its poses carry the role
  ``detouring`` (with the leader it follows): that is its request to wait.
* A leader that hears one of its followers detouring stops and waits
  (``leader_waiting``) until that follower's pose says it follows again, or
  ``detour_timeout`` after the detour was first heard (a request whose end was lost, or
  a detour that fails, cannot hold the group for ever). Its holds for followers in
  warning (LF's leader disconnect) still apply, and come first.
* A follower gives up a detour that takes longer than ``detour_timeout`` or whose
  navigation fails, and rejoins; the task stays in its agenda for later (not tried
  again on a detour while it keeps this role).

Everything else is LF (role assignment, holds, regrouping, AON).
"""

from __future__ import annotations

import copy
import math
from typing import Any

from mrcomm.agents import agenda
from mrcomm.agents.behaviour import AgentContext
from mrcomm.agents.executor_params import ExecutorParams
from mrcomm.agents.lf import LeaderFollowerExecutor
from mrcomm.agents.lf_machine import ACTIVITY_OF_FULL_STATE, LF_STATES, LF_TRANSITIONS, LfParams
from mrcomm.agents.machine_table import build_table
from mrcomm.messaging.messages import TaskSpec
from mrcomm.metrics import labels as L
from mrcomm.ports import NavStatus
from mrcomm.specs import parameter


class LfWaitParams(LfParams):
    detour_distance: float = parameter(
        3.0,
        "a follower does its own task this close to it and to its leader (straight line)",
        "m",
        gt=0,
    )
    detour_timeout: float = parameter(
        60.0, "a detour (and the leader's wait for it) ends after at most this long", "s", gt=0
    )


def _with_detours(states: list[Any]) -> list[Any]:
    """LF's states with the follower's detour and the leader's wait added."""
    out = copy.deepcopy(states)
    for state in out:
        if not isinstance(state, dict):
            continue
        if state["name"] == "follower":
            state["children"] += ["detouring", "executing"]
            state["transitions"] += [
                {"trigger": "detour", "source": ["following", "waiting"], "dest": "detouring"},
                {"trigger": "arrive", "source": "detouring", "dest": "executing"},
                {"trigger": "conflict", "source": "detouring", "dest": "avoiding"},
                {"trigger": "rejoin", "source": ["detouring", "executing"], "dest": "following"},
            ]
        elif state["name"] == "leader":
            state["children"] += ["waiting"]
            state["transitions"] += [
                {"trigger": "wait_for", "source": "navigating", "dest": "waiting"},
                {"trigger": "release", "source": "waiting", "dest": "navigating"},
            ]
    return out


LF_WAIT_STATES = _with_detours(LF_STATES)
ACTIVITY_OF_DETOUR_STATE = {
    **ACTIVITY_OF_FULL_STATE,
    "follower_detouring": L.MOVING,
    "follower_executing": L.TASK,
    "leader_waiting": L.LEADER_DETOUR_WAIT,
}


class LfWaitExecutor(LeaderFollowerExecutor):
    """LF whose followers do their own tasks near the group (see the module docstring)."""

    states = LF_WAIT_STATES
    transitions = LF_TRANSITIONS
    Params = LfWaitParams

    def __init__(self, context: AgentContext, params: ExecutorParams) -> None:
        #: mate -> when this leader first heard it detouring (the current detour).
        self._detours_heard: dict[str, float] = {}
        self._detour_since = 0.0
        #: (round, task) of detours given up: not tried again while in that round's role.
        self._given_up: set[tuple[int, str]] = set()
        super().__init__(context, params)

    @property
    def lfw(self) -> LfWaitParams:
        assert isinstance(self.params, LfWaitParams)
        return self.params

    def activity_of(self, state: str) -> str | None:
        return ACTIVITY_OF_DETOUR_STATE.get(state) or super().activity_of(state)

    def current_role(self) -> str:
        if self._on_detour():
            return L.ROLE_DETOURING
        return super().current_role()

    def _on_detour(self) -> bool:
        return self._in("follower") and self.leaf() in ("detouring", "executing")

    def navigation_target(self) -> tuple[float, float] | None:
        if self._on_detour() and self.goal is not None:
            return self.goal.x, self.goal.y
        return super().navigation_target()

    # -- follower ------------------------------------------------------------------------
    def _nearby_task(self) -> TaskSpec | None:
        """An available task of its own within the detour distance of it and of its
        leader's last known position."""
        leader = self._leader_position()
        if leader is None or not self.agenda:
            return None
        pose = self.base.pose
        reach = self.lfw.detour_distance
        elapsed = self._now - (self._t0 or 0.0)
        near = [
            t
            for t in agenda.available(self.agenda, elapsed, self.known_done)
            if (self.role_round.number, t.task_id) not in self._given_up
            and math.hypot(t.x - pose.x, t.y - pose.y) <= reach
            and math.hypot(t.x - leader[0], t.y - leader[1]) <= reach
        ]
        return agenda.closest(near, pose) if near else None

    def _start_detour(self) -> bool:
        task = self._nearby_task()
        if task is None:
            return False
        self.goal = task
        self._detour_since = self._now
        self.timeline.event(L.DETOUR, self._now, task_id=task.task_id, leader=self.leader)
        self.base.navigate_to(task.x, task.y)
        self.trigger("detour")
        return True

    def _step_follower_following(self) -> None:
        if self._in("follower") and not self._leader_gone() and self._start_detour():
            return
        super()._step_follower_following()

    def _step_follower_waiting(self) -> None:
        if self._in("follower") and not self._leader_gone() and self._start_detour():
            return
        super()._step_follower_waiting()

    def _step_follower_detouring(self) -> None:
        if self.before_follower_step():
            return
        if self._now - self._detour_since > self.lfw.detour_timeout:
            self._end_detour("timed out")
            return
        if self.base.status is NavStatus.ABORTED:
            self._end_detour("navigation failed")
            return
        self._step_navigating()  # arrive -> executing; a mate in the way -> avoiding

    def _step_follower_executing(self) -> None:
        if self.before_follower_step():
            return
        self._step_executing()

    def after_task_completed(self) -> None:
        if self._on_detour():
            self._end_detour("completed")
            return
        super().after_task_completed()

    def _end_detour(self, how: str) -> None:
        self.timeline.event(L.DETOUR_ENDED, self._now, how=how)
        if how != "completed" and self.goal is not None:
            self._given_up.add((self.role_round.number, self.goal.task_id))
        self.base.cancel()
        self.goal = None
        self._follow_target = None
        self._next_refresh = self._now
        self.trigger("rejoin")

    # -- leader --------------------------------------------------------------------------
    def _detouring_followers(self) -> list[str]:
        """Its followers whose latest pose says they are doing a task of their own,
        within the detour time-out of when that was first heard."""
        out = []
        for mate in self.team:
            detouring = (
                self.team_view.role(mate) == L.ROLE_DETOURING
                and self.team_view.leader(mate) == self.robot_id
            )
            if not detouring:
                self._detours_heard.pop(mate, None)
                continue
            since = self._detours_heard.setdefault(mate, self._now)
            if self._now - since <= self.lfw.detour_timeout:
                out.append(mate)
        return out

    def _step_leader_navigating(self) -> None:
        if self._detouring_followers() and not self._followers_out():
            self.base.cancel()
            self.trigger("wait_for")
            return
        super()._step_leader_navigating()

    def _step_leader_waiting(self) -> None:
        # A follower out of the connection area comes first: navigating holds for it
        # at once (LF's leader disconnect).
        if self._followers_out() or not self._detouring_followers():
            assert self.goal is not None
            self.base.navigate_to(self.goal.x, self.goal.y)
            self.trigger("release")

    def _follows_me(self, mate: str) -> bool:
        if self.team_view.role(mate) == L.ROLE_DETOURING:
            return self.team_view.leader(mate) == self.robot_id
        return super()._follows_me(mate)


LfWaitExecutor.STATE_TABLE = build_table(
    LfWaitExecutor, LfWaitExecutor.states, LfWaitExecutor.PASSIVE_STATES
)
