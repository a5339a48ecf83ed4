"""Faults in live mode (issue 7 §4), each a whole mission of separate processes:

* a robot killed with SIGKILL mid-mission: the rest carries on, the mission ends by its
  time limit, that robot's unfinished tasks count as failed and nothing else is lost;
* a robot restarted after a crash rejoins with a new incarnation, resynchronises and
  resumes its remaining agenda without redoing what the team knows is done;
* with an AON lease, a silent member is reported as left out instead of being waited
  for, and is brought up to date when it returns.
"""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

import pytest
import yaml

from mrcomm.live.launcher import LiveTeam
from mrcomm.live.settings import LiveSettings
from mrcomm.net.zenoh_config import make_options
from mrcomm.run.config import make_config

from .helpers import S1, journal, s1_variant, wait_for

pytestmark = pytest.mark.slow

SPEED = 20.0


def completed(record_dir: Path, robot: str) -> list[str]:
    return [
        str(line["data"]["task_id"])
        for line in journal(record_dir, robot)
        if line.get("k") == "ev" and line.get("label") == "task_completed"
    ]


def assigner_has(record_dir: Path, task: str) -> bool:
    """Whether the task assigner (in whichever process hosts it) received ``task``'s
    success."""
    return any(
        line.get("k") == "status_rx" and line["task_id"] == task and line["state"] == "SUCCESS"
        for line in journal(record_dir, "*")
    )


def team(tmp_path: Path, lease: float | None = None, **run: object) -> LiveTeam:
    config = make_config(None, **{"scenario": S1, **run})
    return LiveTeam(LiveSettings(config, make_options(), tmp_path, speed=SPEED, lease=lease))


# S1 NB missions take 180-190 s simulated: the limit leaves the surviving robots room to
# finish (a live run lags a little behind the simulated clock, and a dead robot is an
# obstacle to drive around) while the killed robot's tasks stay unfinished.
KILL_MISSION_LIMIT = 300.0


def test_killed_robot_leaves_the_team_carrying_on_and_its_tasks_failed(tmp_path: Path) -> None:
    with team(tmp_path, max_time=KILL_MISSION_LIMIT) as t:
        t.start()
        # Killed once the assigner has task 1 (a status still in the dying process's send
        # queue is known to nobody: seen once in a fresh clone's make test).
        wait_for(lambda: assigner_has(tmp_path, "1"), 60, "robot_1's first status")
        t.kill("robot_1", signal.SIGKILL)
        t.wait()
        result, report = t.collect()
    mission = result.mission
    assert mission["timed_out"] is True and mission["end_time"] == pytest.approx(KILL_MISSION_LIMIT)
    assert mission["successful"] is False
    assert result.robots["robot_1"]["failed_tasks"] == ["4", "7"]  # unfinished: failed
    assert result.robots["robot_2"]["failed_tasks"] == []  # the rest carried on
    assert result.robots["robot_3"]["failed_tasks"] == []
    assert result.robots["robot_2"]["tasks_completed"] == 2
    assert result.robots["robot_3"]["tasks_completed"] == 2
    # Nothing else lost: what robot_1 recorded before the kill is in the result.
    assert result.robots["robot_1"]["tasks_completed"] == 1
    assert result.robots["robot_1"]["movement_time"] > 10.0
    assert report["processes"]["robot_1"]["finished"] == [False]
    assert all(report["processes"][r]["finished"] == [True] for r in ("robot_2", "robot_3"))
    # `mrcomm live` exits non-zero on this: a process of the team died.
    assert report["died"] == ["robot_1 killed by signal 9"]


