"""lf-wait's machine on a fake base and bus (SLT link sensor, warning at 4 m): a
follower does its own task near the group and rejoins, its leader waits for it, and
both give up after the detour time-out. With LF's own scenarios, every transition of
lf-wait's table is taken (the last test checks that)."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from mrcomm.agents.lf_machine import LF_TRANSITIONS
from mrcomm.agents.lf_wait import LF_WAIT_STATES, LfWaitExecutor, LfWaitParams
from mrcomm.messaging.messages import TaskState
from mrcomm.metrics import labels as L
from mrcomm.metrics.compute import lf_wait_metrics
from mrcomm.net.link_sensors import DistanceSensor
from mrcomm.ports import NavStatus
from mrcomm.world.geometry import Pose

from .fakes import Harness, pose_of, task, untaken
from .test_lf_machine import SCENARIOS as LF_SCENARIOS
from .test_lf_machine import follow, lead


def lf_wait(**params: float) -> Harness:
    return Harness(LfWaitExecutor, link_sensor=DistanceSensor(4.0), params=LfWaitParams(**params))


def _near_task_for_the_follower(h: Harness) -> None:
    """robot_1 follows robot_2 (last heard at 6, 0); it stands at 3, 0 and one of its
    own tasks lies at 4, 0: 1 m from it, 2 m from its leader."""
    follow(h)
    h.base.pose = Pose(3.0, 0.0, 0.0)
    h.agent.agenda.append(task("near", 4.0, 0.0))


def scenario_follower_does_a_task_near_the_group_and_rejoins(h: Harness) -> None:
    _near_task_for_the_follower(h)
    assert h.step() == "follower_detouring"
    assert h.base.goal == (4.0, 0.0)
    h.step(times=2)
    poses = h.bus.published("pose")
    assert poses[-1].role == L.ROLE_DETOURING and poses[-1].leader == "robot_2"
    h.base.arrive()
    assert h.step() == "follower_following"  # completed at once (no duration), rejoined
    assert "near" in h.agent.completed and all(t.task_id != "near" for t in h.agent.agenda)
    assert h.agent.aon is not None and h.agent.aon.pending_ids()  # reported with AON
    h.step(times=2)
    assert h.bus.published("pose")[-1].role == L.ROLE_FOLLOWER
    metrics = lf_wait_metrics(h.timeline)
    assert metrics["detours"] == 1 and metrics["detour_tasks"] == 1


def scenario_a_waiting_follower_detours_too_and_gives_up_a_failed_one(h: Harness) -> None:
    _near_task_for_the_follower(h)
    h.agent.agenda.pop()  # not yet: first reach the leader and wait there
    h.base.pose = Pose(5.0, 0.0, 0.0)
    assert h.step() == "follower_waiting"
    h.agent.agenda.append(task("near", 4.0, 0.0))
    assert h.step() == "follower_detouring"
    h.base.status = NavStatus.ABORTED
    assert h.step() == "follower_following"  # navigation failed: back with the group
    assert any(t.task_id == "near" for t in h.agent.agenda)  # kept for later


def scenario_a_detour_that_takes_too_long_is_given_up(h: Harness) -> None:
    _near_task_for_the_follower(h)
    assert h.step() == "follower_detouring"
    h.step(times=int(h.agent.lfw.detour_timeout / 0.1) + 2)
    assert h.agent.state == "follower_following"
    ended = [e.data["how"] for e in h.timeline.events if e.label == L.DETOUR_ENDED]
    assert ended == ["timed out"]


def scenario_a_detouring_follower_avoids_a_mate(h: Harness) -> None:
    _near_task_for_the_follower(h)
    assert h.step() == "follower_detouring"
    h.hear(pose_of("robot_3", 3.6, 0.0, 3.14159, v=0.3, goal_dist=5.0))
    assert h.step() == "follower_avoiding"


def scenario_leader_waits_for_a_detouring_follower(h: Harness) -> None:
    lead(h)
    h.hear(pose_of("robot_2", -2.0, 0.0, role=L.ROLE_DETOURING, leader="robot_1"))
    assert h.step() == "leader_waiting"
    assert h.base.goal is None  # stopped
    h.step(times=20)
    assert h.agent.state == "leader_waiting"
    h.hear(pose_of("robot_2", -1.5, 0.0, role=L.ROLE_FOLLOWER, leader="robot_1"))
    assert h.step() == "leader_navigating"  # the follower is back
    assert h.base.goal == (10.0, 0.0)
    assert h.timeline.total(L.LEADER_DETOUR_WAIT) == pytest.approx(2.1, abs=0.11)


def scenario_leader_stops_waiting_after_the_time_out(h: Harness) -> None:
    lead(h)
    h.hear(pose_of("robot_2", -2.0, 0.0, role=L.ROLE_DETOURING, leader="robot_1"))
    assert h.step() == "leader_waiting"
    h.step(times=int(h.agent.lfw.detour_timeout / 0.1) + 2)
    assert h.agent.state == "leader_navigating"  # its "follows again" was lost: go on


def scenario_leader_does_not_wait_for_another_leaders_follower(h: Harness) -> None:
    lead(h)
    h.hear(pose_of("robot_2", -2.0, 0.0, role=L.ROLE_DETOURING, leader="robot_3"))
    assert h.step(times=3) == "leader_navigating"


SCENARIOS: list[Callable[[Harness], None]] = [
    scenario_follower_does_a_task_near_the_group_and_rejoins,
    scenario_a_waiting_follower_detours_too_and_gives_up_a_failed_one,
    scenario_a_detour_that_takes_too_long_is_given_up,
    scenario_a_detouring_follower_avoids_a_mate,
    scenario_leader_waits_for_a_detouring_follower,
    scenario_leader_stops_waiting_after_the_time_out,
    scenario_leader_does_not_wait_for_another_leaders_follower,
]


@pytest.mark.parametrize("scenario", SCENARIOS, ids=lambda f: f.__name__.removeprefix("scenario_"))
def test_scenario(scenario: Callable[[Harness], None]) -> None:
    scenario(lf_wait())


@pytest.mark.parametrize(
    "scenario", LF_SCENARIOS, ids=lambda f: f.__name__.removeprefix("scenario_")
)
def test_lf_scenarios_hold_for_lf_wait(scenario: Callable[[Harness], None]) -> None:
    # With no task of its own near the group, lf-wait is LF.
    scenario(lf_wait())


def test_every_lf_wait_transition_is_taken_by_these_tests() -> None:
    taken: list[tuple[str, str]] = []
    for scenario in [*LF_SCENARIOS, *SCENARIOS]:
        harness = lf_wait()
        scenario(harness)
        taken += harness.taken
    missing = untaken(LF_TRANSITIONS, taken)
    for state in LF_WAIT_STATES:
        if isinstance(state, dict) and state["name"] in ("leader", "follower"):
            missing += untaken(state["transitions"], taken, prefix=state["name"] + "_")
    assert not missing, missing


def test_a_task_near_the_follower_but_far_from_the_leader_is_left_for_later() -> None:
    h = lf_wait()
    follow(h)  # leader last heard at 6, 0
    h.base.pose = Pose(3.0, 0.0, 0.0)
    h.agent.agenda.append(task("behind", 0.5, 0.0))  # 2.5 m from it, 5.5 m from the leader
    assert h.step() == "follower_following"
    assert TaskState.SUCCESS not in [m.state for m in h.bus.published("task_status")]


def test_the_detour_parameters_are_checked() -> None:
    for bad in ({"detour_distance": 0.0}, {"detour_timeout": -1.0}):
        with pytest.raises(ValueError, match=next(iter(bad))):
            LfWaitParams(**bad)
