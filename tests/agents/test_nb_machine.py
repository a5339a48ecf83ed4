"""The NB machine, unit by unit, on a fake base and a fake bus: every transition of
its table is taken by these tests (the last test checks that)."""

from __future__ import annotations

import math
from typing import Any, ClassVar

import pytest

from mrcomm.agents.executor import NB_TRANSITIONS, TaskExecutor
from mrcomm.agents.team_view import TeamView
from mrcomm.messaging.messages import (
    TOPIC_POSE,
    TOPIC_TASK_STATUS,
    CommandKind,
    OperatorCommand,
    TaskState,
)
from mrcomm.metrics import labels as L
from mrcomm.ports import NavStatus

from .fakes import Harness, pose_of, task, untaken


@pytest.fixture
def nb() -> Harness:
    return Harness(TaskExecutor)


def test_goes_to_the_closest_task_reports_it_once_and_ends_idle(nb: Harness) -> None:
    nb.assign([task("far", 10.0, 0.0), task("near", 2.0, 0.0)])
    assert nb.step() == "navigating"
    assert nb.base.goal == (2.0, 0.0)  # greedy: the closest first
    nb.base.arrive()
    assert nb.step() == "navigating"  # zero duration: done, next task chosen at once
    assert nb.base.goal == (10.0, 0.0)
    nb.base.arrive()
    assert nb.step() == "idle"
    statuses = nb.bus.published(TOPIC_TASK_STATUS)
    assert [(s.task_id, s.state) for s in statuses] == [
        ("near", TaskState.SUCCESS),
        ("far", TaskState.SUCCESS),
        ("", TaskState.AGENDA_COMPLETE),
    ]  # each once: NB never re-sends
    nb.step(times=20)
    assert len(nb.bus.published(TOPIC_TASK_STATUS)) == 3
    assert nb.agent.done
    assert ("navigating", "executing") in nb.taken


def test_a_task_with_a_duration_is_executed_that_long(nb: Harness) -> None:
    nb.assign([task("t", 1.0, 0.0, duration=1.0)])
    nb.step()
    nb.base.arrive()
    assert nb.step() == "executing"
    assert nb.step(times=5) == "executing"
    assert nb.step(times=6) == "idle"
    assert nb.timeline.total(L.TASK) == pytest.approx(1.0, abs=0.11)


def test_waits_for_a_task_that_has_not_arrived(nb: Harness) -> None:
    nb.assign([task("later", 3.0, 0.0, arrival_time=1.0)])
    assert nb.step() == "waiting"
    assert nb.base.goal is None
    nb.step(times=9)
    assert nb.agent.state == "waiting"
    assert nb.step(times=2) == "navigating"


def test_a_failed_navigation_keeps_the_task_and_retries(nb: Harness) -> None:
    nb.assign([task("t", 5.0, 0.0)])
    nb.step()
    nb.base.status = NavStatus.ABORTED
    assert nb.step() == "retrying"
    assert [t.task_id for t in nb.agent.agenda] == ["t"]  # a task never fails for this
    nb.step(times=int(nb.agent.params.nav_retry_delay / 0.1) - 1)
    assert nb.agent.state == "retrying"
    assert nb.step(times=2) == "navigating"
    assert nb.base.goals == [(5.0, 0.0), (5.0, 0.0)]


def test_a_mate_ahead_heading_at_us_is_a_near_collision_then_we_resume(nb: Harness) -> None:
    nb.assign([task("t", 10.0, 0.0)])
    nb.step()
    # Mate 0.8 m ahead, coming towards us; it is closer to its goal: it has right of way.
    nb.hear(pose_of("robot_2", 0.8, 0.0, math.pi, v=0.3, goal_dist=1.0))
    assert nb.step() == "avoiding"
    assert nb.base.cancels == 1
    assert [e.label for e in nb.timeline.events].count(L.NEAR_COLLISION) == 1
    nb.hear(pose_of("robot_2", 0.8, 3.0, math.pi / 2, v=0.3, goal_dist=1.0))  # gone
    nb.step(times=int((nb.agent.params.collision_pause + nb.agent.params.clear_time) / 0.1) + 2)
    assert nb.agent.state == "navigating"
    assert nb.base.goal == (10.0, 0.0)
    assert nb.timeline.total(L.DELAY) > nb.agent.params.collision_pause - 0.11