def test_restarted_robot_resyncs_and_does_not_redo_known_tasks(tmp_path: Path) -> None:
    with team(tmp_path, max_time=400.0) as t:
        t.start()
        # Killed once the team knows task 1 is done: a status still in the dying
        # process's send queue is known to nobody, and redoing that task would be right.
        wait_for(lambda: assigner_has(tmp_path, "1"), 60, "robot_1's first status")
        t.kill("robot_1", signal.SIGKILL)
        t.spawn("robot_1")  # a new process: a new incarnation
        t.wait()
        result, report = t.collect()
    process = report["processes"]["robot_1"]
    assert len(process["incarnations"]) == 2
    assert process["incarnations"][0] < process["incarnations"][1]
    assert process["resynced"] == [False, True]
    assert process["finished"] == [False, True]
    assert result.mission["successful"] is True and result.mission["timed_out"] is False
    assert sorted(completed(tmp_path, "robot_1")) == ["1", "4", "7"]  # task 1 only once
    resync = [x for x in journal(tmp_path, "robot_1") if x.get("k") == "resync"]
    assert resync and resync[0]["skipped"] == ["1"]


def test_lease_leaves_a_silent_member_out_and_updates_it_when_it_returns(
    tmp_path: Path,
) -> None:
    with team(tmp_path, behaviour="lf", threshold="slt", max_time=600.0, lease=10.0) as t:
        t.start()
        # Killed once the assigner has task 3 (a status still in the dying process's
        # send queue is known to nobody, and the restarted robot does it again: seen
        # once in a fresh clone's make test, as in the test above).
        wait_for(lambda: assigner_has(tmp_path, "3"), 60, "robot_3's first status")
        t.kill("robot_3", signal.SIGKILL)

        def left_out() -> list[dict[str, object]]:
            return [
                x
                for r in ("robot_1", "robot_2")
                for x in journal(tmp_path, r)
                if x.get("k") == "left_out"
            ]

        # A status sent while robot_3 is gone is, after the lease, reported finished
        # with robot_3 left out (not waited for).
        reports = wait_for(left_out, 120, "a left-out report")
        assert all("robot_3" in x["absent"] for x in reports)  # type: ignore[operator]
        assert all(x["msg"][0] != "robot_3" for x in reports)  # type: ignore[index]
        t.spawn("robot_3")
        t.wait()
        result, _ = t.collect()
    assert result.mission["successful"] is True
    assert sum(a["left_out_reports"] for a in result.aon["agents"].values()) >= 1
    # Brought up to date: nothing pending anywhere at the end.
    assert result.aon["total"]["pending"] == 0
    assert sorted(completed(tmp_path, "robot_3")) == ["3", "6"]


