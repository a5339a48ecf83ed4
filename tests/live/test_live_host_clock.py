"""Agents stepped on their host's clock (``mrcomm agent --clock host``, ``mrcomm live
--agent-clock host``; issue 7 §3), as on real robots where no world clock exists:

* the clock itself: steps every ``dt`` from the agreed start, no drift, missed steps
  skipped rather than run in a burst;
* a short live mission at speed 1 with every agent on its host's clock succeeds as the
  simulation does;
* an agent keeps stepping (its time advances, its poses keep reaching its team mates)
  while the world's ticks are held back (the world process stopped with SIGSTOP), and
  catches up its base state when they resume;
* bad input: an unknown clock, a host clock with a world not at speed 1.
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
from itertools import pairwise
from pathlib import Path
from typing import Any

import duckdb
import pytest

from mrcomm.errors import InputError
from mrcomm.live.collect import _host_clock, read_journals
from mrcomm.live.host_clock import HostClock, check_world_speed
from mrcomm.live.launcher import LiveTeam
from mrcomm.live.settings import LiveSettings
from mrcomm.net.zenoh_config import make_options
from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission

from .helpers import S1, journal, s1_variant, wait_for

CODE = "from mrcomm.cli.main import app; app()"


class FakeClock:
    def __init__(self) -> None:
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


# -- the clock (fast) ----------------------------------------------------------------------


def test_host_clock_steps_every_dt_from_the_agreed_start_without_drift() -> None:
    mono = FakeClock()
    clock = HostClock(0.1, monotonic=mono, wall=lambda: 1000.0 + mono.t)
    assert not clock.started and not clock.due() and clock.take() is None
    clock.start(2.0)  # the first tick said 2.0: that step is due now
    assert clock.take() == 2.0 and clock.take() is None
    assert clock.until_next() == pytest.approx(0.1)
    steps = []
    for _ in range(1000):  # woken a little late every time: lateness never accumulates
        mono.t += clock.until_next() + 0.003
        now = clock.take()
        assert now is not None
        steps.append(now)
    assert steps[-1] == pytest.approx(102.0)  # 1000 steps of 0.1 s after 2.0
    assert all(b - a == pytest.approx(0.1) for a, b in pairwise(steps))
    assert clock.skipped == 0 and clock.max_late == pytest.approx(0.003)
    # Mission time 102.0 was at monotonic 200.0, i.e. wall 1200.0.
    assert clock.wall_of(102.0) == pytest.approx(1200.0)


def test_host_clock_skips_missed_steps_instead_of_bursting() -> None:
    mono = FakeClock()
    clock = HostClock(0.1, monotonic=mono)
    clock.start(0.0)
    assert clock.take() == 0.0
    mono.t += 0.55  # the process was held up for five and a half steps
    assert clock.take() == 0.5  # straight to the latest due step
    assert clock.take() is None and clock.skipped == 4
    assert clock.until_next() == pytest.approx(0.05)  # back on the schedule of t0
    mono.t += 0.05
    assert clock.take() == 0.6


def test_world_speed_and_clock_names_are_checked() -> None:
    check_world_speed(1.0)
    with pytest.raises(InputError, match="--speed 10"):
        check_world_speed(10.0)
    run = make_config(None, scenario=S1)
    with pytest.raises(InputError, match="needs --speed 1") as err:
        LiveSettings(run, make_options(), Path("."), speed=10.0, agent_clock="host")
    assert err.value.field == "--agent-clock"
    with pytest.raises(InputError, match="did you mean 'host'"):
        LiveSettings(run, make_options(), Path("."), agent_clock="hots")


# -- bad input on the command line (fast) ---------------------------------------------------


def mrcomm(*args: str, timeout: float = 60) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", CODE, *args], capture_output=True, text=True, timeout=timeout
    )


def one_line_error(done: subprocess.CompletedProcess[str], *needles: str) -> None:
    assert done.returncode == 2, (done.returncode, done.stderr[-2000:])
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("mrcomm: error:"), done.stderr
    for needle in needles:
        assert needle in lines[0], lines[0]


def test_cli_host_clock_needs_speed_one(tmp_path: Path) -> None:
    records = tmp_path / "records"
    done = mrcomm(
        "live", str(S1), "--agent-clock", "host", "--speed", "10", "--record-dir", str(records)
    )
    one_line_error(done, "--agent-clock", "needs --speed 1, not 10")
    assert not records.exists()  # refused before anything was written or launched
    one_line_error(mrcomm("live", str(S1), "--agent-clock", "wall"), "--agent-clock", "shared")
    one_line_error(
        mrcomm("agent", str(S1), "--robot", "robot_1", "--clock", "hots"),
        "--clock",
        "did you mean 'host'",
    )


# -- whole missions at speed 1 (slow) -------------------------------------------------------


def near_scenario(directory: Path) -> Path:
    """S1's map, team and start with one near task per robot (round robin: one each):
    a mission of about 24 simulated seconds, short enough to run at speed 1."""
    spots = [(11.0, 14.0), (21.0, 14.0), (18.0, 20.5)]
    tasks = [
        {
            "task_id": str(i),
            "type": "INSPECT",
            "location": {"x": x, "y": y},
            "arrival_time": 0,
            "num_robots": 1,
            "duration": 0,
            "depends": [],
        }
        for i, (x, y) in enumerate(spots, start=1)
    ]
    return s1_variant(directory, "S1-near3", tasks)


def clock_lines(record_dir: Path, process: str) -> list[dict[str, Any]]:
    """The agent's clock lines, each with the pose count of the snapshot it opens."""
    out: list[dict[str, Any]] = []
    for line in journal(record_dir, process):
        if line["k"] == "clock":
            out.append(dict(line))
        elif line["k"] == "counts" and out:
            out[-1]["pose_sent"] = line["agents"][process].get("pose", {}).get("sent", 0)
    return [c for c in out if "pose_sent" in c]


