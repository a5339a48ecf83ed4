"""``mrcomm scenario make``: a map, a scenario and a task file for any team size.

One seeded generator draws, in a fixed order, the floor plan, the starts and the tasks,
so the same request gives byte-identical files. Everything is written into a staging
directory next to the output and renamed into place once the scenario has loaded with
:func:`~mrcomm.world.scenario.load_scenario` — which checks every start and task is
reachable — so the output exists whole and valid, or not at all::

    DIR/<name>.yaml           the scenario (its header says the command that made it)
    DIR/<name>_tasks.yaml     the tasks, in round-robin order
    DIR/<name>_map.yaml/.png  the map (ROS map_server, trinary)
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray

from mrcomm.errors import InputError
from mrcomm.fileio import atomic_write_text, staged_directory
from mrcomm.world.generate.maps import KINDS
from mrcomm.world.generate.place import (
    START_MODES,
    drivable,
    place_starts,
    place_tasks,
    squared_distance,
)
from mrcomm.world.mapio import save_map
from mrcomm.world.occupancy import OccupancyGrid
from mrcomm.world.scenario import ROBOT_RADIUS, load_scenario

#: Largest side of a generated map (m) and the most robots and tasks in one.
MAX_SIDE = 2000.0
MAX_ROBOTS = 10_000
MAX_TASKS = 100_000
#: Maps up to this area (m²) are drawn at 5 cm, larger ones at 10 cm (memory, file size).
FINE_AREA = 150.0 * 150.0
#: Most cells a generated map may have (500 x 500 m at 10 cm): generating takes ~65
#: bytes a cell at its peak (distance transform, regions), so this is ~1.6 GB.
MAX_CELLS = 25_000_000
TASK_TYPES = ("SENSOR_SWEEP", "INSPECT")
#: The planning grid of every generated scenario's robots (m; the robots' default is
#: 0.1 m): every passage a generator draws stays open at 0.2 m (a 0.9 m door leaves a
#: 0.44 m band of centres 0.23 m from both jambs, which always holds a whole cell), and
#: A* searches a quarter of the cells — the bulk of a large team's planning time (a
#: whole multiple of both map resolutions, 5 and 10 cm).
PLANNING_RESOLUTION = 0.2
#: Maps of at least this area (m²) get route repair (``robot.repair_horizon``,
#: robot/repair.py): on them a route is hundreds of metres long, and searching it all
#: again for each mate met was most of a large team's time. Smaller maps (S2–S4) search
#: whole routes again, as their completion was measured with.
REPAIR_FROM_M2 = 40_000.0
#: How far along its route (m) a robot's repairs rejoin it: five sensing ranges, past
#: any mate it is planning round.
REPAIR_HORIZON = 10.0
#: Generated scenarios make doors and corridors narrower than this one-lane (m): the
#: office's 0.9 m doors, the corridor map's 1 m lane, the campus's 0.9 m inner doors;
#: not the 2 m corridors and 2.6 m aisles, where two robots pass each other, nor the
#: campus's 1.2 m doors (measured between wall cell centres, 1.3 on its 0.1 m cells).
ONE_LANE_WIDTH = 1.3
_SIZE = re.compile(r"^\s*([0-9]+(?:\.[0-9]+)?)\s*[xX]\s*([0-9]+(?:\.[0-9]+)?)\s*$")


@dataclass(frozen=True)
class Request:
    """What to generate (see ``mrcomm scenario make --help``)."""

    kind: str
    width: float
    height: float
    robots: int
    tasks: int
    start: str
    assigner: str
    seed: int
    name: str

    @property
    def resolution(self) -> float:
        return 0.05 if self.width * self.height <= FINE_AREA else 0.1

    def command(self) -> str:
        return (
            f"mrcomm scenario make --map {self.kind} --size {self.width:g}x{self.height:g} "
            f"--robots {self.robots} --tasks {self.tasks} --start {self.start} "
            f"--assigner {self.assigner} --seed {self.seed} --name {self.name}"
        )


def parse_size(text: str) -> tuple[float, float]:
    """``"60x40"`` -> (60.0, 40.0) metres."""
    match = _SIZE.match(text)
    if match is None:
        raise InputError(f"expected WIDTHxHEIGHT in metres, e.g. 60x40, got {text!r}",
                         field="--size")  # fmt: skip
    width, height = float(match.group(1)), float(match.group(2))
    if not (0 < width <= MAX_SIDE and 0 < height <= MAX_SIDE):
        raise InputError(f"each side must be within 0-{MAX_SIDE:g} m, got {text}", field="--size")
    return width, height


def check_request(request: Request) -> None:
    """Every option valid, in one line each, before anything is drawn."""
    if request.kind not in KINDS:
        raise InputError(f"unknown map {request.kind!r}; choose {', '.join(KINDS)}", field="--map")
    smallest = KINDS[request.kind][1]
    if min(request.width, request.height) < smallest:
        raise InputError(
            f"a {request.kind} map needs sides of at least {smallest:g} m", field="--size"
        )
    cells = round(request.width / request.resolution) * round(request.height / request.resolution)
    if cells > MAX_CELLS:
        raise InputError(
            f"{request.width:g}x{request.height:g} m is {cells:,} cells at "
            f"{request.resolution:g} m; at most {MAX_CELLS:,} (e.g. 500x500 m)",
            field="--size",
        )
    if not 1 <= request.robots <= MAX_ROBOTS:
        raise InputError(f"must be 1-{MAX_ROBOTS}, got {request.robots}", field="--robots")
    if not 1 <= request.tasks <= MAX_TASKS:
        raise InputError(f"must be 1-{MAX_TASKS}, got {request.tasks}", field="--tasks")
    if request.start not in START_MODES:
        raise InputError(
            f"unknown start {request.start!r}; choose {', '.join(START_MODES)}", field="--start"
        )
    if not 0 <= request.seed < 2**63:
        raise InputError(f"must be 0 to 2**63-1, got {request.seed}", field="--seed")
    if not re.match(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$", request.name):
        raise InputError(f"{request.name!r} is not a file name stem", field="--name")
    assigner_spec(request.assigner, request.robots, None)


def assigner_spec(text: str, robots: int, base: tuple[float, float] | None) -> dict[str, Any]:
    """``base`` | ``virtual`` | ``robot_K`` -> the scenario's ``assigner`` mapping."""
    if text == "virtual":
        return {"kind": "virtual"}
    if text == "base":
        x, y = base if base is not None else (0.0, 0.0)
        return {"kind": "base_station", "position": {"x": x, "y": y}}
    match = re.match(r"^robot_([0-9]+)$", text)
    if match is None or not 1 <= int(match.group(1)) <= robots:
        raise InputError(
            f"expected base, virtual or robot_K with K in 1..{robots}, got {text!r}",
            field="--assigner",
        )
    return {"kind": "robot", "host": text}


