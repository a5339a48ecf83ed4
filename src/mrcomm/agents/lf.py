"""LF — the communication-aware Leader-Follower behaviour, enclosing NB.

A hierarchical state machine: ``na`` is NB plus a network trigger; ``leader`` and
``follower`` are sub-machines; ``assigning`` collects utilities and roles;
``regrouping`` drives back to the team's last known position when nobody answers;
``reporting`` brings the task assigner a completion it missed.

* Trigger: an NA robot whose link to a team mate (judged by its link sensor from the
  mate's last known pose) crosses the warning threshold stops, cancels its goal,
  publishes DISCONNECT_ROLE and opens a new role-assignment *round*. Robots that hear a
  newer round join it; an idle robot joins with utility 0 (so it follows) but never
  opens one (in groups it joins none: it stays where it is).
* Role assignment: every member publishes its utility at 4 Hz until it has every
  member's; the highest utility leads (ties by the team-wide random order) — in a
  round of more than ``group_size`` members the best ``ceil(n/group_size)`` lead and
  the others follow the nearest (:mod:`mrcomm.agents.lf_groups`). Roles are then
  published the same way. A role message settles the round for whoever still
  collects, and a member already past the round answers late utilities with its role,
  so no exchange waits on another; a timeout decides with what was collected. In
  groups a robot at work in a group joins a newer round only from its own group
  (``lf_groups.joins``), and one whose round nobody answers leads itself, a group of one,
  where the original regroups.
* Leader: drives to its closest task and holds while any of *its* followers' links is
  in warning (leader disconnect time); its followers are the mates whose poses say
  they follow it (or that named it leader this round and have not spoken since). With
  ``hold_prediction`` it judges each follower where it should be by now
  (:mod:`mrcomm.agents.lf_route`). With ``hold_grace`` it holds only once a follower
  has been in warning that long, so the group may stretch to the communication limit
  and past it (a robot out of range regroups). On completion it reports with AON and
  dissolves the roles.
* Follower: drives to the leader's last known position (moved on for its age with
  ``mate_extrapolation``), refreshing the goal as leader poses arrive (more often when
  far), and waits there (in groups also where it is while the leader comes its way:
  ``await_radius``); it returns to NA when the leader's completion reaches it.
* Task statuses go with AON (acknowledged all-or-nothing), to every robot and the
  assigner. With ``report_back`` (on in teams larger than a group) a robot with
  nothing left to do whose completion the assigner missed goes to find it
  (:mod:`mrcomm.agents.report_tour`).
"""

from __future__ import annotations

import math
from functools import partial
from typing import Any, cast

from transitions.extensions import HierarchicalMachine

from mrcomm.agents import agenda
from mrcomm.agents.aon_statuses import AonStatuses
from mrcomm.agents.behaviour import AgentContext, require_params
from mrcomm.agents.collision import Mate
from mrcomm.agents.executor import TaskExecutor
from mrcomm.agents.executor_params import ExecutorParams
from mrcomm.agents.lf_groups import joins, nearest_leader, round_leaders
from mrcomm.agents.lf_hold import LeaderHold
from mrcomm.agents.lf_machine import (
    ACTIVITY_OF_FULL_STATE,
    LF_STATES,
    LF_TRANSITIONS,
    ROLE_OF_TOP_STATE,
    LfParams,
)
from mrcomm.agents.lf_route import direct_hop, leader_coming
from mrcomm.agents.link_chain import chain_links
from mrcomm.agents.role_round import RoleRound
from mrcomm.agents.utility import robot_inputs, utility_function
from mrcomm.messaging.messages import (
    TOPIC_ROLE,
    TOPIC_UTILITY,
    Message,
    RoleMsg,
    TaskState,
    TaskStatus,
    UtilityMsg,
)
from mrcomm.metrics import labels as L
from mrcomm.metrics.timeline import ROLE
from mrcomm.ports import NavStatus
from mrcomm.world.geometry import Pose

