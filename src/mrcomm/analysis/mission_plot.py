"""The figure of one mission: the map, start poses, labelled tasks, every robot's
trajectory and where near collisions happened."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib

matplotlib.use("Agg")  # figures are files; never open a window
import matplotlib.pyplot as plt
import numpy as np

from mrcomm.metrics import labels as L

if TYPE_CHECKING:
    from mrcomm.run.result import MissionResult

_COLOURS = plt.get_cmap("tab10")


def save_mission_plot(result: MissionResult, path: Path, fmt: str = "png") -> None:
    scenario = result.scenario
    grid = scenario.grid
    xmin, xmax, ymin, ymax = grid.extent
    width = 12.0
    height = max(4.0, width * (ymax - ymin) / (xmax - xmin) + 1.0)
    fig, ax = plt.subplots(figsize=(width, height))
    ax.imshow(
        np.where(grid.occupied, 0.15, 1.0),
        cmap="gray",
        vmin=0,
        vmax=1,
        origin="lower",
        extent=grid.extent,
        interpolation="nearest",
    )
    for i, robot in enumerate(scenario.robots):
        robot_colour = _COLOURS(i % 10)
        track = np.array([(x, y) for _, x, y in result.trajectories.get(robot.id, [])])
        if len(track):
            ax.plot(track[:, 0], track[:, 1], "-", color=robot_colour, lw=1.4, label=robot.id)
        ax.plot(robot.pose.x, robot.pose.y, "o", color=robot_colour, ms=7, mec="black")
        timeline = result.timelines.get(robot.id)
        if timeline is not None:
            points = [
                (e.data["x"], e.data["y"])
                for e in timeline.events
                if e.label == L.NEAR_COLLISION and "x" in e.data
            ]
            if points:
                pts = np.array(points)
                ax.plot(pts[:, 0], pts[:, 1], "x", color="red", ms=8, mew=2)
    failed = set(result.mission.get("failed_tasks", []))
    for task in scenario.tasks:
        colour = "crimson" if task.task_id in failed else "darkgreen"
        ax.plot(task.x, task.y, "*", color=colour, ms=14, mec="black")
        ax.annotate(
            task.task_id,
            (task.x, task.y),
            xytext=(5, 5),
            textcoords="offset points",
            fontsize=10,
            fontweight="bold",
            color=colour,
        )
    ax.plot([], [], "o", color="grey", mec="black", label="start")
    ax.plot([], [], "*", color="darkgreen", ms=12, mec="black", label="task (communicated)")
    ax.plot([], [], "*", color="crimson", ms=12, mec="black", label="task (failed)")
    ax.plot([], [], "x", color="red", ms=8, mew=2, label="near collision")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_aspect("equal")
    verdict = "successful" if result.mission.get("successful") else "failed"
    ax.set_title(
        f"{result.config.get('label')} · {result.config.get('scenario_name')} · "
        f"seed {result.config.get('seed')} · mission {verdict}"
    )
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=9)
    fig.tight_layout()
    fig.savefig(path, format=fmt, dpi=130)
    plt.close(fig)
