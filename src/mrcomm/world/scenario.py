"""Scenario and task files: validated, frozen descriptions of a mission.

A scenario file names a map and a task file (paths relative to the scenario file), the
team (robot ids and start poses, in file order) and where the task assigner runs::

    name: S1
    map: ../maps/office.yaml
    tasks: s1_tasks.yaml
    robots:
      - {id: robot_1, pose: {x: 16.3, y: 16.7, theta: -1.2}}
    assigner: {host: robot_1}          # or {kind: base_station, position: {x: .., y: ..}}
                                       # or {kind: virtual}
    robot: {max_v: 0.3, planner_resolution: 0.2}   # optional: the robots' parameters
    one_lane_width: 1.3                # optional: robots queue at narrower passages

``robot`` sets parameters of the team's robots (their defaults are a Turtlebot 2's; the
names and meanings are in docs/ROBOT.md); they are checked where the robots are built.
``one_lane_width`` (m, default 0: none) makes the doors and corridors narrower than it
one-lane passages, where robots queue (world/passages.py, agents/passage_queue.py).

A task file is a list of tasks in MRComm's task format (docs/ARCHITECTURE.md).
:func:`load_scenario` checks the mission is feasible on its map (poses clear of walls,
every task reachable from every start for a robot of the given radius) so a bad file
fails at load time with a one-line :class:`~mrcomm.errors.InputError`, not minutes into a sweep.
"""

from __future__ import annotations

import functools
import graphlib
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
import pydantic
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator
from scipy import ndimage

from mrcomm.errors import InputError
from mrcomm.world.geometry import Pose
from mrcomm.world.mapio import MAX_COORDINATE, load_map
from mrcomm.world.occupancy import OccupancyGrid
from mrcomm.world.tasks import TaskSpec
from mrcomm.world.yamlfile import read_yaml, validation_error

#: Turtlebot 2 footprint radius: the default clearance a pose needs.
ROBOT_RADIUS = 0.18
#: Robot ids become part of live-mode key expressions, so keep them plain.
ID_PATTERN = r"^[A-Za-z0-9_\-]+$"
#: Longest robot id: it names the robot's certificate (X.509 names hold 64 characters,
#: and its pulse's is the id and ``-pulse``).
MAX_ID_LENGTH = 48

Number = Annotated[float, Field(allow_inf_nan=False)]
Coordinate = Annotated[float, Field(allow_inf_nan=False, ge=-MAX_COORDINATE, le=MAX_COORDINATE)]
#: Longest time accepted (s) for a task's arrival or duration (about 30 years).
Duration = Annotated[float, Field(allow_inf_nan=False, ge=0.0, le=1e9)]


class _Model(BaseModel):
    # strict: a YAML string "1.5" where a number belongs is a mistake, not a number.
    model_config = ConfigDict(extra="forbid", frozen=True, strict=True)


def _id_to_str(value: Any) -> Any:
    """YAML reads ``task_id: 1`` as an int; an id is a name, so accept and stringify."""
    if isinstance(value, int) and not isinstance(value, bool):
        return str(value)
    return value


class PointModel(_Model):
    x: Coordinate
    y: Coordinate


class PoseModel(_Model):
    x: Coordinate
    y: Coordinate
    theta: Annotated[float, Field(allow_inf_nan=False, ge=-1e3, le=1e3)] = 0.0


class TaskModel(_Model):
    task_id: str = Field(min_length=1)
    type: str = Field(min_length=1)
    location: PointModel
    arrival_time: Duration = 0.0
    num_robots: int = Field(default=1, ge=1, le=1_000_000)
    duration: Duration = 0.0
    depends: list[str] = Field(default_factory=list)

    @field_validator("task_id", mode="before")
    @classmethod
    def _task_id(cls, value: Any) -> Any:
        return _id_to_str(value)

    @field_validator("depends", mode="before")
    @classmethod
    def _depends(cls, value: Any) -> Any:
        return [_id_to_str(v) for v in value] if isinstance(value, list) else value