@pytest.mark.parametrize("behaviour", ["nb", "lf"])
def test_a_rogue_peer_publishing_garbage_on_every_topic_takes_no_agent_down(
    tmp_path: Path, behaviour: str
) -> None:
    """A process on the team's network publishes, all mission long, a message of the
    wrong type on every topic under every member's key (a heartbeat on a pose key used
    to kill every agent), statuses and poses in a member's name under its own key,
    undecodable bytes, clock ticks far in the future, not a number, at another speed or
    ending the mission beyond the world's reach: the bus edge and the tick guard refuse
    all of it, counted by cause, no agent dies and the mission succeeds as without it
    (``--insecure``: nothing is authenticated; a forged end tick with a believable time
    cannot be told from the world's without the team's certificates)."""
    import math
    import threading

    import msgspec

    from mrcomm.live.protocol import Tick
    from mrcomm.messaging.messages import Heartbeat, PoseMsg, TaskState, TaskStatus, encode
    from mrcomm.messaging.topics import TOPICS, Lane, lane_of
    from mrcomm.net.zenoh_node import ZenohNode

    stop = threading.Event()
    sent = {"samples": 0, "ticks": 0}

    def attack(node: ZenohNode, members: list[str]) -> None:
        seq = 0
        while not stop.is_set():
            seq += 1
            for topic, spec in TOPICS.items():
                lane = lane_of(topic)
                for member in members:
                    # The wrong type under the member's own key and name.
                    wrong: object = (
                        PoseMsg(sender=member, incarnation=1, seq=seq, stamp=0.0, x=0, y=0, theta=0)
                        if spec.message is Heartbeat
                        else Heartbeat(sender=member, incarnation=1, seq=seq, stamp=0.0)
                    )
                    node.put(node.key(member, topic), encode(wrong), lane)  # type: ignore[arg-type]
                node.put(node.key("evil", topic), b"\xc1 garbage", lane)
            forged = TaskStatus(
                sender="robot_1", incarnation=1, seq=seq, stamp=0.0, robot="robot_1",
                task_id="4", state=TaskState.SUCCESS,
            )  # fmt: skip
            node.put(node.key("evil", "task_status"), encode(forged), lane_of("task_status"))
            # Clock ticks no world can have sent: far in the future (one froze every
            # agent: later genuine ticks looked stale), not a number, at another speed,
            # or ending the mission at a time it cannot have reached.
            ticks = [
                Tick(time=1e9, speed=SPEED, states=()),
                Tick(time=math.inf, speed=SPEED, states=()),
                Tick(time=math.nan, speed=SPEED, states=()),
                Tick(time=1.0, speed=SPEED * 1000, states=()),
                Tick(time=1.0, speed=SPEED, states=(), end=True, end_time=1e9),
            ]
            for fake in ticks:
                node.put(node.key("world", "tick"), msgspec.msgpack.encode(fake), Lane.BEST_EFFORT)
            sent["samples"] += len(TOPICS) * (len(members) + 1) + 1 + len(ticks)
            sent["ticks"] += len(ticks)
            stop.wait(0.05)

    with team(tmp_path, max_time=600.0, behaviour=behaviour) as t:
        t.start()
        wait_for(lambda: "1" in completed(tmp_path, "robot_1"), 60, "robot_1's first task")
        peers = [f"tcp/127.0.0.1:{port}" for port in t.ports.values()]
        rogue = ZenohNode(make_options(team=t.settings.zenoh.team, connect=peers))
        thread = threading.Thread(
            target=attack, args=(rogue, ["robot_1", "robot_2", "robot_3", "assigner"])
        )
        thread.start()
        try:
            t.wait()
        finally:
            stop.set()
            thread.join()
            rogue.close()
        result, report = t.collect()
    assert report["died"] == []
    assert result.mission["successful"] is True and result.mission["timed_out"] is False
    assert sent["samples"] > 1000
    for robot in ("robot_1", "robot_2", "robot_3"):
        refused = report["processes"][robot]["refused"]
        assert refused.get("wrong_type", 0) > 100, (robot, refused)
        assert refused.get("undecodable", 0) > 10, (robot, refused)
        # Every forged tick that reached it is refused. The ticks go best effort, which
        # drops samples under load: a few precede the rogue's links, and on a loaded
        # 2-core VM 627 of 790 and 571 of 715 arrived (79-80 %). A tick let through
        # instead would freeze or end the mission (the assertions above).
        assert refused.get("implausible_tick", 0) > 0.5 * sent["ticks"], (robot, refused, sent)
    # The forged SUCCESS under "evil" reached the assigner's process and was refused.
    assert report["processes"]["robot_2"]["refused"].get("forged_sender", 0) > 10


def _leader(record_dir: Path) -> str | None:
    """The leader of the latest role round any robot took a role in."""
    rounds = [
        (line["time"], line["data"]["leader"])
        for robot in ("robot_1", "robot_2", "robot_3")
        for line in journal(record_dir, robot)
        if line.get("k") == "ev" and line.get("label") == "role_assigned"
    ]
    return max(rounds)[1] if rounds else None


