"""The planner searches a window of the grid around start and goal; its paths must be
the whole-grid search's, exactly (the window's proof is in ``robot/planner.py``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import mrcomm.robot.planner as planner_module
from mrcomm.robot.planner import GridPlanner
from mrcomm.run.resources import ScenarioResources

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = ROOT / "data" / "scenarios"


def _free_points(
    planner: GridPlanner, rng: np.random.Generator, k: int
) -> list[tuple[float, float]]:
    free = np.argwhere(~planner.blocked)
    cells = free[rng.choice(len(free), size=k, replace=False)]
    return [planner.cell_centre(int(iy), int(ix)) for iy, ix in cells]


def _plans(
    planner: GridPlanner, pairs: list[tuple[tuple[float, float], tuple[float, float]]], mates: list
) -> list[object]:
    out = []
    for (start, goal), near in zip(pairs, mates, strict=True):
        out.append(planner.plan(start, goal))
        out.append(planner.plan(start, goal, near))
    return out


@pytest.mark.parametrize("scenario", ["s1.yaml", "s2/s2.yaml", "s4/s4.yaml"])
def test_window_gives_the_whole_grid_path(scenario: str, monkeypatch: pytest.MonkeyPatch) -> None:
    planner = ScenarioResources.load(SCENARIOS / scenario).planner
    monkeypatch.setattr(planner_module, "WINDOW_FROM_CELLS", 0)  # windows on any grid
    rng = np.random.default_rng(7)
    points = _free_points(planner, rng, 120)
    pairs = list(zip(points[0::2], points[1::2], strict=True))
    # Short hops too: the common re-plan of a few metres around a mate.
    for start in points[:20]:
        goal = (start[0] + rng.uniform(-4, 4), start[1] + rng.uniform(-4, 4))
        pairs.append((start, goal))
    # Mates near the straight line between start and goal, as a re-plan has them.
    mates = []
    for start, goal in pairs:
        t = rng.uniform(0.2, 0.8, size=3)
        mates.append(
            [
                (
                    start[0] + u * (goal[0] - start[0]) + rng.normal(0, 0.3),
                    start[1] + u * (goal[1] - start[1]) + rng.normal(0, 0.3),
                )
                for u in t
            ]
        )
    windowed = _plans(planner, pairs, mates)
    monkeypatch.setattr(planner_module, "WINDOW_FRACTION", 0.0)  # always the whole grid
    whole = _plans(planner, pairs, mates)
    assert windowed == whole
    assert sum(p is not None for p in whole) > len(whole) // 2


def test_a_window_too_small_for_its_path_is_searched_again(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A route that must leave the first window (a long way round a wall) is found in a
    larger one, and it is the whole grid's route."""
    planner = ScenarioResources.load(SCENARIOS / "s2" / "s2.yaml").planner
    monkeypatch.setattr(planner_module, "WINDOW_FROM_CELLS", 0)
    searched: list[tuple[int, int, int, int]] = []
    real = planner_module.pyastar2d.astar_path

    def recording(grid, start, goal, allow_diagonal):  # type: ignore[no-untyped-def]
        searched.append(grid.shape)
        return real(grid, start, goal, allow_diagonal=allow_diagonal)

    monkeypatch.setattr(planner_module.pyastar2d, "astar_path", recording)
    rng = np.random.default_rng(3)
    points = _free_points(planner, rng, 200)
    again = 0
    for start, goal in zip(points[0::2], points[1::2], strict=True):
        searched.clear()
        path = planner.plan(start, goal)
        if len(searched) > 1:
            again += 1
            monkeypatch.setattr(planner_module, "WINDOW_FRACTION", 0.0)
            assert planner.plan(start, goal) == path
            monkeypatch.setattr(planner_module, "WINDOW_FRACTION", 0.5)
    assert again > 0


def test_campus_plans_on_windows_are_the_whole_grid_plans(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The 3000 x 3000 cell campus, where windows are on by default."""
    from mrcomm.robot.params import RobotParams
    from mrcomm.world.scenario import load_scenario

    scenario = load_scenario(SCENARIOS / "campus1000" / "campus1000.yaml")
    planner = GridPlanner(scenario.grid, RobotParams())
    assert planner.shape[0] * planner.shape[1] >= planner_module.WINDOW_FROM_CELLS
    rng = np.random.default_rng(11)
    pairs = []
    for robot in scenario.robots[:24]:
        start = (robot.pose.x, robot.pose.y)
        reach = rng.choice([3.0, 12.0, 40.0])
        goal = (start[0] + rng.uniform(-reach, reach), start[1] + rng.uniform(-reach, reach))
        pairs.append((start, goal))
    mates = [[((s[0] + g[0]) / 2, (s[1] + g[1]) / 2)] for s, g in pairs]
    windowed = _plans(planner, pairs, mates)
    monkeypatch.setattr(planner_module, "WINDOW_FRACTION", 0.0)
    whole = _plans(planner, pairs, mates)
    assert windowed == whole
    assert sum(p is not None for p in whole) > len(whole) // 2
