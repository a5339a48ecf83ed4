"""Fast unit tests of the live pieces: RemoteBase (the Base port over commands and
states), the restart resynchronisation, timeline journalling and its merge."""

from __future__ import annotations

import inspect
import json
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from mrcomm.live.collect import _timeline, read_journals
from mrcomm.live.journal import Journal, TimelineTail
from mrcomm.live.protocol import (
    BaseCommand,
    BaseState,
    Roster,
    SyncReply,
    SyncRequest,
    encoder,
    roster_of,
)
from mrcomm.live.remote_base import RemoteBase
from mrcomm.live.resync import Resync, reply_for
from mrcomm.messaging.messages import TOPIC_ASSIGNMENT, Assignment, Message, TaskSpec, TaskStatus
from mrcomm.metrics.timeline import ACTIVITY, Timeline
from mrcomm.net.zenoh_node import drain
from mrcomm.ports import Base, NavStatus
from mrcomm.world.geometry import Pose


def state(status: str, inc: int, ack: int, x: float = 1.0) -> BaseState:
    return BaseState("robot_1", status, x, 2.0, 0.5, 3.0, 0.4, inc, ack)


def test_remote_base_implements_every_member_of_the_base_port() -> None:
    members = {n for n, _ in inspect.getmembers(Base) if not n.startswith("_")}
    assert members <= set(dir(RemoteBase)), members - set(dir(RemoteBase))


def test_remote_base_reports_the_latest_command_until_the_world_acknowledges_it() -> None:
    sent: list[BaseCommand] = []
    base = RemoteBase("robot_1", 7, Pose(0.0, 0.0, 0.0), sent.append)
    assert base.status is NavStatus.IDLE and base.pose == Pose(0.0, 0.0, 0.0)
    base.update(state("succeeded", 7, 0))  # before any command: the world's view
    assert base.status is NavStatus.SUCCEEDED
    base.navigate_to(5.0, 6.0)
    assert sent[-1] == BaseCommand("robot_1", 7, 1, "goto", 5.0, 6.0)
    base.update(state("succeeded", 7, 0))  # the old goal's success: not ours
    assert base.status is NavStatus.ACTIVE
    base.update(state("succeeded", 3, 5))  # a former incarnation's acknowledgement
    assert base.status is NavStatus.ACTIVE
    base.update(state("aborted", 7, 1, x=4.0))
    assert base.status is NavStatus.ABORTED
    assert (base.pose.x, base.odometry_distance, base.speed) == (4.0, 3.0, 0.4)
    base.cancel()
    assert sent[-1].kind == "cancel" and base.status is NavStatus.IDLE
    assert base.make_plan(1.0, 1.0) is None  # no planner: cannot tell
    assert base.route == ()  # the world does not send the route its base drives


def test_remote_base_plans_on_its_own_map(s1_resources: Any) -> None:
    start = s1_resources.scenario.robots[0].pose
    base = RemoteBase("robot_1", 1, start, lambda c: None, s1_resources.planner)
    route = base.make_plan(22.2, 13.8)
    assert route is not None and len(route) >= 2
    assert abs(route[-1][0] - 22.2) < 0.5 and abs(route[-1][1] - 13.8) < 0.5


class _FakeExecutor:
    def __init__(self) -> None:
        self.robot_id = "robot_1"
        self.incarnation = 9
        self.known_done: set[str] = {"2"}
        self.statuses: list[TaskStatus] = []

    def on_team_status(self, status: TaskStatus) -> None:
        self.statuses.append(status)


class _FakeEndpoint:
    def __init__(self) -> None:
        self.gate: Any = None
        self.injected: list[tuple[str, Message]] = []

    def inject(self, topic: str, message: Message) -> None:
        self.injected.append((topic, message))


def _task(task_id: str, n: int = 1) -> TaskSpec:
    return TaskSpec(task_id, "T", 0.0, 0.0, num_robots=n)


def _assignment(*tasks: TaskSpec) -> Assignment:
    return Assignment(
        sender="assigner",
        incarnation=1,
        seq=0,
        stamp=0.0,
        robot="robot_1",
        tasks=tasks,
        team=("robot_1", "robot_2"),
    )