class RobotModel(_Model):
    id: str = Field(pattern=ID_PATTERN, max_length=MAX_ID_LENGTH)
    pose: PoseModel


class AssignerModel(_Model):
    kind: Literal["robot", "base_station", "virtual"] = "robot"
    host: str | None = None
    position: PointModel | None = None

    @model_validator(mode="after")
    def _fields_match_kind(self) -> AssignerModel:
        if self.kind == "robot":
            if self.host is None:
                raise ValueError("kind 'robot' needs 'host' (the id of the robot it runs on)")
            if self.position is not None:
                raise ValueError("kind 'robot' takes its position from its host: drop 'position'")
        elif self.kind == "base_station":
            if self.position is None:
                raise ValueError("kind 'base_station' needs 'position' {x, y}")
            if self.host is not None:
                raise ValueError("kind 'base_station' has no 'host'")
        elif self.host is not None or self.position is not None:
            raise ValueError("kind 'virtual' takes neither 'host' nor 'position'")
        return self


class ScenarioModel(_Model):
    name: str = Field(min_length=1)
    description: str = ""
    map: str = Field(min_length=1)
    tasks: str = Field(min_length=1)
    robots: list[RobotModel] = Field(min_length=1)
    assigner: AssignerModel
    robot: dict[str, Number] = Field(default_factory=dict)
    #: Doors and corridors narrower than this (m) are one-lane: robots queue at them.
    one_lane_width: Annotated[float, Field(ge=0, le=100, allow_inf_nan=False)] = 0.0


_TASK_LIST = list[TaskModel]


@functools.cache
def _task_adapter() -> pydantic.TypeAdapter[list[TaskModel]]:
    # Built on first use (no work at import time), then reused.
    return pydantic.TypeAdapter(_TASK_LIST)


@dataclass(frozen=True)
class RobotStart:
    """A team member and where it starts."""

    id: str
    pose: Pose


@dataclass(frozen=True)
class AssignerSpec:
    """Where the task assigner runs: on a robot (``host``), at a fixed base station
    (``position``), or nowhere (``virtual``: never out of range)."""

    kind: Literal["robot", "base_station", "virtual"]
    host: str | None = None
    position: tuple[float, float] | None = None

    def locate(self, robots: Mapping[str, tuple[float, float]]) -> tuple[float, float]:
        """Where the assigner is, given the robots' positions: its host's position, the
        base station's, or NaN for a virtual assigner (no position, never out of range)."""
        if self.kind == "robot" and self.host is not None:
            return robots[self.host]
        if self.kind == "base_station" and self.position is not None:
            return self.position
        return (math.nan, math.nan)


@dataclass(frozen=True)
class Scenario:
    """A loaded, validated mission: map, team, tasks and assigner."""

    name: str
    path: Path
    map_path: Path
    tasks_path: Path
    grid: OccupancyGrid
    robots: tuple[RobotStart, ...]
    tasks: tuple[TaskSpec, ...]
    assigner: AssignerSpec
    description: str = ""
    robot_radius: float = ROBOT_RADIUS
    #: The scenario's ``robot`` section: robot parameters it sets (name, value).
    robot_settings: tuple[tuple[str, float], ...] = ()
    #: Passages of the map narrower than this (m) are one-lane: robots queue at them
    #: (0: none; world/passages.py).
    one_lane_width: float = 0.0

    @property
    def team(self) -> tuple[str, ...]:
        """Robot ids in file order (the round-robin order)."""
        return tuple(r.id for r in self.robots)