def test_a_mate_alongside_in_the_same_direction_is_no_conflict(nb: Harness) -> None:
    nb.assign([task("t", 10.0, 0.0)])
    nb.step()
    nb.hear(pose_of("robot_2", 0.7, 0.3, 0.0, v=0.3, goal_dist=8.0))
    assert nb.step(times=5) == "navigating"


def test_an_idle_robot_in_a_mates_way_steps_aside(nb: Harness) -> None:
    nb.assign([])
    assert nb.step() == "idle"
    # A mate with a goal, 1 m behind us and heading our way.
    nb.hear(pose_of("robot_2", -1.0, 0.0, 0.0, v=0.3, goal_dist=5.0))
    assert nb.step() == "clearing"
    aside = nb.base.goal
    assert aside is not None and abs(aside[1]) == pytest.approx(nb.agent.params.make_way_step)
    nb.base.arrive()
    assert nb.step() == "idle"
    assert [e.label for e in nb.timeline.events].count(L.MADE_WAY) == 1


def test_a_mates_pose_heard_more_than_ten_seconds_ago_puts_no_robot_in_its_way(
    nb: Harness,
) -> None:
    """An idle robot in a corner stepped aside every 0.4 s, to the time limit, for a
    mate's pose 346 s old: each step aside failed, and the old pose still said "in the
    way". A mate that close is heard several times a second."""
    nb.assign([])
    nb.step(times=110)  # 11 s on
    behind = dict(v=0.3, goal_dist=5.0)
    nb.hear(pose_of("robot_2", -1.0, 0.0, 0.0, stamp=nb.now - 10.5, seq=2, **behind))
    assert nb.step(times=5) == "idle"
    nb.hear(pose_of("robot_2", -1.0, 0.0, 0.0, stamp=nb.now - 0.2, seq=3, **behind))
    assert nb.step() == "clearing"


def test_a_task_given_while_making_way_is_planned_once_idle(nb: Harness) -> None:
    nb.assign([])
    assert nb.step() == "idle"
    nb.hear(pose_of("robot_2", -1.0, 0.0, 0.0, v=0.3, goal_dist=5.0))
    assert nb.step() == "clearing"
    nb.agent.on_command(command(CommandKind.ADD, task=task("x", 5.0, 5.0)))
    assert nb.step() == "clearing"  # it finishes stepping aside first
    nb.base.arrive()
    nb.hear(pose_of("robot_2", -9.0, 0.0, 0.0))  # the mate has gone by
    assert nb.step() == "idle"
    assert nb.step() == "unassigned"
    assert nb.step() == "navigating" and nb.base.goal == (5.0, 5.0)


def test_poses_go_out_at_five_hertz_with_the_goal_distance(nb: Harness) -> None:
    nb.assign([task("t", 3.0, 4.0)])
    nb.step(times=10)
    poses = nb.bus.published(TOPIC_POSE)
    assert len(poses) == 5
    assert poses[-1].goal_dist == pytest.approx(5.0)


def test_the_team_view_knows_each_mates_age() -> None:
    view = TeamView()
    view.hear(pose_of("robot_2", 1.0, 2.0, role="leader", leader=""), now=3.0)
    assert view.age("robot_2", 4.5) == pytest.approx(1.5)
    assert math.isinf(view.age("robot_3", 4.5))
    assert view.poses["robot_2"].x == 1.0 and view.role("robot_2") == "leader"
    assert view.heard_within(2.0, 4.5) and not view.heard_within(1.0, 4.5)


def test_a_state_without_a_handler_is_refused_when_the_class_is_defined() -> None:
    with pytest.raises(TypeError, match="state 'dancing' has no handler"):

        class Dancer(TaskExecutor):
            states: ClassVar[list[Any]] = [*TaskExecutor.states, "dancing"]

    with pytest.raises(TypeError, match="handlers for no state: _step_singing"):

        class Singer(TaskExecutor):
            def _step_singing(self) -> None:
                pass