#: Which of the given points (an (n, 2) array) the robots can reach on the map, for a
#: scenario whose ``robot`` section is the mapping: the robots' planning grid.
Reach = Callable[[OccupancyGrid, dict[str, float], NDArray[np.float64]], NDArray[np.bool_]]


def make_scenario(
    request: Request,
    out: Path,
    check: Callable[[Path], object] = load_scenario,
    progress: Callable[[str], None] | None = None,
    reach: Reach | None = None,
) -> Path:
    """Generate and write the scenario into ``out`` (absent or empty); returns the
    scenario file's path. ``check`` loads it before it is moved into place (by default
    the loader: every start and task reachable on the map; callers that know the
    robots pass a check of their planning grid too, and ``reach``, so that starts and
    tasks are placed only where it will pass). ``progress`` is told each stage."""
    check_request(request)
    tell = progress or (lambda _: None)
    with staged_directory(out, "--out") as staging:
        # Drawn and written in a helper so the grid it held is freed before the loader
        # reads the map again (a 300 m campus holds ~1 GB while it is drawn).
        tell(f"drawing the {request.kind} map, placing {request.robots} starts and "
             f"{request.tasks} tasks")  # fmt: skip
        _generate(request, staging, reach)
        tell("checking that every start and task can be reached")
        check(staging / f"{request.name}.yaml")  # reachability: on the map, and as asked
    return out / f"{request.name}.yaml"


