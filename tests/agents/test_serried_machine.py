"""serried's machine on a fake base and bus (SLT link sensor, warning at 4 m): the
lowest-ranked robot with tasks leads and the others follow it; the leader holds for a
mate in warning; a robot whose agenda is done reports it with AON and follows the next
leader; the agenda is over only when everyone's is; the team splits into groups by
rank; a leader never heard is passed over."""

from __future__ import annotations

from mrcomm.agents.executor import NB_TRANSITIONS
from mrcomm.agents.serried import SERRIED_TRANSITIONS, SerriedExecutor, SerriedParams
from mrcomm.messaging.messages import TOPIC_TASK_STATUS, TaskState, TaskStatus
from mrcomm.metrics.compute import serried_metrics
from mrcomm.net.link_sensors import DistanceSensor
from mrcomm.ports import NavStatus
from mrcomm.world.geometry import Pose

from .fakes import Harness, pose_of, task, untaken

TEAM = ("robot_1", "robot_2", "robot_3")  # ranks 0, 1, 2 in the harness


def serried(robot: str = "robot_1") -> Harness:
    return Harness(
        SerriedExecutor, robot=robot, link_sensor=DistanceSensor(4.0), params=SerriedParams()
    )


def finished(mate: str) -> TaskStatus:
    return TaskStatus(sender=mate, incarnation=1, seq=50, stamp=0.0, robot=mate, task_id="",
                      state=TaskState.AGENDA_COMPLETE)  # fmt: skip


def scenario_the_first_in_rank_leads_and_holds_for_a_mate_in_warning(h: Harness) -> None:
    h.assign([task("1", 8.0, 0.0)], team=TEAM)
    h.hear(pose_of("robot_2", -1.0, 0.0))
    assert h.step() == "navigating" and h.agent.group_leader() == "robot_1"
    assert h.bus.published("pose")[-1].role == "leader"
    h.hear(pose_of("robot_2", -5.0, 0.0))  # beyond the 4 m warning
    assert h.step() == "holding" and h.base.goal is None
    h.hear(pose_of("robot_2", -2.0, 0.0))
    assert h.step() == "navigating" and h.base.goal == (8.0, 0.0)
    h.base.arrive()
    h.step()
    assert h.agent.state == "idle"  # its agenda done: reported with AON
    assert h.agent.aon is not None and h.agent.aon.pending_ids()
    assert serried_metrics(h.timeline)["group_hold_time"] > 0
    # robot_2 still has tasks: robot_1 follows it now.
    h.step()
    assert h.agent.state == "following" and h.agent.group_leader() == "robot_2"


def scenario_a_follower_follows_steps_aside_and_takes_its_turn(h: Harness) -> None:
    h.assign([task("5", -6.0, 0.0)], team=TEAM)
    h.hear(pose_of("robot_1", 6.0, 0.0, role="leader"))
    assert h.step() == "following" and h.base.goal == (6.0, 0.0)
    assert h.bus.published("pose")[-1].leader == "robot_1"
    h.base.pose = Pose(5.0, 0.0, 0.0)  # within the follow distance: stops
    h.step(times=11)
    assert h.base.status is not NavStatus.ACTIVE
    # The leader comes its way with a goal: a stopped follower makes way.
    h.hear(pose_of("robot_1", 4.0, 0.0, 0.0, v=0.3, goal_dist=4.0, role="leader"))
    assert h.step() == "clearing"
    h.base.arrive()
    h.step()  # cleared: idle with tasks left reports nothing, and follows again
    assert TaskState.AGENDA_COMPLETE not in [m.state for m in h.bus.published(TOPIC_TASK_STATUS)]
    h.bus.deliver(TOPIC_TASK_STATUS, finished("robot_1"))
    h.step(times=2)
    assert h.agent.state == "navigating" and h.base.goal == (-6.0, 0.0)  # its turn


