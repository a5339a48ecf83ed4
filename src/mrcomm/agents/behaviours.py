"""The built-in team behaviours as registered variants (kind ``behaviour``).

A behaviour is an executor class (a stepped state machine acting through the Bus and
Base ports) with a pydantic model of its parameters (the class's ``Params``). Its spec
names both, the network models it works with, the topics it publishes, the metrics it
adds and whether its statuses go with AON. The classes are imported on first use.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mrcomm.specs import TeamMetric, VariantSpec, get_spec, variant_names

if TYPE_CHECKING:
    from mrcomm.agents.executor import TaskExecutor

#: Leader-Follower's team metrics (the original study's): each robot's time by role.
LF_TEAM_METRICS = (
    TeamMetric("na_movement_time", "NA movement time", "s"),
    TeamMetric("leader_movement_time", "Leader movement time", "s"),
    TeamMetric("follower_movement_time", "Follower movement time", "s"),
    TeamMetric("leader_disconnect_time", "Leader disconnect time", "s"),
    TeamMetric("follower_waiting_time", "Follower waiting time", "s"),
    TeamMetric("role_assignment_time", "Role assignment time", "s"),
    TeamMetric("switching_time", "Switching time", "s"),
)

NB_SPEC = VariantSpec(
    kind="behaviour",
    name="nb",
    entry="mrcomm.agents.executor:TaskExecutor",
    params="mrcomm.agents.executor_params:ExecutorParams",
    summary="NB, no behaviour: each robot goes to its closest task and reports it once "
    "(plain publish); it ignores link quality",
    topics=("pose", "task_status"),
    uses_threshold=False,
    aliases=("baseline", "no-behaviour"),
)
LF_SPEC = VariantSpec(
    kind="behaviour",
    name="lf",
    entry="mrcomm.agents.lf:LeaderFollowerExecutor",
    params="mrcomm.agents.lf_machine:LfParams",
    summary="LF, leader-follower: robots whose link warns elect a leader by utility; "
    "followers keep within the threshold; statuses go with AON",
    aliases=("leader-follower", "leaderfollower"),
    topics=("pose", "task_status", "utility", "role", "aon"),
    robot_metrics="mrcomm.metrics.compute:lf_metrics",
    metrics=(
        "na_movement_time",
        "leader_movement_time",
        "follower_movement_time",
        "regrouping_movement_time",
        "leader_disconnect_time",
        "follower_waiting_time",
        "switching_time",
        "role_assignment_time",
        "disconnects_detected",
        "roles_assigned",
        "times_leader",
    ),
    team_metrics=LF_TEAM_METRICS,
    uses_aon=True,
)
RPS_SPEC = VariantSpec(
    kind="behaviour",
    name="rps",
    entry="mrcomm.agents.rps:RendezvousExecutor",
    params="mrcomm.agents.rps:RpsParams",
    summary="RPS, rendezvous point: robots disperse to their tasks (as NB) and regroup "
    "at a meeting point every K tasks or T seconds, publishing again there every status "
    "they know of",
    topics=("pose", "task_status"),
    robot_metrics="mrcomm.metrics.compute:rps_metrics",
    metrics=("rendezvous_count", "rendezvous_time", "statuses_reshared"),
    team_metrics=(TeamMetric("rendezvous_time", "Rendezvous time", "s"),),
    uses_threshold=False,
)
SERRIED_SPEC = VariantSpec(
    kind="behaviour",
    name="serried",
    entry="mrcomm.agents.serried:SerriedExecutor",
    params="mrcomm.agents.serried:SerriedParams",
    summary="Serried ranks: the team moves as one group to each task in turn, led by each "
    "robot in turn (team-wide order); the leader holds while a mate's link warns; "
    "statuses with AON",
    topics=("pose", "task_status", "aon"),
    robot_metrics="mrcomm.metrics.compute:serried_metrics",
    metrics=("group_hold_time",),
    team_metrics=(TeamMetric("group_hold_time", "Group hold time", "s"),),
    uses_aon=True,
)
LF_WAIT_SPEC = VariantSpec(
    kind="behaviour",
    name="lf-wait",
    entry="mrcomm.agents.lf_wait:LfWaitExecutor",
    params="mrcomm.agents.lf_wait:LfWaitParams",
    summary="LF whose followers do their own tasks near the group: a follower asks its "
    "leader to wait (its poses say 'detouring'), completes the task and rejoins",
    topics=("pose", "task_status", "utility", "role", "aon"),
    robot_metrics="mrcomm.metrics.compute:lf_wait_metrics",
    metrics=(*LF_SPEC.metrics, "detours", "detour_tasks", "leader_detour_wait_time"),
    team_metrics=(
        *LF_TEAM_METRICS,
        TeamMetric("leader_detour_wait_time", "Leader detour wait time", "s"),
        TeamMetric("detour_tasks", "Tasks done on detours", "count", "greater"),
    ),
    uses_aon=True,
)


def behaviour_names() -> list[str]:
    return variant_names("behaviour")


def behaviour_class(name: str) -> type[TaskExecutor]:
    cls: type[TaskExecutor] = get_spec("behaviour", name).load()
    return cls