def load_tasks(path: str | Path) -> tuple[TaskSpec, ...]:
    """Load and check a task file (MRComm's task format): ids unique, dependencies known and
    acyclic. Map and team checks happen in :func:`load_scenario`."""
    file = Path(path)
    raw = read_yaml(file)
    if raw is None or raw == []:
        raise InputError("no tasks: expected a list of tasks", file=file)
    if not isinstance(raw, list):
        raise InputError(f"must be a list of tasks, got {type(raw).__name__}", file=file)
    try:
        models = _task_adapter().validate_python(raw)
    except pydantic.ValidationError as err:
        raise validation_error(err, file=file, root=_TASK_LIST) from None
    seen: dict[str, int] = {}
    for i, task in enumerate(models):
        if task.task_id in seen:
            raise InputError(
                f"duplicate task_id '{task.task_id}' (also in [{seen[task.task_id]}])",
                file=file,
                field=f"[{i}].task_id",
            )
        seen[task.task_id] = i
    for i, task in enumerate(models):
        for j, dep in enumerate(task.depends):
            if dep not in seen:
                raise InputError(f"unknown task_id '{dep}'", file=file, field=f"[{i}].depends[{j}]")
            if dep == task.task_id:
                raise InputError(
                    "a task cannot depend on itself", file=file, field=f"[{i}].depends[{j}]"
                )
    sorter = graphlib.TopologicalSorter({t.task_id: t.depends for t in models})
    try:
        sorter.prepare()
    except graphlib.CycleError as err:
        cycle = " -> ".join(str(t) for t in err.args[1])
        raise InputError(f"dependency cycle: {cycle}", file=file, field="depends") from None
    return tuple(
        TaskSpec(
            task_id=t.task_id,
            type=t.type,
            x=float(t.location.x),
            y=float(t.location.y),
            arrival_time=float(t.arrival_time),
            num_robots=t.num_robots,
            duration=float(t.duration),
            depends=tuple(t.depends),
        )
        for t in models
    )


def _resolve(base: Path, name: str) -> Path:
    path = Path(name).expanduser()
    # normpath folds "scenarios/../maps" so messages and records show a clean path.
    return path if path.is_absolute() else Path(os.path.normpath(base.parent / path))


def load_scenario(path: str | Path, *, robot_radius: float | None = None) -> Scenario:
    """Load a scenario file, its map and its task file, and check the mission is
    feasible for robots of ``robot_radius`` (default: the ``radius`` its ``robot``
    section sets, else a Turtlebot 2's). Any problem is a one-line InputError."""
    file = Path(path)
    raw = read_yaml(file)
    if not isinstance(raw, dict):
        raise InputError("must be a mapping (name, map, tasks, robots, assigner)", file=file)
    try:
        model = ScenarioModel.model_validate(raw)
    except pydantic.ValidationError as err:
        raise validation_error(err, file=file, root=ScenarioModel) from None

    ids: dict[str, int] = {}
    for i, robot in enumerate(model.robots):
        if robot.id in ids:
            raise InputError(
                f"duplicate robot id '{robot.id}' (also robots[{ids[robot.id]}])",
                file=file,
                field=f"robots[{i}].id",
            )
        ids[robot.id] = i
    if model.assigner.kind == "robot" and model.assigner.host not in ids:
        raise InputError(
            f"host '{model.assigner.host}' is not a robot of this scenario ({', '.join(ids)})",
            file=file,
            field="assigner.host",
        )

    if robot_radius is None:
        robot_radius = float(model.robot.get("radius", ROBOT_RADIUS))
        if robot_radius <= 0:
            raise InputError(f"must be > 0, got {robot_radius!r}", file=file, field="robot.radius")

    map_path = _resolve(file, model.map)
    if not map_path.is_file():
        raise InputError(f"map file not found: {map_path}", file=file, field="map")
    tasks_path = _resolve(file, model.tasks)
    if not tasks_path.is_file():
        raise InputError(f"task file not found: {tasks_path}", file=file, field="tasks")
    grid = load_map(map_path)
    tasks = load_tasks(tasks_path)

    for i, task in enumerate(tasks):
        if task.num_robots > len(ids):
            raise InputError(
                f"task '{task.task_id}' needs {task.num_robots} robots but the team of "
                f"{file.name} has {len(ids)}",
                file=tasks_path,
                field=f"[{i}].num_robots",
            )

    robots = tuple(
        RobotStart(r.id, Pose(float(r.pose.x), float(r.pose.y), float(r.pose.theta)))
        for r in model.robots
    )
    _check_feasible(grid, robots, tasks, robot_radius, file, tasks_path)

    assigner = AssignerSpec(
        kind=model.assigner.kind,
        host=model.assigner.host,
        position=(
            (float(model.assigner.position.x), float(model.assigner.position.y))
            if model.assigner.position is not None
            else None
        ),
    )
    return Scenario(
        name=model.name,
        path=file,
        map_path=map_path,
        tasks_path=tasks_path,
        grid=grid,
        robots=robots,
        tasks=tasks,
        assigner=assigner,
        description=model.description,
        robot_radius=robot_radius,
        robot_settings=tuple(model.robot.items()),
        one_lane_width=float(model.one_lane_width),
    )