def _generate(request: Request, directory: Path, reach: Reach | None) -> None:
    """Draw the plan, then the starts, then the tasks (this order, from one generator:
    the same seed gives the same files) and write them into ``directory``; with
    ``reach``, only on the cells it says the robots reach."""
    rng = np.random.default_rng(request.seed)
    draw, _ = KINDS[request.kind]
    grid = OccupancyGrid(
        draw(request.width, request.height, request.resolution, rng), request.resolution
    )
    cells = drivable(grid, ROBOT_RADIUS)
    usable = None
    if reach is not None and len(cells):
        usable = reach(grid, robot_section(request.width, request.height), cells)
    where = f"on a {request.width:g}x{request.height:g} m {request.kind}"
    starts = place_starts(cells, request.robots, request.start, rng, where, usable)
    headings = rng.uniform(-math.pi, math.pi, size=len(starts))
    tasks = place_tasks(cells, request.tasks, rng, where, usable)
    centre = (request.width / 2, request.height / 2)
    nearest = int(np.argmin(squared_distance(cells, centre)))
    base = (_r(cells[nearest, 0]), _r(cells[nearest, 1]))
    _write(request, directory, grid, starts, headings, tasks, base)


def _r(value: float) -> float:
    """Coordinates to the centimetre (cell centres stay well inside their margin)."""
    return round(float(value), 2)


def _write(
    request: Request,
    directory: Path,
    grid: OccupancyGrid,
    starts: list[tuple[float, float]],
    headings: Any,
    tasks: list[tuple[float, float]],
    base: tuple[float, float],
) -> None:
    name = request.name
    header = (
        f"Generated by: {request.command()}\nEdit the command and re-run it rather than this file."
    )
    # PNG, not PGM (map_server reads both): compressed, a 300 m campus at 10 cm is
    # 9 MB as PGM and a few hundred kB as PNG.
    save_map(grid, directory / f"{name}_map.yaml", image_name=f"{name}_map.png", comment=header)
    task_list = [
        {
            "task_id": str(i + 1),
            "type": TASK_TYPES[i % len(TASK_TYPES)],
            "location": {"x": _r(x), "y": _r(y)},
            "arrival_time": 0,
            "num_robots": 1,
            "duration": 0,
            "depends": [],
        }
        for i, (x, y) in enumerate(tasks)
    ]
    comment = "".join(f"# {line}\n" for line in header.splitlines())
    atomic_write_text(
        directory / f"{name}_tasks.yaml",
        comment + yaml.safe_dump(task_list, sort_keys=False, default_flow_style=None),
    )
    scenario: dict[str, Any] = {
        "name": name.upper() if re.match(r"^s[0-9]+$", name) else name,
        "description": (
            f"{request.kind.capitalize()} {request.width:g} x {request.height:g} m, "
            f"N={request.robots} robots ({request.start} start), T={request.tasks} tasks, "
            "round-robin agenda."
        ),
        "map": f"{name}_map.yaml",
        "tasks": f"{name}_tasks.yaml",
        "robots": [
            {
                "id": f"robot_{i + 1}",
                "pose": {"x": _r(x), "y": _r(y), "theta": round(float(headings[i]), 2)},
            }
            for i, (x, y) in enumerate(starts)
        ],
        "assigner": assigner_spec(request.assigner, request.robots, base),
    }
    scenario["robot"] = robot_section(request.width, request.height)
    scenario["one_lane_width"] = ONE_LANE_WIDTH
    atomic_write_text(
        directory / f"{name}.yaml",
        comment + yaml.safe_dump(scenario, sort_keys=False, default_flow_style=None, width=100),
    )


def robot_section(width: float, height: float) -> dict[str, float]:
    """The ``robot`` section of a generated scenario of this size (m)."""
    robot = {"planner_resolution": PLANNING_RESOLUTION}
    if width * height >= REPAIR_FROM_M2:
        robot["repair_horizon"] = REPAIR_HORIZON
    return robot


def tasks_from_locations(locations: list[tuple[float, float]]) -> str:
    """A task file (YAML text) from a list of locations, in the given order: the
    assigner's round robin gives location i to the (i mod N)-th robot."""
    task_list = [
        {
            "task_id": str(i + 1),
            "type": TASK_TYPES[i % len(TASK_TYPES)],
            "location": {"x": float(x), "y": float(y)},
            "arrival_time": 0,
            "num_robots": 1,
            "duration": 0,
            "depends": [],
        }
        for i, (x, y) in enumerate(locations)
    ]
    return yaml.safe_dump(task_list, sort_keys=False, default_flow_style=None)
