"""Small synthetic maps for the robot tests (rooms, a narrow door, corridors) and a
lock-step loop that drives SimBases the way the simulator does."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from mrcomm.ports import NavStatus
from mrcomm.robot import GridPlanner, RobotParams, SimBase
from mrcomm.world.geometry import Pose
from mrcomm.world.occupancy import OccupancyGrid

RES = 0.05


def blank(width_m: float, height_m: float) -> np.ndarray:
    """A free map with a one-cell outer wall."""
    occ = np.zeros((round(height_m / RES), round(width_m / RES)), dtype=bool)
    occ[0, :] = occ[-1, :] = True
    occ[:, 0] = occ[:, -1] = True
    return occ


def fill(occ: np.ndarray, x0: float, y0: float, x1: float, y1: float, value: bool = True) -> None:
    """Set the rectangle [x0, x1) x [y0, y1) (metres) to ``value``."""
    occ[round(y0 / RES) : round(y1 / RES), round(x0 / RES) : round(x1 / RES)] = value


def two_rooms(door: float = 0.8) -> OccupancyGrid:
    """10 m x 5 m, a 0.1 m wall at x = 5 with one door of width ``door`` centred at
    y = 2.5 (the only way between the rooms)."""
    occ = blank(10.0, 5.0)
    fill(occ, 5.0, 0.0, 5.1, 5.0)
    fill(occ, 5.0, 2.5 - door / 2, 5.1, 2.5 + door / 2, False)
    return OccupancyGrid(occ, RES)


def sealed_rooms() -> OccupancyGrid:
    """Two rooms with no door between them."""
    occ = blank(10.0, 5.0)
    fill(occ, 5.0, 0.0, 5.1, 5.0)
    return OccupancyGrid(occ, RES)


def ring() -> OccupancyGrid:
    """12 m x 6 m box with a 10 m x 3 m block in the middle: a 1 m wide corridor all
    round it (two routes between the left and the right end)."""
    occ = blank(12.0, 6.0)
    fill(occ, 1.5, 1.5, 10.5, 4.5)
    return OccupancyGrid(occ, RES)


def dead_end() -> OccupancyGrid:
    """A 1 m wide corridor, 10 m long, closed at both ends (only one route)."""
    occ = blank(10.0, 3.0)
    fill(occ, 0.0, 0.0, 10.0, 1.0)
    fill(occ, 0.0, 2.0, 10.0, 3.0)
    return OccupancyGrid(occ, RES)


def make_base(
    grid: OccupancyGrid,
    start: tuple[float, float, float],
    seed: int = 0,
    robot_id: str = "robot_1",
    planner: GridPlanner | None = None,
    params: RobotParams | None = None,
) -> SimBase:
    params = params or RobotParams()
    planner = planner or GridPlanner(grid, params)
    return SimBase(robot_id, grid, planner, Pose(*start), params, np.random.default_rng(seed))


Trace = list[tuple[float, float, float, float, float]]  # t, x, y, v, w (ground truth)


def run(
    bases: list[SimBase],
    duration: float,
    dt: float = 0.1,
    parked: Callable[[float], list[tuple[float, float]]] | None = None,
    stale: bool = False,
    stop_when_done: bool = True,
) -> list[Trace]:
    """Lock-step loop like the simulator's: each base sees the others' true positions
    (as they are when its turn comes, or all from the start of the step if ``stale``)
    plus any ``parked`` robots. Returns one ground-truth trace per base."""
    traces: list[Trace] = [[] for _ in bases]
    steps = round(duration / dt)
    for k in range(steps):
        now = k * dt
        extra = parked(now) if parked else []
        before = [(b.true_pose.x, b.true_pose.y) for b in bases]
        for i, b in enumerate(bases):
            current = before if stale else [(o.true_pose.x, o.true_pose.y) for o in bases]
            others = [p for j, p in enumerate(current) if j != i] + extra
            b.update(dt, now, others)
            tp = b.true_pose
            traces[i].append((now + dt, tp.x, tp.y, b.speed, b.angular_speed))
        if stop_when_done and all(
            b.status is not NavStatus.ACTIVE and b.speed == 0.0 and b.angular_speed == 0.0
            for b in bases
        ):
            break
    return traces