def _placement_problem(grid: OccupancyGrid, x: float, y: float, radius: float) -> str | None:
    """Why a robot of ``radius`` cannot stand at (x, y), or None if it can."""
    if not grid.in_bounds(x, y):
        xmin, xmax, ymin, ymax = grid.extent
        return f"is off the map (x {xmin:g}..{xmax:g}, y {ymin:g}..{ymax:g})"
    if not grid.is_free(x, y):
        return "is inside a wall"
    clearance = grid.clearance(x, y)
    if clearance <= radius:
        return f"is too close to a wall (clearance {clearance:.2f} m, robot radius {radius:g} m)"
    return None


def _check_feasible(
    grid: OccupancyGrid,
    robots: tuple[RobotStart, ...],
    tasks: tuple[TaskSpec, ...],
    radius: float,
    scenario_file: Path,
    tasks_file: Path,
) -> None:
    """Every start and task clear of walls; starts not overlapping; every task in the
    same free region of the radius-inflated grid as every start."""
    for i, robot in enumerate(robots):
        x, y = robot.pose.x, robot.pose.y
        problem = _placement_problem(grid, x, y, radius)
        if problem:
            raise InputError(
                f"{robot.id} start ({x:g}, {y:g}) {problem}",
                file=scenario_file,
                field=f"robots[{i}].pose",
            )
    for i, a in enumerate(robots):
        for b in robots[i + 1 :]:
            gap = math.hypot(a.pose.x - b.pose.x, a.pose.y - b.pose.y)
            if gap < 2 * radius:
                raise InputError(
                    f"{a.id} and {b.id} start {gap:.2f} m apart: footprints "
                    f"(radius {radius:g} m) overlap",
                    file=scenario_file,
                    field=f"robots[{robots.index(b)}].pose",
                )
    for i, task in enumerate(tasks):
        problem = _placement_problem(grid, task.x, task.y, radius)
        if problem:
            raise InputError(
                f"task '{task.task_id}' at ({task.x:g}, {task.y:g}) {problem}",
                file=tasks_file,
                field=f"[{i}].location",
            )
    # 4-connected regions: a path through a diagonal pinch would be no path at all for
    # a planner that forbids corner cutting.
    labels, _ = ndimage.label(~grid.inflated(radius).occupied)
    labels = np.asarray(labels)

    def region(x: float, y: float) -> int:
        return int(labels[grid.world_to_cell(x, y)])

    first = robots[0]
    home = region(first.pose.x, first.pose.y)
    for i, other in enumerate(robots):
        if region(other.pose.x, other.pose.y) != home:
            raise InputError(
                f"{other.id}'s start ({other.pose.x:g}, {other.pose.y:g}) is unreachable "
                f"from {first.id}'s start for a robot of radius {radius:g} m",
                file=scenario_file,
                field=f"robots[{i}].pose",
            )
    for i, task in enumerate(tasks):
        if region(task.x, task.y) != home:
            raise InputError(
                f"task '{task.task_id}' at ({task.x:g}, {task.y:g}) is unreachable from the "
                f"robots' starts (e.g. {first.id} at ({first.pose.x:g}, {first.pose.y:g})) "
                f"for a robot of radius {radius:g} m",
                file=tasks_file,
                field=f"[{i}].location",
            )


__all__ = [
    "ROBOT_RADIUS",
    "AssignerSpec",
    "RobotStart",
    "Scenario",
    "load_scenario",
    "load_tasks",
]