def test_killing_the_lf_leader_lets_its_followers_carry_on(tmp_path: Path) -> None:
    """SIGKILL of the LF leader mid-mission: its followers see its liveliness vanish,
    dissolve the group and carry on among the living; the rest of the team finishes its
    tasks, only the dead leader's fail (they used to wait for it until the time limit)."""
    with team(tmp_path, max_time=900.0, behaviour="lf", network="ah", threshold="slt") as t:
        t.start()
        wait_for(lambda: _leader(tmp_path) is not None, 90, "a leader")
        leader = _leader(tmp_path)
        assert leader is not None
        t.kill(leader, signal.SIGKILL)
        t.wait()
        result, report = t.collect()
    assert report["died"] == [f"{leader} killed by signal 9"]
    others = [r for r in ("robot_1", "robot_2", "robot_3") if r != leader]
    reasons = {
        robot: [
            line["data"].get("reason")
            for line in journal(tmp_path, robot)
            if line.get("k") == "ev" and line.get("label") == "roles_dissolved"
        ]
        for robot in others
    }
    # A follower of the dead leader saw it go (one may have been leading itself).
    assert any("leader's process has gone" in r for r in reasons.values()), reasons
    for robot in others:
        assert result.robots[robot]["failed_tasks"] == [], (robot, result.robots[robot])
    assert result.robots[leader]["failed_tasks"]  # the dead leader's own tasks fail


def _presence(record_dir: Path, agent: str) -> list[bool]:
    """What the world saw of ``agent``'s liveliness, in order."""
    return [
        bool(line["alive"])
        for line in journal(record_dir, "world")
        if line.get("k") == "presence" and line.get("agent") == agent
    ]


#: Wall seconds a SIGSTOP test keeps its robot stopped (the issue's 30 s: three times
#: the default link lease of 10 s, so its mates' links to it are long gone).
STOP_WALL = 30.0


def _mates_saw(record_dir: Path, robot: str, by: str = "robot_1") -> list[bool]:
    """How ``by`` judged ``robot``'s standing (gone: False, back: True), in order."""
    return [
        bool(line["alive"])
        for line in journal(record_dir, by)
        if line.get("k") == "mate" and line.get("agent") == robot
    ]


def _s1_dependent(directory: Path) -> Path:
    """S1 where robot_2's task 5 arrives only at 250 s and robot_3's task 6 depends on
    it: robot_3, done with task 3, waits for task 5 — completed while robot_3 is
    stopped, its status sent once (NB) over links that are down."""
    tasks = yaml.safe_load((S1.parent / "s1_tasks.yaml").read_text())
    for task in tasks:
        if task["task_id"] == "5":
            task["arrival_time"] = 250
        if task["task_id"] == "6":
            task["depends"] = ["5"]
    directory.mkdir()
    return s1_variant(directory, "S1-dependent", tasks)


def test_a_stopped_robot_rejoins_when_continued_and_finishes(tmp_path: Path) -> None:
    """SIGSTOP of robot_3 for 30 s of wall time once it has done task 3 and waits for
    task 5 (robot_2's, which its task 6 depends on), then SIGCONT. Its mates treat it
    as gone (its links' lease runs out: its token vanishes) and as back; task 5 is
    completed meanwhile, its status lost for robot_3 (NB sends it once). Continued,
    robot_3 knows it was away, catches up with what the team completed (it used to wait
    for task 5 until the time limit) and finishes task 6; no process dies."""
    scenario = _s1_dependent(tmp_path / "scenario")
    records = tmp_path / "records"
    with team(records, scenario=scenario, max_time=1500.0) as t:
        t.start()
        wait_for(lambda: "3" in completed(records, "robot_3"), 90, "robot_3's first task")
        pid = t.children["robot_3"].process.pid
        os.kill(pid, signal.SIGSTOP)
        deadline = time.monotonic() + STOP_WALL
        try:
            wait_for(lambda: _mates_saw(records, "robot_3")[-1:] == [False], 30, "it to go")
            wait_for(lambda: "5" in completed(records, "robot_2"), 30, "task 5 done")
            wait_for(lambda: time.monotonic() >= deadline, STOP_WALL, "30 s stopped")
        finally:
            os.kill(pid, signal.SIGCONT)
        wait_for(lambda: _mates_saw(records, "robot_3")[-1:] == [True], 60, "it to come back")
        t.wait()
        result, report = t.collect()
    assert report["died"] == []
    assert sorted(completed(records, "robot_3")) == ["3", "6"]
    lines = journal(records, "robot_3")
    # It knew it had been away, and learnt task 5 from the team's answers.
    away = [line for line in lines if line.get("k") == "away"]
    assert away and away[0]["wall_s"] > 10.0, away
    caught_up = [line for line in lines if line.get("k") == "caught_up"]
    assert caught_up and "5" in caught_up[0]["learnt"], caught_up
    assert result.mission["successful"] is True, result.mission


