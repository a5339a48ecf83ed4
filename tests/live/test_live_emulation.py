"""Live missions over an emulated radio (``mrcomm live --emulate``): every process in
its own network namespace, the world setting each ordered pair's kernel packet drops
from the network model (AH range, SPL) as the robots move, the agents filtering
nothing themselves. LF succeeds; NB loses statuses as in simulation; the kernel's
delivery per pair follows the model's decisions."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission

from .helpers import S1, journal
from .netns import skip_unless_possible
from .test_live_conformance import mrcomm

pytestmark = pytest.mark.slow


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
