"""A scenario's ``robot`` section: the robots of its runs are built with what it sets
(here a slower top speed and a coarser planning grid), and a bad section is caught
before anything runs."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from mrcomm.errors import InputError
from mrcomm.run.config import make_config
from mrcomm.run.resources import ScenarioResources, checked_scenario
from mrcomm.sim.mission import Mission
from tests.conftest import ROOT, S1_PATH


def s1_with(tmp_path: Path, robot: object) -> Path:
    """S1 with a ``robot`` section, written beside its own map and task file."""
    data = yaml.safe_load(S1_PATH.read_text())
    data["map"] = str((S1_PATH.parent / data["map"]).resolve())
    data["tasks"] = str((S1_PATH.parent / data["tasks"]).resolve())
    data["robot"] = robot
    path = tmp_path / "s1_robot.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def test_the_robots_drive_and_plan_as_the_scenario_says(tmp_path: Path) -> None:
    path = s1_with(tmp_path, {"max_v": 0.25, "planner_resolution": 0.1})
    resources = ScenarioResources.load(path)
    assert resources.robot_params.max_v == 0.25
    assert resources.planner.resolution == pytest.approx(0.1)
    assert ScenarioResources.load(S1_PATH).planner.resolution == pytest.approx(0.1)
    coarse = ScenarioResources.load(s1_with(tmp_path, {"planner_resolution": 0.2}))
    assert coarse.planner.k == 4 and coarse.planner.shape[0] < 0.51 * resources.planner.shape[0]

    def top_speed_and_time(resources: ScenarioResources, scenario: Path) -> tuple[float, float]:
        mission = Mission(make_config(None, scenario=scenario, seed=1), resources)
        fastest = 0.0
        while not mission.done:
            mission.step()
            fastest = max(fastest, *(base.speed for base in mission.bases.values()))
        return fastest, mission.run().mission["execution_phase_time"]

    slow_top, slow_time = top_speed_and_time(resources, path)
    top, time = top_speed_and_time(ScenarioResources.load(S1_PATH), S1_PATH)
    assert slow_top <= 0.25 + 1e-9 < top
    assert slow_time > 1.3 * time


@pytest.mark.parametrize(
    ("robot", "field", "message"),
    [
        ({"max_vel": 0.3}, "robot.max_vel", "unknown robot parameter 'max_vel'.*max_v"),
        ({"max_v": 0}, "robot.max_v", "must be > 0"),
        ({"planner_resolution": 0.12}, "robot.planner_resolution", "whole multiple.*0.05 m"),
        ({"planner_resolution": 0.02}, "robot.planner_resolution", "whole multiple"),
    ],
)
def test_a_bad_robot_parameter_names_the_scenario_and_the_field(
    tmp_path: Path, robot: dict[str, float], field: str, message: str
) -> None:
    path = s1_with(tmp_path, robot)
    for load in (ScenarioResources.load, checked_scenario):
        with pytest.raises(InputError, match=message) as info:
            load(path)
        assert info.value.field == field and info.value.file == str(path)


def test_a_planning_grid_too_coarse_for_the_doors_is_refused(tmp_path: Path) -> None:
    """S1's start room has 0.8 m doors: open on a 0.2 m planning grid, closed on 0.25 m
    cells (whole multiples of its 5 cm map both)."""
    assert ScenarioResources.load(s1_with(tmp_path, {"planner_resolution": 0.2}))
    path = s1_with(tmp_path, {"planner_resolution": 0.25})
    for load in (ScenarioResources.load, checked_scenario):
        with pytest.raises(
            InputError, match=r"cannot be reached from the start of robot 'robot_1'.*0\.25 m"
        ) as info:
            load(path)
        assert info.value.field == "robot.planner_resolution"


def test_run_and_sweep_reject_a_bad_robot_section_before_starting(tmp_path: Path) -> None:
    path = s1_with(tmp_path, {"max_vel": 0.3})
    code = [sys.executable, "-c", "from mrcomm.cli.main import app; app()"]
    out = tmp_path / "out.png"
    run = subprocess.run(
        [*code, "run", str(path), "--plot", str(out)],
        capture_output=True, text=True, cwd=ROOT, timeout=120,
    )  # fmt: skip
    assert run.returncode == 2
    assert run.stderr.strip().count("\n") == 0 and "robot.max_vel" in run.stderr
    assert "Traceback" not in run.stderr and not out.exists()
    experiment = tmp_path / "study.yaml"
    experiment.write_text(
        yaml.safe_dump({"name": "x", "scenario": str(path), "repetitions": 1,
                        "factors": {"network": ["wlan"], "behaviour": ["nb"]}})
    )  # fmt: skip
    db = tmp_path / "study.duckdb"
    sweep = subprocess.run(
        [*code, "sweep", str(experiment), "--db", str(db)],
        capture_output=True, text=True, cwd=ROOT, timeout=120,
    )  # fmt: skip
    assert sweep.returncode == 2, sweep.stderr
    assert "robot.max_vel" in sweep.stderr and "Traceback" not in sweep.stderr
    assert not db.exists()