def test_resync_skips_what_the_team_knows_this_robot_completed() -> None:
    executor, endpoint, requests = _FakeExecutor(), _FakeEndpoint(), []
    resync = Resync(executor, endpoint, lambda: requests.append(1), wait=2.0)  # type: ignore[arg-type]
    resync.start(50.0)
    assert requests == [1] and endpoint.gate is not None
    agenda = _assignment(_task("1"), _task("4"), _task("5", n=2), _task("7"))
    # The assignment broadcast arriving meanwhile is held back (and kept).
    assert endpoint.gate(TOPIC_ASSIGNMENT, agenda) is None
    old = SyncReply("robot_2", "robot_1", 8, (("9", ""),))  # an old incarnation's
    assert resync.on_reply(old, 50.1) == []
    reply = SyncReply("robot_2", "robot_1", 9, (("1", "robot_1"), ("4", ""), ("5", "robot_2")))
    assert resync.on_reply(reply, 50.2) == []  # applied with the assignment, not before
    assert not resync.step(50.5, alive={"robot_2", "robot_3"})  # robot_3 still to answer
    assert resync.step(52.0, alive={"robot_2", "robot_3"})  # the wait is over
    topic, message = endpoint.injected[0]
    assert topic == TOPIC_ASSIGNMENT and isinstance(message, Assignment)
    # 1: robot_1's own; 4: single-robot task done by someone; 5 needs two robots and
    # robot_2's part says nothing of ours; 7: unknown.
    assert [t.task_id for t in message.tasks] == ["5", "7"]
    assert resync.skipped == ["1", "4"]
    assert {s.task_id for s in executor.statuses} == {"1", "4", "5"}
    assert endpoint.gate is None


def test_a_robot_back_from_away_catches_up_with_what_the_team_completed() -> None:
    """Its state stands (no assignment is held back); the completions it lacks are
    learnt as team statuses as the answers come, for the wait after it asked."""
    executor, endpoint, requests = _FakeExecutor(), _FakeEndpoint(), []
    resync = Resync(executor, endpoint, lambda: requests.append(1), wait=2.0)  # type: ignore[arg-type]
    reply = SyncReply("robot_2", "robot_1", 9, (("2", ""), ("5", "robot_2")))
    assert resync.on_reply(reply, 10.0) == []  # nobody asked: ignored
    resync.catch_up(100.0)
    assert requests == [1] and endpoint.gate is None and not resync.active
    assert resync.on_reply(reply, 100.5) == ["5"]  # 2 it knew already
    assert [(s.task_id, s.robot) for s in executor.statuses] == [("5", "robot_2")]
    assert resync.on_reply(SyncReply("robot_2", "robot_1", 9, (("7", ""),)), 103.0) == []
    assert endpoint.injected == [] and not resync.applied


def test_reply_carries_known_tasks_and_the_assigners_agenda() -> None:
    executor = _FakeExecutor()

    assigner = SimpleNamespace(
        incarnation=3,
        team=("robot_1", "robot_2"),
        agenda={"robot_1": [_task("1")], "robot_2": [_task("2")]},
        success_received={("2", "robot_2"): 10.0},
    )
    request = SyncRequest("robot_1", 9)
    reply = reply_for(request, "robot_2", executor, assigner, 60.0)  # type: ignore[arg-type]
    assert reply.to == "robot_1" and reply.to_incarnation == 9
    assert set(reply.done) == {("2", ""), ("2", "robot_2")}
    assert reply.assignment is not None and [t.task_id for t in reply.assignment.tasks] == ["1"]


def test_journalled_timeline_survives_a_kill_and_merges_incarnations(tmp_path: Path) -> None:
    first = Timeline("robot_1")
    journal = Journal(tmp_path / "robot_1.1.jsonl")
    journal.start(process="robot_1", incarnation=1)
    tail = TimelineTail(first, journal)
    first.set_state(ACTIVITY, "init", 0.0)
    tail.flush(0.0)
    first.set_state(ACTIVITY, "moving", 1.0)
    first.event("task_completed", 5.0, task_id="1")
    tail.flush(5.0)
    journal.write("clock", sim=8.0, wall=0.0)
    journal.flush()  # ... and then SIGKILL: no close, no end line
    second = Timeline("robot_1")
    journal2 = Journal(tmp_path / "robot_1.2.jsonl")
    journal2.start(process="robot_1", incarnation=2)
    journal2.write("first_tick", time=10.0, wall=0.0)
    tail2 = TimelineTail(second, journal2)
    second.set_state(ACTIVITY, "moving", 10.0)
    second.close_all(20.0)
    tail2.flush(20.0)
    journal2.write("end", time=20.0)
    journal2.close()
    (tmp_path / "world.1.jsonl").write_text(json.dumps({"k": "start"}) + "\n")
    journals = [j for j in read_journals(tmp_path) if j.process == "robot_1"]
    merged = _timeline("robot_1", journals, end=20.0)
    moving = [(i.start, i.end) for i in merged.intervals if i.label == "moving"]
    assert moving == [(1.0, 8.0), (10.0, 20.0)]  # the killed one closed where it stopped
    assert merged.count("task_completed") == 1


