"""Metric computation from hand-made timelines (SPEC §8)."""

import itertools

import pytest

from mrcomm.metrics import labels as L
from mrcomm.metrics.compute import RobotFacts, execution_phase, mission_metrics, robot_metrics
from mrcomm.metrics.timeline import ACTIVITY, ROLE, Timeline


def _timeline() -> Timeline:
    tl = Timeline("r1")
    tl.event(L.ASSIGNMENT_RECEIVED, 0.1)
    tl.set_state(ACTIVITY, L.INIT, 0.1)
    tl.event(L.STARTED_MOVING, 0.6)
    tl.set_state(ACTIVITY, L.MOVING, 0.6)
    tl.event(L.NEAR_COLLISION, 5.0, mate="r2", repeat=False)
    tl.set_state(ACTIVITY, L.DELAY, 5.0)
    tl.set_state(ACTIVITY, L.MOVING, 7.5)
    tl.event(L.NEAR_COLLISION, 8.0, mate="r2", repeat=True)
    tl.set_state(ACTIVITY, L.DELAY, 8.0)
    tl.set_state(ACTIVITY, L.MOVING, 9.0)
    tl.set_state(ACTIVITY, L.MOVING, 9.5)  # repeating a state changes nothing
    tl.set_state(ACTIVITY, L.TASK, 20.0)
    tl.event(L.TASK_COMPLETED, 22.0, task_id="1")
    tl.set_state(ACTIVITY, L.IDLE, 22.0)
    tl.set_state(ROLE, "na", 0.1)  # an overlapping track does not disturb activity
    tl.close_all(30.0)
    return tl


def test_intervals_and_totals() -> None:
    tl = _timeline()
    assert tl.total(L.MOVING) == pytest.approx((5.0 - 0.6) + (8.0 - 7.5) + (20.0 - 9.0))
    assert tl.total(L.DELAY) == pytest.approx(3.5)
    assert tl.total(L.IDLE) == pytest.approx(8.0)
    assert tl.total("na", ROLE) == pytest.approx(29.9)
    acts = [i for i in tl.intervals if i.track == ACTIVITY]
    for earlier, later in itertools.pairwise(acts):
        assert earlier.end <= later.start  # one activity at a time


def test_robot_metrics_from_a_hand_made_timeline() -> None:
    facts = RobotFacts(
        distance=12.5, min_separation=0.7, max_separation=9.0, tasks_assigned=1, tasks_failed=0
    )
    m = robot_metrics(_timeline(), facts)
    assert m["initialisation_time"] == pytest.approx(0.5)
    assert m["movement_time"] == pytest.approx(15.9)
    assert m["delay_time"] == pytest.approx(3.5)
    assert m["task_execution_time"] == pytest.approx(2.0)
    assert m["idle_time"] == pytest.approx(8.0)
    assert m["near_collisions"] == 2
    assert m["near_collisions_filtered"] == 1
    assert m["tasks_completed"] == 1
    assert m["last_task_time"] == pytest.approx(22.0)


def test_mission_metrics_sum_robots_and_take_extremes() -> None:
    t1, t2 = _timeline(), Timeline("r2")
    t2.event(L.ASSIGNMENT_RECEIVED, 0.3)
    t2.event(L.TASK_COMPLETED, 25.0, task_id="2")
    t2.close_all(30.0)
    assert execution_phase({"r1": t1, "r2": t2}) == (0.3, 25.0)
    r1 = robot_metrics(t1, RobotFacts(10.0, 0.7, 9.0, 1, 0))
    r2 = robot_metrics(t2, RobotFacts(4.0, 0.9, 12.0, 1, 1))
    m = mission_metrics(
        {"r1": r1, "r2": r2}, {"r1": t1, "r2": t2}, tasks_total=2, failed_tasks=["10", "2"]
    )
    assert m["execution_phase_time"] == pytest.approx(24.7)
    assert m["total_distance"] == pytest.approx(14.0)
    assert m["near_collisions"] == 2
    assert m["min_separation"] == 0.7 and m["max_separation"] == 12.0
    assert m["failed_tasks"] == ["2", "10"]
    assert m["successful"] is False


def test_a_task_done_twice_counts_once() -> None:
    """A robot restarted in a live run may complete a task again: 7 tasks never
    become 8 completed."""
    from mrcomm.metrics.compute import completed_tasks

    timeline = Timeline("r1")
    for t, task in ((10.0, "1"), (20.0, "2"), (30.0, "2")):
        timeline.event(L.TASK_COMPLETED, t, task_id=task)
    assert completed_tasks(timeline) == {"1", "2"}
    other = Timeline("r2")
    other.event(L.TASK_COMPLETED, 5.0, task_id="3")
    robots = {"r1": {"tasks_completed": 2}, "r2": {"tasks_completed": 1}}
    robots = {rid: {**_zero_metrics(), **m} for rid, m in robots.items()}
    mission = mission_metrics(robots, {"r1": timeline, "r2": other}, tasks_total=3, failed_tasks=[])
    assert mission["tasks_completed"] == 3


def _zero_metrics() -> dict[str, float | None]:
    keys = ("movement_time", "distance", "near_collisions", "near_collisions_filtered")
    keys += ("delay_time", "idle_time", "task_execution_time")
    return {**dict.fromkeys(keys, 0.0), "min_separation": None, "max_separation": None}
