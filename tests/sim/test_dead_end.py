"""A robot parked in a dead end past a mate's goal (S1's task 7, the corridor's east
end, narrowing to a point): the mate holds before its goal for the parked robot, whose
every step aside leads past the mate. Before the occupied-goal breaker the two waited
for each other until the mission's time limit (seeds 2 and 3, NB and LF alike; seen
live too). Now the mate arrives before its taken goal after the breaker's timeout."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from mrcomm.metrics import labels as L
from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission

ROOT = Path(__file__).resolve().parents[2]
TASK_7 = {"x": 47.1, "y": 3.9}  # S1's task 7


def dead_end(directory: Path) -> Path:
    task = {"task_id": "7", "type": "SENSOR_SWEEP", "location": TASK_7, "arrival_time": 0,
            "num_robots": 1, "duration": 0, "depends": []}  # fmt: skip
    (directory / "dead_end_tasks.yaml").write_text(yaml.safe_dump([task]))
    scenario = {
        "name": "dead_end",
        "description": "robot_1 drives to task 7; robot_2 stands past it, robot_3 behind",
        "map": str(ROOT / "data" / "maps" / "office.yaml"),
        "tasks": "dead_end_tasks.yaml",
        "robots": [
            {"id": "robot_1", "pose": {"x": 46.95, "y": 4.05, "theta": -0.8}},
            {"id": "robot_2", "pose": {"x": 47.32, "y": 3.57, "theta": 2.3}},
            {"id": "robot_3", "pose": {"x": 47.0, "y": 5.4, "theta": -1.5}},
        ],
        "assigner": {"host": "robot_1"},
    }
    path = directory / "dead_end.yaml"
    path.write_text(yaml.safe_dump(scenario))
    return path


@pytest.mark.parametrize("behaviour", ["nb", "lf"])
@pytest.mark.parametrize("seed", [2, 3])
def test_a_robot_arrives_before_the_goal_a_parked_mate_holds(
    tmp_path: Path, behaviour: str, seed: int
) -> None:
    options = {"scenario": dead_end(tmp_path), "seed": seed, "network": "wlan", "spl": 0,
               "behaviour": behaviour, "max_time": 200}  # fmt: skip
    run = run_mission(make_config(None, **options))
    assert run.mission["successful"] and not run.mission["timed_out"]
    events = [e for e in run.timelines["robot_1"].events if e.label == L.GOAL_OCCUPIED]
    assert [(e.data["task_id"], e.data["mate"]) for e in events] == [("7", "robot_2")]
    arrived = next(e for e in run.timelines["robot_1"].events if e.label == L.ARRIVED)
    assert 10.0 <= arrived.time <= 15.0  # the breaker's 10 s after robot_1 stopped
    # Without the breaker (a timeout beyond the mission) robot_2 squeezes past robot_1
    # in the end, crawling at its hold distance: 90 s and more (it waited for good
    # before the planner left a snapped start cell open, see tests/robot/test_office).
    never = {"behaviour": {"occupied_goal": {"timeout": 1000.0}}}
    stuck = run_mission(make_config(None, **options, params=never))
    assert stuck.mission["successful"] and stuck.sim_time_s > 60.0
