"""A loaded scenario plus what every run on it can share (the planner's cost grid), so a
sweep builds it once per process."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from mrcomm.robot.params import RobotParams
from mrcomm.robot.planner import GridPlanner
from mrcomm.world.scenario import Scenario, load_scenario


@dataclass(frozen=True, eq=False)
class SimWorld:
    scenario: Scenario
    robot_params: RobotParams
    planner: GridPlanner

    @classmethod
    def load(cls, scenario_path: Path, robot_params: RobotParams | None = None) -> SimWorld:
        scenario = load_scenario(scenario_path)
        params = robot_params or RobotParams()
        return cls(scenario, params, GridPlanner(scenario.grid, params))