def test_a_stopped_lf_leader_is_left_and_rejoins_when_continued(tmp_path: Path) -> None:
    """SIGSTOP of the LF leader for 30 s: its followers see it go and dissolve the group
    (as for a dead leader); continued, it comes back, resumes, and every task of the
    team is done — the stopped leader's too."""
    with team(tmp_path, max_time=1500.0, behaviour="lf", network="wlan", threshold="slt") as t:
        t.start()
        wait_for(lambda: _leader(tmp_path) is not None, 90, "a leader")
        leader = _leader(tmp_path)
        assert leader is not None
        pid = t.children[leader].process.pid
        os.kill(pid, signal.SIGSTOP)
        deadline = time.monotonic() + STOP_WALL
        try:
            wait_for(lambda: _presence(tmp_path, leader)[-1:] == [False], 30, "it to go")
            wait_for(lambda: time.monotonic() >= deadline, STOP_WALL, "30 s stopped")
        finally:
            os.kill(pid, signal.SIGCONT)
        wait_for(lambda: _presence(tmp_path, leader)[-1:] == [True], 60, "it to come back")
        t.wait()
        result, report = t.collect()
    assert report["died"] == []
    reasons = [
        line["data"].get("reason", "")
        for robot in ("robot_1", "robot_2", "robot_3")
        if robot != leader
        for line in journal(tmp_path, robot)
        if line.get("k") == "ev" and line.get("label") == "roles_dissolved"
    ]
    assert any("leader's process has gone" in r for r in reasons), reasons
    for mate in ("robot_1", "robot_2", "robot_3"):
        if mate != leader:  # treated as gone while stopped, and as back
            assert _mates_saw(tmp_path, leader, by=mate)[-2:] == [False, True], mate
    assert result.mission["successful"] is True, result.mission
    for robot in ("robot_1", "robot_2", "robot_3"):
        assert result.robots[robot]["failed_tasks"] == [], (robot, result.robots[robot])


def test_a_dead_team_ends_the_live_run_at_once(tmp_path: Path) -> None:
    """Every agent process killed mid-mission: the launcher stops the world within
    seconds (not at the mission's time limit, 30 min at speed 1) and names the first
    process to die and its log."""
    import threading

    from mrcomm.errors import MissionFailed

    config = make_config(None, scenario=S1)
    failure: list[BaseException] = []

    def wait(team: LiveTeam) -> None:
        try:
            team.wait()
        except MissionFailed as err:
            failure.append(err)

    with LiveTeam(LiveSettings(config, make_options(), tmp_path, speed=1.0)) as t:
        t.start()
        wait_for(lambda: journal_has_tick(tmp_path), 60, "the mission's first tick")
        waiting = threading.Thread(target=wait, args=(t,))
        waiting.start()
        t.kill("robot_3", signal.SIGKILL)
        wait_for(lambda: "robot_3" in t.gone, 10, "robot_3 seen dead")
        assert waiting.is_alive()  # two robots left: the mission goes on
        start = time.monotonic()
        for robot in ("robot_1", "robot_2"):
            t.kill(robot, signal.SIGKILL)
        waiting.join(timeout=60)
        waited = time.monotonic() - start
        assert not t.running("world")
    assert len(failure) == 1, failure
    assert waited < 30, waited  # against a mission timeout of more than 1,800 s
    assert t.mission_timeout() > 1800
    message = str(failure[0])
    assert "every agent process has died (3)" in message
    assert "robot_3 killed by signal 9" in message
    assert str(tmp_path / "robot_3.log") in message


def journal_has_tick(record_dir: Path) -> bool:
    return any(line.get("k") == "first_tick" for line in journal(record_dir, "robot_*"))
