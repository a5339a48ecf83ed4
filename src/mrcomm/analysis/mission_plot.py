"""The figure of one mission (``mrcomm run --plot``): the map, start poses, labelled
tasks, every robot's trajectory and where near collisions happened."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib

matplotlib.use("Agg")  # figures are files; never open a window
import matplotlib.pyplot as plt
import numpy as np

from mrcomm.analysis.mission_map import draw_mission_map
from mrcomm.metrics import labels as L

if TYPE_CHECKING:
    from mrcomm.run.result import MissionResult


def save_mission_plot(result: MissionResult, path: Path, fmt: str = "png") -> None:
    """``mrcomm run --plot``: the mission on its map (:mod:`mrcomm.analysis.mission_map`)."""
    scenario = result.scenario
    grid = scenario.grid
    xmin, xmax, ymin, ymax = grid.extent
    width = 12.0
    height = max(4.0, width * (ymax - ymin) / (xmax - xmin) + 1.0)
    fig, ax = plt.subplots(figsize=(width, height))
    tracks = {
        robot.id: np.array([(x, y) for _, x, y in result.trajectories.get(robot.id, [])])
        for robot in scenario.robots
    }
    starts = {robot.id: (robot.pose.x, robot.pose.y) for robot in scenario.robots}
    points = [
        (e.data["x"], e.data["y"])
        for timeline in result.timelines.values()
        for e in timeline.events
        if e.label == L.NEAR_COLLISION and "x" in e.data
    ]
    draw_mission_map(
        ax,
        grid.occupied,
        grid.extent,
        tracks,
        [(t.task_id, t.x, t.y) for t in scenario.tasks],
        failed=result.mission.get("failed_tasks", []),
        near_collisions=np.array(points).reshape(-1, 2),
        starts=starts,
        task_labels=len(scenario.tasks) <= 100,
    )
    verdict = "successful" if result.mission.get("successful") else "failed"
    ax.set_title(
        f"{result.config.get('label')} · {result.config.get('scenario_name')} · "
        f"seed {result.config.get('seed')} · mission {verdict}"
    )
    fig.tight_layout()
    fig.savefig(path, format=fmt, dpi=130)
    plt.close(fig)
