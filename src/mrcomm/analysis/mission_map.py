"""One mission on its map — the robots' paths from start (○) to end (■), the tasks (★:
green when their status reached the assigner, crimson when it did not) and the near
collisions (×) — drawn the same way for ``mrcomm run --plot`` and the report's
trajectory figures. Every robot of any team gets a colour of its own."""

from __future__ import annotations

import colorsys
from collections.abc import Collection, Mapping, Sequence

import numpy as np
from matplotlib import colormaps
from matplotlib.axes import Axes
from matplotlib.colors import to_hex
from matplotlib.lines import Line2D

DONE_COLOUR = "darkgreen"
FAILED_COLOUR = "crimson"
#: Teams larger than this get one legend line for all robots, not one each.
MAX_LEGEND_ROBOTS = 20


def robot_colours(n: int) -> list[str]:
    """``n`` distinct colours: matplotlib's tab10 up to 10 robots (so small teams look
    as before), tab20 up to 20, beyond that a low-discrepancy walk through hue, lightness
    and saturation (hue a golden angle apart, so neighbours in the list contrast); no two
    robots share one."""
    if n <= 10:
        return [to_hex(colormaps["tab10"](i)) for i in range(n)]
    if n <= 20:
        return [to_hex(colormaps["tab20"](i)) for i in range(n)]
    colours: list[str] = []
    seen: set[str] = set()
    i = 0
    while len(colours) < n:
        hue = (i * 0.6180339887) % 1.0
        lightness = 0.32 + 0.36 * ((i * 0.7548776662) % 1.0)
        saturation = 0.55 + 0.4 * ((i * 0.5698402910) % 1.0)
        colour = to_hex(colorsys.hls_to_rgb(hue, lightness, saturation))
        if colour not in seen:  # 24-bit colours: skip the rare rounding twin
            seen.add(colour)
            colours.append(colour)
        i += 1
    return colours


def draw_mission_map(
    ax: Axes,
    occupied: np.ndarray,
    extent: tuple[float, float, float, float],
    tracks: Mapping[str, np.ndarray],
    tasks: Sequence[tuple[str, float, float]],
    failed: Collection[str] = (),
    near_collisions: np.ndarray | None = None,
    starts: Mapping[str, tuple[float, float]] | None = None,
    task_labels: bool = True,
) -> None:
    """Draw the map, each robot's track (an (n, 2) array of x, y; robots in the order
    given), its start (``starts``, else its track's first point) and end, the tasks
    (``failed``: the ids whose status never arrived) and the near collisions (an (n, 2)
    array). The legend shows only what is drawn."""
    ax.imshow(np.where(occupied, 0.2, 1.0), cmap="gray", vmin=0, vmax=1, origin="lower",
              extent=extent, interpolation="nearest")  # fmt: skip
    robots = list(tracks)
    colours = dict(zip(robots, robot_colours(len(robots)), strict=True))
    small = len(robots) > MAX_LEGEND_ROBOTS
    for robot in robots:
        track, colour = tracks[robot], colours[robot]
        start = starts.get(robot) if starts else (tuple(track[0]) if len(track) else None)
        if len(track):
            ax.plot(track[:, 0], track[:, 1], "-", color=colour, lw=0.8 if small else 1.3,
                    label=None if small else robot)  # fmt: skip
            ax.plot(track[-1, 0], track[-1, 1], "s", color=colour, mec="black",
                    ms=3 if small else 5)  # fmt: skip
        if start is not None:
            ax.plot(*start, "o", color=colour, mec="black", ms=3 if small else 6)
    failed = set(failed)
    for task_id, x, y in tasks:
        colour = FAILED_COLOUR if task_id in failed else DONE_COLOUR
        ax.plot(x, y, "*", color=colour, ms=6 if small else 12, mec="black", mew=0.5)
        if task_labels:
            ax.annotate(task_id, (x, y), xytext=(4, 4), textcoords="offset points",
                        fontsize=8, fontweight="bold", color=colour)  # fmt: skip
    if near_collisions is not None and len(near_collisions):
        ax.plot(near_collisions[:, 0], near_collisions[:, 1], "x", color="red", ms=8, mew=2)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_aspect("equal")
    handles = legend_handles(len(robots), small, bool(failed & {t for t, _, _ in tasks}),
                             near_collisions is not None and len(near_collisions) > 0)  # fmt: skip
    ax.legend(handles=[*ax.get_legend_handles_labels()[0], *handles], loc="upper left",
              bbox_to_anchor=(1.01, 1.0), fontsize=8)  # fmt: skip


def legend_handles(robots: int, small: bool, any_failed: bool, any_collision: bool) -> list[Line2D]:
    """The legend entries of what is on the map (after the robots' own lines)."""

    def mark(marker: str, colour: str, label: str, size: float) -> Line2D:
        return Line2D([], [], linestyle="none", marker=marker, color=colour,
                      markeredgecolor="black", markersize=size, label=label)  # fmt: skip

    handles = []
    if small:
        handles.append(Line2D([], [], color="grey", label=f"{robots} robots, a colour each"))
    handles += [mark("o", "grey", "start", 6), mark("s", "grey", "end", 5),
                mark("*", DONE_COLOUR, "task (communicated)", 11)]  # fmt: skip
    if any_failed:
        handles.append(mark("*", FAILED_COLOUR, "task (failed)", 11))
    if any_collision:
        handles.append(Line2D([], [], linestyle="none", marker="x", color="red", mew=2,
                              label="near collision"))  # fmt: skip
    return handles