def test_incarnations_never_repeat_even_when_the_clock_steps_back(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Time-ordered, random below the millisecond, and above every journalled one."""
    import time as time_module

    from mrcomm.live.journal import INCARNATION_RANDOM_BITS, journal_path, new_incarnation

    first = new_incarnation(tmp_path, "robot_1")
    assert first >> INCARNATION_RANDOM_BITS == pytest.approx(time_module.time() * 1000, abs=5000)
    assert first < 2**53  # exact in any JSON reader
    journal_path(tmp_path, "robot_1", first).write_text("")
    journal_path(tmp_path, "robot_10", first + 10**9).write_text("")  # another process
    # The clock steps back an hour: the restart still gets a new, larger incarnation.
    now = time_module.time_ns()
    monkeypatch.setattr(time_module, "time_ns", lambda: now - 3600 * 10**9)
    again = new_incarnation(tmp_path, "robot_1")
    assert again == first + 1
    assert new_incarnation(tmp_path, "robot_2") < first  # its own history only
    # Random low bits: many starts in one millisecond are not all alike.
    assert len({new_incarnation(None, "robot_3") for _ in range(50)}) > 40


def test_a_team_holds_back_the_members_it_is_told_to(tmp_path: Path) -> None:
    """``start(hold=...)`` starts every process but those held; an unknown name is an
    error before anything starts."""
    from mrcomm.live.launcher import LiveTeam
    from mrcomm.live.settings import LiveSettings
    from mrcomm.net.zenoh_config import make_options
    from mrcomm.run.config import make_config

    from .helpers import S1

    team = LiveTeam(LiveSettings(make_config(None, scenario=S1), make_options(), tmp_path))
    with pytest.raises(ValueError, match="'robot_9'"):
        team.start(hold=("robot_9",))
    assert team.children == {}
    with team:
        team.start(hold=("robot_2", "robot_3"))
        assert sorted(team.children) == ["robot_1", "world"]
        assert set(team.ports) == set(team.names)  # the held know where to listen


def test_a_roster_answer_that_does_not_decode_names_nobody() -> None:
    """The world's roster names who is present; answers are merged, and one that is not
    a roster (another process answering on the key) counts for nothing."""
    enc = encoder()
    world = enc.encode(Roster({"robot_1": (7,), "robot_2": (3, 9)}))
    other = enc.encode(Roster({"robot_1": (5,)}))
    assert roster_of([world, b"\x00not a roster", other]) == {
        "robot_1": (5, 7),
        "robot_2": (3, 9),
    }
    assert roster_of([]) == {}
    assert roster_of([enc.encode({"present": "everyone"})]) == {}


class _Flood:
    """An inbox that never runs dry (a process flooded on its return from a stop), on a
    clock that advances 10 ms per item handled."""

    def __init__(self) -> None:
        self.now = 0.0
        self.taken = 0
        self.waits: list[float | None] = []

    def poll(self, timeout: float | None) -> Any:
        self.waits.append(timeout)
        return object()

    def handle(self, item: Any) -> bool:
        self.taken += 1
        self.now += 0.01
        return False

    def clock(self) -> float:
        return self.now


def test_draining_a_flood_returns_to_the_heartbeat_in_time() -> None:
    """However many items keep arriving, a drain returns once its time is up, so the
    agent's loop beats (and notices it was away) between drains."""
    flood = _Flood()
    drain(flood.poll, flood.handle, 0.125, flood.clock)
    assert flood.taken == 13  # 0.13 s of handling: the first past 0.125 s ends it
    assert flood.waits[0] == 0.125 and set(flood.waits[1:]) == {None}


def test_a_drain_stops_at_once_when_told_and_when_nothing_comes() -> None:
    items = [1, 2, 3]
    handled: list[Any] = []

    def poll(timeout: float | None) -> Any:
        return items.pop(0) if items else None

    drain(poll, lambda item: handled.append(item) or item == 2, 10.0)
    assert handled == [1, 2] and items == [3]  # the mission ended with item 2
    drain(poll, handled.append, 10.0)  # type: ignore[arg-type]
    assert handled == [1, 2, 3] and items == []  # drained: nothing more came


def test_free_ports_lie_below_the_kernels_ephemeral_range() -> None:
    """A port handed to a process about to listen must not be one the kernel can give
    to any socket that connects meanwhile (the flaky UDP mission start)."""
    import socket

    from mrcomm.live.launcher import free_port

    low = int(Path("/proc/sys/net/ipv4/ip_local_port_range").read_text().split()[0])
    for udp in (False, True):
        ports = {free_port("127.0.0.1", udp=udp) for _ in range(20)}
        assert all(20000 <= p < low for p in ports), ports
        assert len(ports) > 15  # spread out, so two launchers rarely meet
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", 0))  # what a connecting socket gets
        assert sock.getsockname()[1] >= low