NA_IDLE = "na_idle"  # transitions' name of NA's idle state
HOME_REACH = 1.0  # m: the assigner's robot is home this close to its start


class LeaderFollowerExecutor(TaskExecutor):
    """LF task executor (see the module docstring)."""

    states = LF_STATES
    transitions = LF_TRANSITIONS
    initial = "na"
    machine_class = HierarchicalMachine
    Params = LfParams
    Statuses = AonStatuses  # statuses go with AON

    def __init__(self, context: AgentContext, params: ExecutorParams) -> None:
        require_params(type(self), params)  # before any use of them
        lf = cast(LfParams, params)
        self._utility = utility_function(lf.utility)
        self.leader: str | None = None
        self._just_completed = False
        self._follow_target: tuple[float, float] | None = None
        self._next_refresh = 0.0
        self._next_monitor = 0.0
        self._top_state = "na"
        self._state_since_role = 0.0
        self.hold = LeaderHold()
        self._no_hold_until = 0.0  # hold_timeout: no new hold before this time
        super().__init__(context, params)
        self.role_round = RoleRound(self.robot_id)
        self.bus.subscribe(TOPIC_UTILITY, self._on_utility)
        self.bus.subscribe(TOPIC_ROLE, self._on_role)

    @property
    def lf(self) -> LfParams:
        """This executor's parameters (``self.params``), typed as LF's."""
        assert isinstance(self.params, LfParams)
        return self.params

    # -- completion and communication ----------------------------------------------------
    @property
    def done(self) -> bool:
        """Agenda complete, back in NA (or the assigner's robot on its way home), and
        every status finished with AON (and, reporting back, the assigner has them)."""
        home = self.state == NA_IDLE or (
            self._in("reporting") and self.aon_statuses.hosts_assigner()
        )
        settled = self._t0 is not None and not self.agenda and home
        return (
            settled
            and self.aon_statuses.settled()
            and not (self._reports_back() and self.aon_statuses.unreported())
        )

    def on_team_status(self, status: TaskStatus) -> None:
        super().on_team_status(status)
        leader_done = status.state is TaskState.SUCCESS and status.robot == self.leader
        if leader_done and self._in("follower"):
            self._dissolve("leader completed its task")

    # -- every step ----------------------------------------------------------------------
    def before_state_step(self) -> None:
        # Idle robots join rounds but never open one (in groups, neither does one without
        # work left that makes way); links are judged at the pose rate.
        if (
            self._in("na")
            and self.leaf() not in ("unassigned", "idle")
            and (self.agenda or self.goal is not None or not self._in_groups())
            and self._now >= self._next_monitor
        ):
            self._next_monitor = self._now + self.params.pose_period
            self._monitor_links()
        elif self.state == NA_IDLE and self._reports_back() and self._to_report():
            self._follow_target = None  # the assigner missed a completion: report it
            self.aon_statuses.report_tour.reset()
            self.trigger("report")

    def _monitor_links(self) -> None:
        pose = self.base.pose
        for mate in self.team:
            known = self.mates.get(mate)
            if known is not None and self._link_warns(mate, pose, known.x, known.y):
                self.timeline.event(L.DISCONNECT_DETECTED, self._now, mate=mate)
                self.send_status("", TaskState.DISCONNECT_ROLE)
                self._open_round(self.role_round.next_number())
                return

    # -- role assignment -----------------------------------------------------------------
    def _open_round(self, round_no: int) -> None:
        self.base.cancel()
        self.role_round.open(round_no, self._my_utility(), self._now)
        self.leader = None
        if self.state == "assigning":
            self._state_since = self._now  # a newer round restarts the collection
        else:
            self.trigger("disconnect")

    def _my_utility(self) -> float:
        if not self.agenda:
            return 0.0
        return self._utility(robot_inputs(self.base, self.agenda, self.goal, self._just_completed))

    def _step_assigning(self) -> None:
        elapsed = self._now - self._state_since
        members = (self.robot_id, *self.team)
        if self.leader is None:
            if self._now >= self.role_round.next_announce:
                self._announce_utility()
            if self.role_round.has_every_score(members) or elapsed >= self.lf.assign_timeout:
                self._decide()
            return
        if self._now >= self.role_round.next_announce:
            self._announce_role()
        late = self._now - self.role_round.decided_at >= self.lf.roles_timeout
        if self.role_round.has_every_role() or late:
            self._take_role()

    def _decide(self, named: str | None = None) -> None:
        """Settle the round with the utilities collected (:mod:`mrcomm.agents.lf_groups`):
        lead, or follow the nearest leader; ``named`` is a leader a member's role message
        named, counted as one."""
        # Nobody answered: go back towards the team; in groups, where a lone robot's round
        # may go unanswered because every group near it is at work, do its own work.
        if self.role_round.alone and self.team and not self._in_groups():
            self.trigger("regroup")
            return
        leaders = round_leaders(self.role_round.scores, self._rank, self.lf.group_size)
        if named is not None and named not in leaders:
            leaders.append(named)
        if not leaders:
            self._dissolve("no robot has work left")
            return
        if self.robot_id in leaders:
            self._settle(self.robot_id)
            return
        positions = {mate: (known.x, known.y) for mate, known in self.mates.items()}
        pose = self.base.pose
        self._settle(nearest_leader(leaders, positions, (pose.x, pose.y), self._rank))

    def _settle(self, leader: str) -> None:
        self.leader = leader
        self.role_round.settle(leader, self._now)

    def _take_role(self) -> None:
        self._just_completed = False
        number = self.role_round.number
        self.timeline.event(L.ROLE_ASSIGNED, self._now, round=number, leader=self.leader)
        if self.leader == self.robot_id:
            self.trigger("become_leader")
            self._lead_next_task()
        else:
            self._follow_target = None
            self._next_refresh = self._now
            self.trigger("become_follower")

    def _announce(self, topic: str, kind: type[UtilityMsg | RoleMsg], **fields: Any) -> None:
        """Publish this robot's utility or role in the current round."""
        self._seq += 1
        message = kind(
            sender=self.robot_id, incarnation=self.incarnation, seq=self._seq,
            stamp=self._now, round=self.role_round.number, **fields,
        )  # fmt: skip
        self.bus.publish(topic, message)
        self.role_round.next_announce = self._now + self.lf.announce_period

    def _announce_utility(self) -> None:
        self._announce(TOPIC_UTILITY, UtilityMsg, utility=self.role_round.scores[self.robot_id])

    def _announce_role(self) -> None:
        assert self.leader is not None
        role = self.role_round.roles[self.robot_id]
        self._announce(TOPIC_ROLE, RoleMsg, role=role, leader=self.leader)

    def _in_round(self, message: UtilityMsg | RoleMsg) -> bool:
        """Whether a round message is of this robot's round, joining a newer one (idle:
        utility 0) unless it works in a group the sender is not in (lf_groups.joins)."""
        if self._t0 is None or message.sender == self.robot_id:
            return False
        if message.round > self.role_round.number:
            sender, top = message.sender, self.STATE_TABLE[self.state].top
            mine = partial(self._follows_me, sender)
            if self._in_groups() and not joins(
                top, sender, self.leader, self.team_view.leader(sender), mine,
                idle=self.state == NA_IDLE,
            ):  # fmt: skip
                self.role_round.pass_by(message.round)
                return False
            self._open_round(message.round)
        return message.round == self.role_round.number

    def _on_utility(self, message: Message) -> None:
        assert isinstance(message, UtilityMsg)
        if not self._in_round(message):
            return
        if self.state == "assigning":
            self.role_round.hear_utility(message.sender, message.utility)
        elif self.leader is not None:
            self._announce_role()  # it is still collecting: answer, never deadlock

    def _on_role(self, message: Message) -> None:
        assert isinstance(message, RoleMsg)
        if not self._in_round(message) or self.state != "assigning":
            return
        self.role_round.hear_role(message.sender, message.role, message.leader, self._now)
        if self.leader is None:  # decided by a member that had every score (or timed out)
            if len(self.role_round.scores) <= self.lf.group_size:
                self._settle(message.leader)  # one group: its leader is ours
            else:
                self._decide(named=message.leader)

    def _dissolve(self, reason: str) -> None:
        self.timeline.event(L.ROLES_DISSOLVED, self._now, reason=reason)
        self.leader = None
        self.base.cancel()
        self.trigger("dissolve")
        self._select_next()

    # -- leader --------------------------------------------------------------------------
    def _lead_next_task(self) -> None:
        elapsed = self._now - (self._t0 or 0.0)
        ready = agenda.available(self.agenda, elapsed, self.known_done)
        if not ready:
            self._dissolve("leader has no available task")
            return
        self.goal = agenda.closest(ready, self.base.pose)
        self.base.navigate_to(self.goal.x, self.goal.y)

    def _followers_out(self) -> bool:
        """Whether a follower holds this leader now (:mod:`mrcomm.agents.lf_hold`)."""
        return self.hold.followers_out(self)

    def _link_warns(self, mate: str, pose: Pose, x: float, y: float) -> bool:
        """Whether this robot's link to ``mate`` (at x, y) is in warning: the direct
        link, or with ``chain_hops`` > 1 the best chain through the mates' last known
        positions (:mod:`mrcomm.agents.link_chain`)."""
        if not self.mate_link_warns(mate, pose, x, y):
            return False
        if self.lf.chain_hops <= 1:
            return True
        positions = {m: (state.x, state.y) for m, state in self.mates.items()}
        positions[mate] = (x, y)
        return (
            chain_links(self.link_sensor, pose, mate, positions, self.lf.chain_hops, self._now)
            is None
        )

    def _follows_me(self, mate: str) -> bool:
        """Whether this leader waits for ``mate``: its latest pose says it follows this
        robot, or it named this robot leader in this round and has said nothing since.
        Only followers: under heavy loss a round can end with two leaders (each decided
        on the utilities it had at the time-out), and two leaders each holding for the
        other's team would wait for ever; a mate that left the roles is not waited for
        either (its own link monitor opens a new round when it needs one)."""
        confirmed = self.role_round.confirmed_at.get(mate)
        if confirmed is not None and self.team_view.heard.get(mate, -math.inf) <= confirmed:
            return True
        role = self.team_view.role(mate)
        if role == L.ROLE_FOLLOWER:
            return self.team_view.leader(mate) == self.robot_id
        return role == L.ROLE_ASSIGNING and confirmed is not None

    def _step_leader_navigating(self) -> None:
        may_hold = self._now >= self._no_hold_until
        if may_hold and self.base.status is NavStatus.ACTIVE and self._followers_out():
            self.base.cancel()
            self.trigger("hold")
            return
        self._step_navigating()

    def _step_leader_holding(self) -> None:
        # hold_timeout (unset: group_hold_timeout in groups): a hold no follower ends gives
        # way, and the leader drives as long before holding again (as serried does).
        lf = self.lf
        timeout = lf.hold_timeout or (lf.group_hold_timeout if self._in_groups() else None)
        timed_out = timeout is not None and self._now - self._state_since >= timeout
        if timeout is not None and timed_out:
            self._no_hold_until = self._now + timeout
        if timed_out or not self._followers_out():
            assert self.goal is not None
            self.base.navigate_to(self.goal.x, self.goal.y)
            self.trigger("release")

    def drop_goal(self) -> None:
        if self._in("leader"):  # no task to lead to: the group dissolves
            self.goal = None
            self._dissolve("its task was reassigned")
            return
        super().drop_goal()

    def _step_leader_retrying(self) -> None:
        if self._now - self._state_since >= self.params.nav_retry_delay:
            assert self.goal is not None
            self.base.navigate_to(self.goal.x, self.goal.y)
            self.trigger("retry")

    def after_task_completed(self) -> None:
        self._just_completed = True
        if self._in("leader"):
            self._dissolve("task completed")
        else:
            self._select_next()

    # -- follower ------------------------------------------------------------------------
    def navigation_target(self) -> tuple[float, float] | None:
        if self._in("follower") or self.state == "regrouping" or self._in("reporting"):
            return self._follow_target
        return super().navigation_target()

    def _leader_position(self) -> tuple[float, float] | None:
        """The leader's last known position, moved on for its age along its heading
        (``mate_extrapolation``; however old: a follower keeps following)."""
        leader = self.leader or ""
        known = self.team_view.known(self._now, None, self.params.mate_extrapolation).get(leader)
        return (known.x, known.y) if known is not None else None

    def _step_follower_clearing(self) -> None:
        self._step_clearing()
        if self.leaf() != "clearing":
            self._follow_target = None
            self._next_refresh = self._now

    def current_role(self) -> str:
        return ROLE_OF_TOP_STATE.get(self.STATE_TABLE[self.state].top, "")

    def current_leader(self) -> str:
        return (self.leader or "") if self._in("follower") else ""

    def _leader_gone(self) -> bool:
        """The leader's process has gone (live mode: its liveliness vanished), or its own
        poses since we follow it say it no longer leads (its completion came earlier)."""
        leader = self.leader or ""
        if leader in self.team_view.departed:
            return True
        fresh = self.team_view.heard.get(leader, -1.0) > self._state_since_role
        return fresh and self.team_view.role(leader) not in (L.ROLE_LEADER, L.ROLE_ASSIGNING)

    def before_follower_step(self) -> bool:
        # In groups a follower gives up (its leader may have finished out of range) when
        # it has waited where its leader was without hearing it for lost_timeout, or has
        # not heard it at all in lost_timeout as a follower: no wait for ever.
        timeout, age = self.lf.lost_timeout, self.team_view.age(self.leader or "", self._now)
        waited = age > timeout and self.leaf() == "waiting"
        unheard = age == math.inf and self._now - self._state_since_role > timeout
        lost = (waited or unheard) and self._in_groups()
        if lost or self._leader_gone():
            gone = self.leader in self.team_view.departed
            why = "lost" if lost else "no longer leads"
            self._dissolve("leader's process has gone" if gone else f"leader {why}")
            return True
        return False

    def _step_follower_following(self) -> None:
        if self.before_follower_step():
            return
        target = self._leader_position()
        if target is None:
            return
        leader = self.mates.get(self.leader or "")
        if leader is not None and self.in_way_of(leader):
            self.step_aside(leader)
            return
        pose = self.base.pose
        distance = math.hypot(target[0] - pose.x, target[1] - pose.y)
        far = self.mate_link_warns(self.leader or "", pose, target[0], target[1])
        near = distance <= self.lf.follow_distance or self._awaits(leader, pose, distance)
        if near and not far:
            self.base.cancel()
            self.trigger("reach")
            return
        aimed = self._follow_target
        moved = aimed is None or math.dist(target, aimed) > 0.5
        stalled = self.base.status is not NavStatus.ACTIVE  # arrived at a hop, or gave up
        if (moved and self._now >= self._next_refresh) or stalled:
            self._follow_target = target
            self._drive_towards_leader(target)
            period = self.lf.refresh_period_far if far else self.lf.refresh_period_near
            self._next_refresh = self._now + period
        self._check_collisions()

    def _drive_towards_leader(self, target: tuple[float, float]) -> None:
        """Navigate to the leader's last known position, unless the follower is in the
        connection area and the planned route would take it out: then one short
        straight hop at the leader, where the straight line is open
        (:func:`mrcomm.agents.lf_route.direct_hop`)."""
        leader = self.leader or ""
        hop = direct_hop(
            self.base, self.link_sensor, leader, target, self.lf.route_check_step,
            self.lf.direct_hop, self._now,
        )  # fmt: skip
        if hop is not None:
            self.timeline.event(L.DIRECT_ROUTE, self._now, leader=leader)
        self.base.navigate_to(*(hop or target))

    def _step_follower_waiting(self) -> None:
        if self.before_follower_step():
            return
        target = self._leader_position()
        if target is None:
            return
        # A waiting follower steps aside for the leader, and for any mate it blocks
        # (e.g. a follower stuck behind it on its way into the leader's sight).
        pose = self.base.pose
        for mate in self.mates.values():
            if self.in_way_of(mate, pose):
                self.step_aside(mate)
                return
        far = self.mate_link_warns(self.leader or "", pose, target[0], target[1])
        distance = math.hypot(target[0] - pose.x, target[1] - pose.y)
        waits = self._awaits(self.mates.get(self.leader or ""), pose, distance)
        if far or (distance > self.lf.refollow_distance and not waits):
            self._follow_target = target
            self.base.navigate_to(*target)
            self._next_refresh = self._now + self.lf.refresh_period_near
            self.trigger("follow")

    # -- regrouping ----------------------------------------------------------------------
    def _step_regrouping(self) -> None:
        """Nobody answered the round: drive to the closest mate's last known position
        and try again once someone is heard (emergent regrouping)."""
        heard_recently = self.team_view.heard_within(1.0, self._now)
        if heard_recently and self._now - self._state_since > 1.0:
            self._open_round(self.role_round.next_number())
            return
        if self._follow_target is None and self.mates:
            pose = self.base.pose
            near = min(self.mates.values(), key=lambda m: math.hypot(m.x - pose.x, m.y - pose.y))
            self._follow_target = (near.x, near.y)
            self.base.navigate_to(*self._follow_target)

    # -- reporting back ------------------------------------------------------------------
    def _in_groups(self) -> bool:
        """The team is larger than one group: the large-team rules apply."""
        return len(self.team) + 1 > self.lf.group_size

    def _awaits(self, leader: Mate | None, pose: Pose, distance: float) -> bool:
        """In groups, the leader is coming this follower's way: it waits for it."""
        radius = self.lf.await_radius if self._in_groups() else 0.0
        return leader_coming(pose, leader, distance, radius)

    def _reports_back(self) -> bool:
        """``report_back``; by default on in a team larger than one group."""
        return self._in_groups() if self.lf.report_back is None else self.lf.report_back

    def _to_report(self) -> tuple[float, float] | None:
        """Where to go for reporting back: the assigner's robot, its work done, goes
        home to be found; a robot whose completion the assigner missed goes to find it
        (:meth:`report_target`). None: nothing to report."""
        home = self.aon_statuses.assigner_home
        if self.aon_statuses.hosts_assigner() and home is not None and not self.agenda:
            pose = self.base.pose
            return home if math.dist((pose.x, pose.y), home) > HOME_REACH else None
        return self.aon_statuses.report_target() if self.aon_statuses.unreported() else None

    def _step_reporting_navigating(self) -> None:
        """Reporting back (:meth:`_to_report`) until there is nothing to report."""
        target = self._to_report()
        if target is None:
            self.base.cancel()
            self.trigger("reported")
            self._select_next()
            return
        aimed = self._follow_target
        if aimed is None or math.dist(target, aimed) > 1.0:
            self._follow_target = target
            self.base.navigate_to(*target)
        self._check_collisions()

    def _in(self, top: str) -> bool:
        """Whether the robot is in ``top`` or a sub-state: ``machine.is_state(top, self,
        allow_substates=True)`` read from the state table (that call costs ~8 µs)."""
        return self.STATE_TABLE[self.state].top == top

    # -- timeline ------------------------------------------------------------------------
    def activity_of(self, state: str) -> str | None:
        return ACTIVITY_OF_FULL_STATE.get(state) or super().activity_of(state)

    def on_state_change(self) -> None:
        top = self.STATE_TABLE[self.state].top
        if top != self._top_state:
            self._top_state = top
            self._state_since_role = self._now
        self.timeline.set_state(ROLE, ROLE_OF_TOP_STATE.get(top), self._now)
        if top == "regrouping":
            self._follow_target = None
