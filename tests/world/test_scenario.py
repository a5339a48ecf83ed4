"""Scenario and task loading: the happy path and every validation error."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from mrcomm.errors import InputError
from mrcomm.messaging.messages import TaskSpec
from mrcomm.world.geometry import Pose
from mrcomm.world.mapio import save_map
from mrcomm.world.occupancy import OccupancyGrid
from mrcomm.world.scenario import AssignerSpec, RobotStart, load_scenario, load_tasks


def _room_map() -> OccupancyGrid:
    """5 m x 3 m room (walls 0.1 m) with a closed box at x in [3.5, 4.5], y in [1, 2]."""
    occ = np.zeros((60, 100), dtype=np.bool_)
    occ[:2, :] = occ[-2:, :] = occ[:, :2] = occ[:, -2:] = True
    occ[20:42, 70:92] = True
    occ[22:40, 72:90] = False  # the inside of the box: free but unreachable
    return OccupancyGrid(occ, 0.05, (0.0, 0.0))


TASKS: list[dict[str, Any]] = [
    {
        "task_id": "1",
        "type": "SENSOR_SWEEP",
        "location": {"x": 1.0, "y": 2.5},
        "arrival_time": 0,
        "num_robots": 1,
        "duration": 0,
        "depends": [],
    },
    {"task_id": "2", "type": "INSPECT", "location": {"x": 3.0, "y": 0.5}, "depends": ["1"]},
    {"task_id": "3", "type": "INSPECT", "location": {"x": 4.7, "y": 2.7}, "num_robots": 2},
]
SCENARIO: dict[str, Any] = {
    "name": "tiny",
    "map": "maps/room.yaml",
    "tasks": "tasks.yaml",
    "robots": [
        {"id": "robot_1", "pose": {"x": 0.5, "y": 0.5, "theta": 0.3}},
        {"id": "robot_2", "pose": {"x": 1.5, "y": 0.5}},
    ],
    "assigner": {"host": "robot_2"},
}


def _write(tmp_path: Path, scenario: Any = None, tasks: Any = None) -> Path:
    (tmp_path / "maps").mkdir(exist_ok=True)
    save_map(_room_map(), tmp_path / "maps" / "room.yaml")
    scenario = SCENARIO if scenario is None else scenario
    tasks = TASKS if tasks is None else tasks
    (tmp_path / "tasks.yaml").write_text(yaml.safe_dump(tasks, sort_keys=False))
    (tmp_path / "scenario.yaml").write_text(yaml.safe_dump(scenario, sort_keys=False))
    return tmp_path / "scenario.yaml"


def test_loads_scenario(tmp_path: Path) -> None:
    s = load_scenario(_write(tmp_path))
    assert s.name == "tiny"
    assert s.path == tmp_path / "scenario.yaml"
    assert s.map_path == tmp_path / "maps" / "room.yaml"
    assert s.robots == (
        RobotStart("robot_1", Pose(0.5, 0.5, 0.3)),
        RobotStart("robot_2", Pose(1.5, 0.5, 0.0)),
    )
    assert s.team == ("robot_1", "robot_2")
    assert s.assigner == AssignerSpec("robot", host="robot_2")
    assert s.tasks[0] == TaskSpec("1", "SENSOR_SWEEP", 1.0, 2.5, 0.0, 1, 0.0, ())
    assert s.tasks[1].depends == ("1",)
    assert [t.task_id for t in s.tasks] == ["1", "2", "3"]
    assert s.grid.width == 100
    with pytest.raises(AttributeError):
        s.name = "other"  # type: ignore[misc]


@pytest.mark.parametrize(
    ("assigner", "expected"),
    [
        ({"kind": "virtual"}, AssignerSpec("virtual")),
        (
            {"kind": "base_station", "position": {"x": 2, "y": 1.5}},
            AssignerSpec("base_station", position=(2.0, 1.5)),
        ),
        ({"kind": "robot", "host": "robot_1"}, AssignerSpec("robot", host="robot_1")),
    ],
)
def test_assigner_kinds(tmp_path: Path, assigner: dict[str, Any], expected: AssignerSpec) -> None:
    scenario = {**SCENARIO, "assigner": assigner}
    assert load_scenario(_write(tmp_path, scenario)).assigner == expected


def test_load_tasks_alone_and_integer_ids(tmp_path: Path) -> None:
    tasks = copy.deepcopy(TASKS)
    tasks[0]["task_id"] = 1
    tasks[1]["depends"] = [1]
    _write(tmp_path, tasks=tasks)
    loaded = load_tasks(tmp_path / "tasks.yaml")
    assert loaded[0].task_id == "1"
    assert loaded[1].depends == ("1",)
    assert loaded[2].num_robots == 2


def _error(tmp_path: Path, scenario: Any = None, tasks: Any = None) -> InputError:
    path = _write(tmp_path, scenario, tasks)
    with pytest.raises(InputError) as info:
        load_scenario(path)
    assert "\n" not in info.value.one_line()
    return info.value


def _task_error(tmp_path: Path, index: int, **changes: Any) -> InputError:
    tasks = copy.deepcopy(TASKS)
    tasks[index].update(changes)
    return _error(tmp_path, tasks=tasks)


def test_task_location_must_be_a_number(tmp_path: Path) -> None:
    tasks = copy.deepcopy(TASKS)
    tasks[2]["location"] = {"x": "far", "y": 1.0}
    err = _error(tmp_path, tasks=tasks)
    assert (
        err.one_line() == f"{tmp_path / 'tasks.yaml'}: [2].location.x: must be a number, got 'far'"
    )


@pytest.mark.parametrize(
    ("index", "changes", "field", "words"),
    [
        (0, {"durration": 3}, "[0]", "unknown key 'durration' (did you mean 'duration'?)"),
        (1, {"num_robots": 0}, "[1].num_robots", "greater than or equal to 1"),
        (1, {"num_robots": 1.5}, "[1].num_robots", "must be an integer"),
        (1, {"num_robots": 3}, "[1].num_robots", "needs 3 robots but the team"),
        (0, {"duration": -1}, "[0].duration", "greater than or equal to 0"),
        (0, {"arrival_time": -0.5}, "[0].arrival_time", "greater than or equal to 0"),
        (2, {"task_id": "1"}, "[2].task_id", "duplicate task_id '1'"),
        (1, {"depends": ["9"]}, "[1].depends[0]", "unknown task_id '9'"),
        (1, {"depends": ["2"]}, "[1].depends[0]", "cannot depend on itself"),
        (0, {"type": ""}, "[0].type", "must not be empty"),
        (0, {"location": {"x": 1.0}}, "[0].location.y", "required key is missing"),
    ],
)
def test_task_errors(
    tmp_path: Path, index: int, changes: dict[str, Any], field: str, words: str
) -> None:
    err = _task_error(tmp_path, index, **changes)
    assert err.file == str(tmp_path / "tasks.yaml")
    assert err.field == field
    assert words in err.message


def test_dependency_cycle(tmp_path: Path) -> None:
    tasks = copy.deepcopy(TASKS)
    tasks[0]["depends"] = ["2"]
    err = _error(tmp_path, tasks=tasks)
    assert "dependency cycle" in err.message


def test_empty_or_non_list_task_file(tmp_path: Path) -> None:
    assert "no tasks" in _error(tmp_path, tasks=[]).message
    assert "list of tasks" in _error(tmp_path, tasks={"task_id": "1"}).message


@pytest.mark.parametrize(
    ("location", "words"),
    [
        ({"x": 3.55, "y": 1.5}, "is inside a wall"),  # the box's west wall, x in [3.5, 3.6)
        ({"x": 0.2, "y": 1.5}, "too close to a wall (clearance"),
        ({"x": 7.0, "y": 1.5}, "is off the map"),
    ],
)
def test_task_placement_errors(tmp_path: Path, location: dict[str, float], words: str) -> None:
    err = _task_error(tmp_path, 1, location=location)
    assert err.field == "[1].location"
    assert words in err.message
    assert "task '2'" in err.message


def test_task_unreachable(tmp_path: Path) -> None:
    err = _task_error(tmp_path, 2, location={"x": 4.0, "y": 1.5})  # inside the closed box
    assert err.file == str(tmp_path / "tasks.yaml")
    assert err.field == "[2].location"
    assert "task '3'" in err.message and "unreachable" in err.message


def _scenario_error(tmp_path: Path, **changes: Any) -> InputError:
    scenario = copy.deepcopy(SCENARIO)
    scenario.update(changes)
    return _error(tmp_path, scenario)


@pytest.mark.parametrize(
    ("changes", "field", "words"),
    [
        ({"robts": []}, "", "unknown key 'robts' (did you mean 'robots'?)"),
        ({"assigner": {"host": "robot_9"}}, "assigner.host", "not a robot"),
        ({"assigner": {"kind": "cloud"}}, "assigner.kind", "must be one of robot, base_station"),
        ({"assigner": {"kind": "base_station"}}, "assigner", "needs 'position'"),
        ({"assigner": {"kind": "virtual", "host": "robot_1"}}, "assigner", "neither"),
        ({"assigner": {"kind": "robot"}}, "assigner", "needs 'host'"),
        ({"assigner": {"hots": "robot_1"}}, "assigner", "did you mean 'host'"),
        ({"map": "maps/none.yaml"}, "map", "map file not found"),
        ({"tasks": "none.yaml"}, "tasks", "task file not found"),
        ({"robots": []}, "robots", "at least 1"),
        ({"name": 7}, "name", "must be a string, got 7"),
        ({"one_lane_width": -1}, "one_lane_width", "greater than or equal to 0"),
        ({"one_lane_width": "wide"}, "one_lane_width", "must be a number"),
    ],
)
def test_scenario_errors(tmp_path: Path, changes: dict[str, Any], field: str, words: str) -> None:
    err = _scenario_error(tmp_path, **changes)
    assert err.file == str(tmp_path / "scenario.yaml")
    assert (err.field or "") == field
    assert words in err.message


def test_missing_assigner(tmp_path: Path) -> None:
    scenario = {k: v for k, v in SCENARIO.items() if k != "assigner"}
    err = _error(tmp_path, scenario)
    assert err.field == "assigner" and "missing" in err.message


def test_robot_errors(tmp_path: Path) -> None:
    robots = copy.deepcopy(SCENARIO["robots"])
    robots[1]["id"] = "robot_1"
    err = _scenario_error(tmp_path, robots=robots, assigner={"kind": "virtual"})
    assert err.field == "robots[1].id" and "duplicate robot id 'robot_1'" in err.message

    robots = copy.deepcopy(SCENARIO["robots"])
    robots[1]["id"] = "robot 2/x"
    err = _scenario_error(tmp_path, robots=robots, assigner={"kind": "virtual"})
    assert err.field == "robots[1].id" and "must match" in err.message

    robots = copy.deepcopy(SCENARIO["robots"])
    robots[1]["pose"] = {"x": 0.07, "y": 2.0}
    err = _scenario_error(tmp_path, robots=robots)
    assert err.field == "robots[1].pose"
    assert "robot_2 start (0.07, 2)" in err.message and "inside a wall" in err.message

    robots = copy.deepcopy(SCENARIO["robots"])
    robots[1]["pose"] = {"x": 0.7, "y": 0.5}
    err = _scenario_error(tmp_path, robots=robots)
    assert err.field == "robots[1].pose" and "overlap" in err.message

    robots = copy.deepcopy(SCENARIO["robots"])
    robots[1]["pose"] = {"x": 4.0, "y": 1.5}  # inside the closed box
    err = _scenario_error(tmp_path, robots=robots)
    assert err.field == "robots[1].pose" and "unreachable" in err.message

    robots = copy.deepcopy(SCENARIO["robots"])
    robots[0]["pose"]["theta"] = "north"
    err = _scenario_error(tmp_path, robots=robots)
    assert err.field == "robots[0].pose.theta" and "must be a number" in err.message


def test_bad_map_is_reported_against_the_map_file(tmp_path: Path) -> None:
    path = _write(tmp_path)
    (tmp_path / "maps" / "room.yaml").write_text("image: room.pgm\nresolution: 0.05\n")
    with pytest.raises(InputError) as info:
        load_scenario(path)
    assert info.value.file == str(tmp_path / "maps" / "room.yaml")
    assert info.value.field == "origin"


def test_robot_radius_is_a_parameter(tmp_path: Path) -> None:
    tasks = copy.deepcopy(TASKS)
    tasks[1]["location"] = {"x": 3.0, "y": 0.4}  # 0.3 m from the wall (edge 0.1)
    path = _write(tmp_path, tasks=tasks)
    assert len(load_scenario(path).tasks) == 3
    with pytest.raises(InputError, match="too close to a wall"):
        load_scenario(path, robot_radius=0.35)


def test_the_robot_section_sets_the_radius_the_mission_is_checked_for(tmp_path: Path) -> None:
    tasks = copy.deepcopy(TASKS)
    tasks[1]["location"] = {"x": 3.0, "y": 0.4}  # 0.3 m from the wall (edge 0.1)
    scenario = {**SCENARIO, "robot": {"radius": 0.35, "max_v": 0.3}}
    with pytest.raises(InputError, match="too close to a wall"):
        load_scenario(_write(tmp_path, scenario=scenario, tasks=tasks))
    scenario["robot"] = {"radius": 0.15, "max_v": 0.3}
    loaded = load_scenario(_write(tmp_path, scenario=scenario, tasks=tasks))
    assert loaded.robot_radius == 0.15
    assert loaded.robot_settings == (("radius", 0.15), ("max_v", 0.3))
    assert load_scenario(_write(tmp_path)).robot_settings == ()


@pytest.mark.parametrize(
    ("robot", "field", "message"),
    [
        ({"max_v": "fast"}, "robot.max_v", "number"),
        ([1, 2], "robot", "must be a mapping"),
        ({"radius": -0.1}, "robot.radius", "must be > 0"),
    ],
)
def test_a_bad_robot_section_is_a_one_line_error(
    tmp_path: Path, robot: Any, field: str, message: str
) -> None:
    path = _write(tmp_path, scenario={**SCENARIO, "robot": robot})
    with pytest.raises(InputError, match=message) as info:
        load_scenario(path)
    assert info.value.field == field and info.value.file == str(path)