@pytest.mark.slow
def test_live_mission_with_agents_on_host_clocks(tmp_path: Path) -> None:
    scenario = near_scenario(tmp_path)
    records = tmp_path / "records"
    db = tmp_path / "runs.duckdb"
    done = mrcomm(
        "live", str(scenario), "--agent-clock", "host", "--speed", "1", "--max-time", "120",
        "--json", "--record-dir", str(records), "--db", str(db), timeout=150,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    live = json.loads(done.stdout)
    # Stored as a configuration of its own (the agents' clock is part of it), and the
    # record, collected again, says the same.
    stored = live["stored"]
    assert stored["mode"] == "live" and stored["repetition"] == 1
    again = mrcomm("collect", str(records), "--db", str(db), "--json")
    assert again.returncode == 0, again.stderr[-2000:]
    assert json.loads(again.stdout)["stored"]["config_id"] == stored["config_id"]
    con = duckdb.connect(str(db), read_only=True)
    options = con.execute(
        "SELECT options FROM configs WHERE config_id = ?", [stored["config_id"]]
    ).fetchone()
    con.close()
    assert options is not None and json.loads(options[0])["agent_clock"] == "host"
    sim = run_mission(make_config(None, scenario=scenario, max_time=120.0)).summary()
    lv, s = live["mission"], sim["mission"]
    assert lv["successful"] is True and s["successful"] is True
    assert lv["timed_out"] is False and lv["tasks_completed"] == 3
    for key in ("execution_phase_time", "total_distance"):
        assert 0.6 < lv[key] / s[key] < 1.6, (key, lv[key], s[key])
    # Poses at 5 Hz of each robot's own time, as in simulation.
    assert 0.6 < live["messages"]["pose"]["sent"] / sim["messages"]["pose"]["sent"] < 1.6
    for robot in ("robot_1", "robot_2", "robot_3"):
        process = live["live"]["processes"][robot]
        assert process["finished"] == [True]
        host = process["host_clock"]
        assert host is not None, process
        assert host["max_base_age_s"] < 1.0  # the base state kept up with its clock
        # One host: its agent clock and the world's read the same time within the
        # first tick's latency (plus the world's pacing).
        assert abs(process["clock_offset_s"]) < 0.5
        clocks = clock_lines(records, robot)
        assert clocks and all(c["clock"] == "host" for c in clocks)


@pytest.mark.slow
def test_agent_keeps_stepping_while_the_world_is_held_back(tmp_path: Path) -> None:
    run = make_config(None, scenario=near_scenario(tmp_path), max_time=120.0)
    records = tmp_path / "records"
    settings = LiveSettings(run, make_options(), records, speed=1.0, agent_clock="host")
    with LiveTeam(settings) as team:
        team.start()
        world = team.children["world"].process
        wait_for(
            lambda: any(c["sim"] >= 3.0 for c in clock_lines(records, "robot_1")),
            60,
            "the mission to run 3 s",
        )
        world.send_signal(signal.SIGSTOP)  # no tick (and no base state) from now on
        try:
            held = wait_for(
                lambda: next(
                    (c for c in clock_lines(records, "robot_1") if c["base_age"] >= 3.0), None
                ),
                30,
                "robot_1's clock to run 3 s past the last tick",
            )
        finally:
            world.send_signal(signal.SIGCONT)
        last_tick = held["sim"] - held["base_age"]
        during = [c for c in clock_lines(records, "robot_1") if c["sim"] > last_tick + 0.5]
        during = [c for c in during if c["sim"] <= held["sim"]]
        # Its time advanced, a step each dt, and its poses kept going out at 5 Hz ...
        assert len(during) >= 2
        first, last = during[0], during[-1]
        assert last["sim"] - first["sim"] >= 1.9
        assert last["base_age"] - first["base_age"] == pytest.approx(
            last["sim"] - first["sim"], abs=0.05
        )
        assert last["pose_sent"] - first["pose_sent"] >= 4 * (last["sim"] - first["sim"])
        # ... and reached its team mates (on their own clocks) while no tick came.
        heard = [
            line["t"]
            for line in journal(records, "robot_2")
            if line["k"] == "msg" and line["frm"] == "robot_1" and line["topic"] == "pose"
        ]
        assert sum(1 for t in heard if last_tick + 1.0 < t < held["sim"]) >= 5
        # The ticks resume: the base state catches up with the agent's clock.
        wait_for(
            lambda: any(
                c["sim"] > held["sim"] and c["base_age"] < 0.5
                for c in clock_lines(records, "robot_1")
            ),
            30,
            "robot_1's base state to catch up",
        )
        team.wait()
        result, report = team.collect()
    assert result.mission["successful"] is True and result.mission["timed_out"] is False
    assert report["processes"]["robot_1"]["host_clock"]["max_base_age_s"] >= 3.0
    robot_1 = [j for j in read_journals(records) if j.process == "robot_1"]
    assert _host_clock(robot_1) == report["processes"]["robot_1"]["host_clock"]
