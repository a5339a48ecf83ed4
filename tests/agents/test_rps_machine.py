"""rps's machine on a fake base and bus: robots go to the meeting point after K tasks or
T seconds and at the end, publish every status they know there (a mate's under the
mate's name) repeatedly, wait for the team or time out, and disperse."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from mrcomm.agents.executor import NB_TRANSITIONS
from mrcomm.agents.rps import RPS_TRANSITIONS, RendezvousExecutor, RpsParams
from mrcomm.messaging.messages import TOPIC_TASK_STATUS, TaskState, TaskStatus
from mrcomm.metrics.compute import rps_metrics
from mrcomm.world.geometry import Pose

from .fakes import Harness, pose_of, task, untaken


def rps(**params: object) -> Harness:
    return Harness(RendezvousExecutor, params=RpsParams(**params))  # type: ignore[arg-type]


def start(h: Harness, tasks: int = 3) -> None:
    """robot_1 at (0, 0); robot_2 first heard at (0, 3): the meeting point is (0, 1.5)."""
    h.assign([task(str(i), 2.0 * i, 0.0) for i in range(1, tasks + 1)])
    h.hear(pose_of("robot_2", 0.0, 3.0))
    assert h.step() == "navigating"


def complete(h: Harness) -> None:
    h.base.arrive()
    h.step()


def reach_point(h: Harness) -> None:
    assert h.agent.state == "meeting"
    assert h.base.goal == pytest.approx((0.0, 1.5))
    h.base.pose = Pose(0.0, 1.2, 0.0)
    assert h.step() == "gathering"
    h.step()  # the first re-share


def shared(h: Harness) -> list[tuple[str, str]]:
    return [
        (m.task_id, m.robot)
        for m in h.bus.published(TOPIC_TASK_STATUS)
        if m.state is TaskState.SUCCESS
    ]


def scenario_meets_after_two_tasks_shares_and_disperses(h: Harness) -> None:
    start(h)
    complete(h)
    assert h.agent.state == "navigating"  # one task done: on to the next
    complete(h)
    reach_point(h)
    assert shared(h)[-2:] == [("1", "robot_1"), ("2", "robot_1")]  # published again
    for _ in range(int(5.0 * 6 / 0.1) + 5):  # the mate is here: leave after 6 re-shares
        h.hear(pose_of("robot_2", 0.5, 2.5))
        h.step()
        if h.agent.state != "gathering":
            break
    assert h.agent.state == "navigating" and h.base.goal == (6.0, 0.0)
    assert shared(h).count(("2", "robot_1")) == 1 + 6  # once when done, 6 times there


def scenario_waits_for_a_missing_mate_until_the_time_out(h: Harness) -> None:
    start(h)
    complete(h)
    complete(h)
    reach_point(h)
    h.step(times=int(h.agent.rps.gather_timeout / 0.1) - 5)
    assert h.agent.state == "gathering"  # robot_2 was never heard at the point
    h.step(times=10)
    assert h.agent.state == "navigating"


def scenario_the_time_rule_interrupts_a_drive(h: Harness) -> None:
    start(h)
    h.step(times=int(h.agent.rps.every_seconds / 0.1) + 1)
    assert h.agent.state == "meeting"
    assert [t.task_id for t in h.agent.agenda] == ["1", "2", "3"]  # nothing dropped


def scenario_final_rendezvous_then_idle_sharing_a_mates_status(h: Harness) -> None:
    start(h, tasks=1)
    mate = TaskStatus(sender="robot_2", incarnation=1, seq=4, stamp=0.0, robot="robot_2",
                      task_id="9", state=TaskState.SUCCESS)  # fmt: skip
    h.bus.deliver(TOPIC_TASK_STATUS, mate)
    complete(h)
    reach_point(h)
    assert ("9", "robot_2") in shared(h)  # passed on in the mate's name
    assert all(m.sender == "robot_1" for m in h.bus.published(TOPIC_TASK_STATUS))
    h.step(times=int(h.agent.rps.gather_timeout / 0.1) + 5)
    assert h.agent.state == "idle"
    metrics = rps_metrics(h.timeline)
    assert metrics["rendezvous_count"] == 1 and metrics["rendezvous_time"] > 29.0


SCENARIOS: list[Callable[[Harness], None]] = [
    scenario_meets_after_two_tasks_shares_and_disperses,
    scenario_waits_for_a_missing_mate_until_the_time_out,
    scenario_final_rendezvous_then_idle_sharing_a_mates_status,
]


@pytest.mark.parametrize("scenario", SCENARIOS, ids=lambda f: f.__name__.removeprefix("scenario_"))
def test_scenario(scenario: Callable[[Harness], None]) -> None:
    scenario(rps())


def test_the_time_rule() -> None:
    scenario_the_time_rule_interrupts_a_drive(
        rps(every_tasks=0, every_seconds=10.0, gather_radius=1.0)
    )


def test_a_fixed_meeting_point() -> None:
    h = rps(meeting="fixed", meeting_x=7.0, meeting_y=-2.0)
    start(h, tasks=1)
    complete(h)
    assert h.agent.state == "meeting" and h.base.goal == (7.0, -2.0)


def test_every_rps_transition_is_taken_by_these_tests() -> None:
    # NB's part of the table is NB's, taken by NB's own tests; rps adds the rest.
    assert RPS_TRANSITIONS[: len(NB_TRANSITIONS)] == NB_TRANSITIONS
    taken: list[tuple[str, str]] = []
    for scenario in SCENARIOS:
        h = rps()
        scenario(h)
        taken += h.taken
    h = rps(every_tasks=0, every_seconds=10.0, gather_radius=1.0)
    scenario_the_time_rule_interrupts_a_drive(h)
    taken += h.taken
    added = RPS_TRANSITIONS[len(NB_TRANSITIONS) :]
    missing = untaken(added, taken)
    # From gathering, "wait" needs a task that has not arrived yet.
    assert [t["trigger"] for t in missing] in ([], ["wait"]), missing


def test_bad_parameters_are_refused() -> None:
    with pytest.raises(ValueError, match="meeting"):
        RpsParams(meeting="moon")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="gather_radius"):
        RpsParams(gather_radius=0.0)
