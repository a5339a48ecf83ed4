"""Conformance (issue 7, "must show"): the same S1 missions under ``mrcomm live
--speed 10`` (world and every agent separate processes over Zenoh) and ``mrcomm run``
(simulation) both succeed or fail in the same way and give metrics of the same
magnitude. Live is not bit-identical: it runs in real time."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission

from .helpers import S1

pytestmark = pytest.mark.slow

CASES = {
    "NB": {"network": "ah", "threshold": "ssd", "behaviour": "nb", "spl": 25.0},
    "LF": {"network": "ah", "threshold": "ssd", "behaviour": "lf", "spl": 25.0},
}


def mrcomm(*args: str, timeout: float) -> subprocess.CompletedProcess[str]:
    code = "from mrcomm.cli.main import app; app()"
    return subprocess.run(
        [sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=timeout
    )


def live_run(options: dict[str, Any], record_dir: Path, *extra: str) -> dict[str, Any]:
    args = ["live", str(S1), "--speed", "10", "--json", "--record-dir", str(record_dir)]
    for key, value in options.items():
        args += [f"--{key}", str(value)]
    args += extra
    done = mrcomm(*args, timeout=240)
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout)


def ratio(a: float, b: float) -> float:
    return a / b if b else float("inf")


@pytest.mark.parametrize("name", sorted(CASES))
def test_live_matches_simulation(name: str, tmp_path: Path) -> None:
    options = CASES[name]
    live = live_run(options, tmp_path)
    assert_matches_simulation(live, options)


def assert_matches_simulation(live: dict[str, Any], options: dict[str, Any]) -> None:
    """The live run's summary against the same mission simulated (S1, seeds 1-4)."""
    # A few seeds show what the random loss varies and what distance decides.
    sims = [run_mission(make_config(None, scenario=S1, seed=k, **options)) for k in (1, 2, 3, 4)]
    sim = sims[0].summary()
    assert live["config"]["mode"] == "live" and live["config"]["label"] == sim["config"]["label"]
    s, lv = sim["mission"], live["mission"]
    # Same verdict, same way: success in both, or failure in both where the tasks
    # lost in every simulated run (out of range when reported) are lost live too.
    assert lv["successful"] == s["successful"]
    assert lv["timed_out"] is False and s["timed_out"] is False
    assert lv["tasks_completed"] == s["tasks_completed"] == 7
    failed = [set(r.mission["failed_tasks"]) for r in sims]
    always = set.intersection(*failed)
    assert always <= set(lv["failed_tasks"])
    assert len(lv["failed_tasks"]) <= max(len(f) for f in failed) + 1  # loss adds the rest
    # Same magnitude.
    for key in ("execution_phase_time", "total_movement_time", "total_distance"):
        assert 0.6 < ratio(lv[key], s[key]) < 1.6, (key, lv[key], s[key])
    pose_live, pose_sim = live["messages"]["pose"], sim["messages"]["pose"]
    assert 0.6 < ratio(pose_live["sent"], pose_sim["sent"]) < 1.6
    # SPL 25 %: each receiver drops about a quarter of what it gets, in both modes.
    for counts in (pose_live, pose_sim):
        dropped = counts["dropped_loss"] / (counts["received"] + counts["dropped_loss"])
        assert 0.2 < dropped < 0.3
    # Over loopback Zenoh loses nothing of its own: every pose sent reached every
    # other agent (3 receivers each) and was received or dropped by our model.
    seen = pose_live["received"] + pose_live["dropped_loss"] + pose_live["dropped_range"]
    assert seen >= 0.99 * 3 * pose_live["sent"]
    if options["behaviour"] == "lf":
        assert live["aon"]["total"]["pending"] == 0
        assert lv["role_assignment_time"] > 0
    # The live world checks the judged near collisions against its ground truth too.
    assert lv["near_collisions"] == lv["near_collisions_confirmed"] + lv["near_collisions_false"]
    assert lv["near_collisions_missed"] >= 0
    latency = live["live"]["pose_latency_ms"]
    assert latency["n"] > 1000 and latency["p50"] < 50.0


def test_live_runs_the_parameters_it_records(tmp_path: Path) -> None:
    """``--set behaviour.*`` takes effect in every live agent, as recorded: a pose
    every second sends the simulation's pose count (it used to send the default
    rate, five times as many, while the result recorded ``pose_period: 1.0``)."""
    options = {"network": "wlan", "behaviour": "nb", "seed": 3}
    live = live_run(options, tmp_path / "pose", "--set", "behaviour.pose_period=1.0")
    config = make_config(None, scenario=S1, params={"behaviour": {"pose_period": 1.0}}, **options)
    sim = run_mission(config).summary()
    assert live["config"]["params"] == sim["config"]["params"] == config.params
    sent_live, sent_sim = live["messages"]["pose"]["sent"], sim["messages"]["pose"]["sent"]
    assert abs(ratio(sent_live, sent_sim) - 1.0) < 0.15, (sent_live, sent_sim)
    default = run_mission(make_config(None, scenario=S1, **options)).summary()
    assert default["messages"]["pose"]["sent"] > 3 * sent_live


def test_live_plugin_parameters_take_effect(tmp_path: Path) -> None:
    """The example plugin with ``repeats=4`` sends each status four times live: more
    statuses than NB sends (it used to behave as NB live)."""
    options = {"network": "wlan", "seed": 2}
    nb = live_run({**options, "behaviour": "nb"}, tmp_path / "nb")
    repeat = live_run(
        {**options, "behaviour": "repeat"}, tmp_path / "repeat", "--set", "behaviour.repeats=4"
    )
    sent_nb = nb["messages"]["task_status"]["sent"]
    sent_repeat = repeat["messages"]["task_status"]["sent"]
    assert repeat["mission"]["successful"] and nb["mission"]["successful"]
    assert sent_repeat >= 3 * sent_nb, (sent_repeat, sent_nb)
