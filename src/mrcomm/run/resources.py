"""A loaded scenario plus what every run on it can share (the planner's cost grid,
signal lookup tables, RSSI traces), so a sweep builds each once per process."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from mrcomm.errors import InputError
from mrcomm.net.signal.bundled import default_model
from mrcomm.net.signal.svr import load_model
from mrcomm.net.signal.table import RssiTable
from mrcomm.net.signal.trace import RssiTrace
from mrcomm.robot.params import RobotParams
from mrcomm.robot.planner import GridPlanner
from mrcomm.world.occupancy import OccupancyGrid
from mrcomm.world.passages import Passages, find_passages
from mrcomm.world.scenario import Scenario, load_scenario


@dataclass(frozen=True, eq=False)
class ScenarioResources:
    scenario: Scenario
    robot_params: RobotParams
    planner: GridPlanner
    _tables: dict[Path | None, RssiTable] = field(default_factory=dict, repr=False)
    _traces: dict[Path, RssiTrace] = field(default_factory=dict, repr=False)
    _passages: list[Passages] = field(default_factory=list, repr=False)

    @classmethod
    def load(
        cls, scenario_path: Path, robot_params: RobotParams | None = None
    ) -> ScenarioResources:
        """The scenario with its robots' parameters (``robot_params``, else those its
        ``robot`` section sets over the defaults) and their planner."""
        scenario = load_scenario(scenario_path)
        params = robot_params or scenario_robot_params(scenario)
        planner = GridPlanner(scenario.grid, params)
        check_planning_reach(scenario, planner)
        return cls(scenario, params, planner)

    def signal_table(self, model_path: Path | None) -> RssiTable:
        """The SSD lookup table of a signal model file (None: the bundled model)."""
        table = self._tables.get(model_path)
        if table is None:
            model = default_model() if model_path is None else load_model(model_path)
            table = self._tables[model_path] = RssiTable.from_model(model)
        return table

    @property
    def passages(self) -> Passages | None:
        """The map's one-lane passages (narrower than the scenario's
        ``one_lane_width``, wider than a robot), where robots queue; None without."""
        width = self.scenario.one_lane_width
        if width <= 0:
            return None
        if not self._passages:
            grid = self.scenario.grid
            self._passages.append(find_passages(grid, width, 2 * self.robot_params.radius))
        return self._passages[0]

    def rssi_trace(self, path: Path) -> RssiTrace:
        """A recorded RSSI trace for ESD replay."""
        trace = self._traces.get(path)
        if trace is None:
            trace = self._traces[path] = RssiTrace.load(path)
        return trace


def scenario_robot_params(scenario: Scenario) -> RobotParams:
    """The defaults with what the scenario's ``robot`` section sets; a bad name or value
    is a one-line InputError naming the scenario file and ``robot.<name>``."""
    settings = dict(scenario.robot_settings)
    params = RobotParams.from_mapping(settings, file=scenario.path, section="robot")
    if "planner_resolution" in settings:
        # The planning grid is made of whole map cells: say so rather than round.
        cells = params.planner_resolution / scenario.grid.resolution
        if cells < 1 - 1e-9 or abs(cells - round(cells)) > 1e-6:
            raise InputError(
                f"must be a whole multiple of the map's resolution "
                f"({scenario.grid.resolution:g} m), got {params.planner_resolution:g}",
                file=scenario.path,
                field="robot.planner_resolution",
            )
    return params


def check_planning_reach(scenario: Scenario, planner: GridPlanner) -> None:
    """Every start and task in one connected region of the planning grid (A* moves to
    the 8 neighbours). The loader checked this on the map for the robot's radius; a
    planning cell is a block of map cells, free only when all of them are, so a
    passage the map leaves open can be closed on a coarse planning grid."""
    labels, _ = ndimage.label(~planner.blocked, structure=np.ones((3, 3), dtype=bool))

    def region(x: float, y: float) -> int:
        cell = planner.snap(x, y)
        return 0 if cell is None else int(labels[cell])

    first = scenario.robots[0]
    home = region(first.pose.x, first.pose.y)
    points = [(f"robot '{r.id}' starting", r.pose.x, r.pose.y) for r in scenario.robots]
    points += [(f"task '{t.task_id}'", t.x, t.y) for t in scenario.tasks]
    for what, x, y in points:
        if home == 0 or region(x, y) != home:
            raise InputError(
                f"{what} at ({x:g}, {y:g}) cannot be reached from the start of robot "
                f"'{first.id}' on the {planner.resolution:g} m planning grid (a passage is "
                "too narrow for its cells): choose a finer one",
                file=scenario.path,
                field="robot.planner_resolution",
            )


def planning_reach(
    grid: OccupancyGrid, settings: dict[str, float], points: NDArray[np.float64]
) -> NDArray[np.bool_]:
    """Which ``points`` (an (n, 2) array) lie in the largest region of the planning grid
    that robots of this ``robot`` section plan on, judged as :func:`check_planning_reach`
    judges a start or task (its planning cell, or the free one it snaps to): where the
    scenario generator may place them so that the check passes."""
    planner = GridPlanner(grid, RobotParams.from_mapping(dict(settings)))
    blocked = planner.blocked
    labels, _ = ndimage.label(~blocked, structure=np.ones((3, 3), dtype=bool))
    labels = np.asarray(labels)
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    main = int(np.argmax(sizes))
    ox, oy = planner.origin
    iy = np.floor((points[:, 1] - oy) / planner.resolution).astype(np.intp)
    ix = np.floor((points[:, 0] - ox) / planner.resolution).astype(np.intp)
    hc, wc = planner.shape
    inside = (iy >= 0) & (iy < hc) & (ix >= 0) & (ix < wc)
    free = np.zeros(len(points), dtype=bool)
    free[inside] = ~blocked[iy[inside], ix[inside]]
    reached = np.zeros(len(points), dtype=bool)
    reached[free] = labels[iy[free], ix[free]] == main
    for k in np.flatnonzero(~free).tolist():  # (these snap to a free cell, as checked)
        cell = planner.snap(float(points[k, 0]), float(points[k, 1]))
        reached[k] = cell is not None and int(labels[cell]) == main
    return reached


def checked_scenario(path: Path) -> Scenario:
    """Load a scenario and check what its robots need too: its ``robot`` section, and
    that every start and task can be reached on their planning grid (what a sweep, a
    live team or the scenario generator does before anything starts)."""
    scenario = load_scenario(path)
    check_planning_reach(scenario, GridPlanner(scenario.grid, scenario_robot_params(scenario)))
    return scenario
