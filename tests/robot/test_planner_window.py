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
    real = planner_module.astar_cells

    def recording(grid, start, goal):  # type: ignore[no-untyped-def]
        searched.append(grid.shape)
        return real(grid, start, goal)

    monkeypatch.setattr(planner_module, "astar_cells", recording)
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


@pytest.mark.parametrize("seed", [1, 2])
def test_astar_cells_is_pyastar2ds_search(seed: int) -> None:
    """The direct call finds pyastar2d's own path, on a whole grid and on a window of it
    (a slice that is not contiguous in memory), and no path where there is none."""
    import pyastar2d

    rng = np.random.default_rng(seed)
    weights = (1.0 + 3.0 * rng.random((60, 80))).astype(np.float32)
    weights[rng.random((60, 80)) < 0.25] = np.inf
    for grid in (weights, weights[5:55, 10:70]):
        free = np.argwhere(np.isfinite(grid))
        for _ in range(20):
            s, g = (tuple(int(v) for v in free[rng.integers(len(free))]) for _ in range(2))
            ours = planner_module.astar_cells(grid, s, g)
            theirs = pyastar2d.astar_path(grid, s, g, allow_diagonal=True)
            assert (ours is None) == (theirs is None)
            if ours is not None:
                np.testing.assert_array_equal(ours, theirs)
    walled = np.ones((5, 5), dtype=np.float32)
    walled[:, 2] = np.inf
    assert planner_module.astar_cells(walled, (0, 0), (4, 4)) is None