def scenario_waits_for_a_task_then_the_team_finishes(h: Harness) -> None:
    h.assign([task("9", 3.0, 0.0, arrival_time=5.0)], team=TEAM)
    h.bus.deliver(TOPIC_TASK_STATUS, finished("robot_1"))
    assert h.step() == "waiting"  # its turn, but its task has not arrived
    h.step(times=60)
    assert h.agent.state == "navigating"
    h.base.status = NavStatus.ABORTED
    assert h.step() == "retrying"
    h.bus.deliver(TOPIC_TASK_STATUS, finished("robot_3"))
    h.step(times=25)
    h.base.arrive()
    h.step(times=2)
    assert h.agent.state == "idle" and h.agent.done is False  # AON still pending


SCENARIOS = [
    (scenario_the_first_in_rank_leads_and_holds_for_a_mate_in_warning, "robot_1"),
    (scenario_a_follower_follows_steps_aside_and_takes_its_turn, "robot_2"),
    (scenario_waits_for_a_task_then_the_team_finishes, "robot_2"),
]


def test_scenarios() -> None:
    for scenario, robot in SCENARIOS:
        scenario(serried(robot))


def test_every_added_transition_is_taken() -> None:
    assert SERRIED_TRANSITIONS[: len(NB_TRANSITIONS)] == NB_TRANSITIONS
    taken: list[tuple[str, str]] = []
    for scenario, robot in SCENARIOS:
        h = serried(robot)
        scenario(h)
        taken += h.taken
    missing = untaken(SERRIED_TRANSITIONS[len(NB_TRANSITIONS) :], taken)
    # follow from unassigned/waiting/executing/retrying and finish/wait from following
    # are safety nets for views that change mid-step; the scenarios take the main ones.
    main = {("follow", "idle"), ("go", "following"), ("hold", "navigating"),
            ("release", "holding"), ("make_way", "following")}  # fmt: skip
    for t in missing:
        sources = t["source"] if isinstance(t["source"], list) else [t["source"]]
        assert not any((t["trigger"], s) in main for s in sources), t


def test_the_team_splits_into_groups_by_its_random_order() -> None:
    """Groups of group_size by rank, the same as every member computes them; 0 is one
    group of the whole team."""
    team = tuple(f"robot_{i}" for i in range(1, 8))
    groups = {}
    for robot in team:
        h = Harness(SerriedExecutor, robot=robot, params=SerriedParams(group_size=3))
        h.assign([task("1", 1.0, 0.0)], team=team)
        groups[robot] = {robot, *h.agent.group}
    assert groups["robot_1"] == groups["robot_3"] == {"robot_1", "robot_2", "robot_3"}
    assert groups["robot_4"] == groups["robot_6"] == {"robot_4", "robot_5", "robot_6"}
    assert groups["robot_7"] == {"robot_7"}
    whole = Harness(SerriedExecutor, robot="robot_5", params=SerriedParams(group_size=0))
    whole.assign([task("1", 1.0, 0.0)], team=team)
    assert set(whole.agent.group) == set(team) - {"robot_5"}


def test_a_leader_never_heard_is_passed_over_after_lost_timeout() -> None:
    """robot_2 would follow robot_1 (first in rank, tasks left) but never hears it: once
    the mission is lost_timeout old it leads its group to its own task instead (it
    followed a leader it never heard for ever before)."""
    h = serried("robot_2")
    h.assign([task("5", -6.0, 0.0)], team=TEAM)
    assert h.step() == "following" and h.agent.group_leader() == "robot_1"
    h.step(times=int(SerriedParams().lost_timeout / 0.1) + 2)
    assert h.agent.group_leader() == "robot_2"
    assert h.agent.state == "navigating" and h.base.goal == (-6.0, 0.0)
    h.hear(pose_of("robot_1", 6.0, 0.0, role="leader"))  # heard again: it leads again
    assert h.agent.group_leader() == "robot_1"