def test_a_task_that_depends_on_another_waits_for_its_completion(nb: Harness) -> None:
    nb.assign([task("a", 1.0, 0.0, depends=("b",)), task("c", 2.0, 0.0)])
    assert nb.step() == "navigating" and nb.base.goal == (2.0, 0.0)  # a must wait for b
    nb.base.arrive()
    assert nb.step() == "waiting"  # executed c; a is not available yet
    nb.agent.set_time(nb.now)
    done = nb.bus.published(TOPIC_TASK_STATUS)[0]
    nb.bus.deliver(
        TOPIC_TASK_STATUS,
        done.__class__(
            **{**_fields(done), "task_id": "b", "robot": "robot_2", "sender": "robot_2"}
        ),
    )
    assert nb.step() == "navigating" and nb.base.goal == (1.0, 0.0)


def command(kind: CommandKind, robot: str = "robot_1", **fields: Any) -> OperatorCommand:
    return OperatorCommand(
        sender="operator", incarnation=1, seq=1, stamp=0.0, command=kind, robot=robot, **fields
    )


def test_operator_commands_change_the_agenda_and_stop_the_robot(nb: Harness) -> None:
    far, near = task("far", 10.0, 0.0), task("near", 2.0, 0.0)
    nb.assign([far, near])
    assert nb.step() == "navigating" and nb.base.goal == (2.0, 0.0)
    # The task it drives to is reassigned: it stops and chooses again.
    nb.agent.on_command(command(CommandKind.REASSIGN, "robot_2", task=near, former="robot_1"))
    assert nb.step() == "retrying" and nb.agent.agenda == [far]
    nb.step(times=20)
    assert nb.base.goal == (10.0, 0.0)
    # Paused: it stops and decides nothing (its pose still goes out) until resumed.
    nb.agent.on_command(command(CommandKind.PAUSE))
    assert nb.base.goal is None and nb.agent.paused
    poses = len(nb.bus.published(TOPIC_POSE))
    nb.step(times=10)
    assert nb.base.goal is None and len(nb.bus.published(TOPIC_POSE)) > poses
    nb.agent.on_command(command(CommandKind.RESUME))
    assert nb.base.goal == (10.0, 0.0)
    nb.base.arrive()
    assert nb.step() == "idle"
    # A task added to an idle robot: it plans again; a command for another robot is
    # not its business.
    nb.agent.on_command(command(CommandKind.ADD, "robot_2", task=task("x", 1.0, 1.0)))
    assert nb.step() == "idle"
    nb.agent.on_command(command(CommandKind.ADD, task=task("x", 1.0, 1.0)))
    assert nb.step() == "navigating" and nb.base.goal == (1.0, 1.0)
    nb.base.arrive()
    assert nb.step() == "idle"
    # Sent back to a task it did (its status was lost): it does and reports it again.
    nb.agent.on_command(command(CommandKind.REDO, task=task("x", 1.0, 1.0)))
    assert nb.step() == "navigating" and nb.base.goal == (1.0, 1.0)
    nb.base.arrive()
    nb.step()
    done = [s.task_id for s in nb.bus.published(TOPIC_TASK_STATUS) if s.state is TaskState.SUCCESS]
    assert done == ["far", "x", "x"]


def _fields(message: Any) -> dict[str, Any]:
    return {f: getattr(message, f) for f in message.__struct_fields__}


def test_every_nb_transition_is_taken_by_these_tests() -> None:
    """The scenarios above, run again, take every transition of NB's table: a new
    transition without a test makes this fail."""
    taken: list[tuple[str, str]] = []
    for scenario in SCENARIOS:
        harness = Harness(TaskExecutor)
        scenario(harness)
        taken += harness.taken
    missing = untaken(NB_TRANSITIONS, taken)
    assert not missing, missing


SCENARIOS = [
    test_goes_to_the_closest_task_reports_it_once_and_ends_idle,
    test_a_task_with_a_duration_is_executed_that_long,
    test_waits_for_a_task_that_has_not_arrived,
    test_a_failed_navigation_keeps_the_task_and_retries,
    test_a_mate_ahead_heading_at_us_is_a_near_collision_then_we_resume,
    test_an_idle_robot_in_a_mates_way_steps_aside,
    test_a_task_that_depends_on_another_waits_for_its_completion,
    test_operator_commands_change_the_agenda_and_stop_the_robot,
]
