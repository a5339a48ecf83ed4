"""What the operator console shows, as plain data taken from a running mission at one
instant (:func:`snapshot`), and drawn as an SVG overlay on the map image (:func:`svg`).

The console shows the team *as the operator knows it* — each robot at its last pose
that reached the operator, with its age (faded when older than :data:`STALE_AFTER`),
each task as the operator heard it (done when its SUCCESS reached the operator) — and,
switchable, the ground truth the simulation has: true positions, what each robot has
completed, whether its status reached the task assigner, and every link's state. So a
lost status is visible: a task the robot has done whose status never arrived.
"""

from __future__ import annotations

import io
import math
from collections.abc import Iterable
from dataclasses import dataclass, field, replace
from html import escape
from typing import TYPE_CHECKING, Any

import numpy as np
from PIL import Image

from mrcomm.experiment.recording_scene import LINK_COLORS, ROBOT_COLORS, link_states
from mrcomm.net.delivery import TopicCounts

if TYPE_CHECKING:
    from mrcomm.agents.operator import Operator
    from mrcomm.sim.mission import Mission
    from mrcomm.world.occupancy import OccupancyGrid

#: A pose older than this (s) is drawn faded: the operator has lost sight of the robot.
STALE_AFTER = 2.0
#: Teams up to this size are drawn with their out-of-range links too.
SMALL_TEAM_LINKS = 4
#: Events the timeline keeps (the newest).
EVENTS_KEPT = 200


@dataclass(frozen=True)
class RobotMark:
    id: str
    known: tuple[float, float, float] | None  # x, y, theta as the operator knows it
    age: float | None  # s since the known pose was sent
    truth: tuple[float, float]
    state: str
    role: str = ""  # as its last pose said (LF roles)
    leader: str = ""  # the robot it follows, as its last pose said


@dataclass(frozen=True)
class TaskMark:
    id: str
    x: float
    y: float
    owner: str  # as the operator knows it
    heard: bool  # its owner's SUCCESS reached the operator
    done: bool  # ground truth: its owner has completed it
    received: bool  # ground truth: its owner's SUCCESS reached the task assigner


@dataclass(frozen=True)
class ConsoleView:
    now: float
    robots: tuple[RobotMark, ...]
    tasks: tuple[TaskMark, ...]
    links: dict[str, str]  # "a-b" -> ok / warning / disconnected (ground truth)
    events: tuple[str, ...]  # the newest
    events_total: int  # how many there have been
    counters: dict[str, dict[str, int]]  # topic -> sent / received / dropped
    commands: tuple[dict[str, Any], ...]
    ended: bool = False
    successful: bool | None = None
    #: Once ended: the result in one line (tasks, execution time, near collisions).
    result: str = ""
    notes: tuple[str, ...] = field(default=())


def snapshot(mission: Mission, operator: Operator, events: list[str]) -> ConsoleView:
    """The console's view of ``mission`` now (call from the thread that steps it): the
    operator's view (:func:`operator_snapshot`) with the simulation's ground truth."""
    counters = counters_of((topic, c) for (_agent, topic), c in mission.network.counts.items())
    view = operator_snapshot(operator, mission.now, events, counters)
    robots = tuple(
        replace(r, truth=(true.x, true.y), state=str(mission.executors[r.id].state))
        for r in view.robots
        for true in [mission.bases[r.id].true_pose]
    )
    received = mission.assigner.success_received
    tasks = tuple(
        replace(t, done=t.id in mission.executors[t.owner].completed,
                received=(t.id, t.owner) in received)
        for t in view.tasks
    )  # fmt: skip
    links = link_states(robots, mission.last_links) if mission.last_links is not None else {}
    return replace(view, robots=robots, tasks=tasks, links=links)


def counters_of(counts: Iterable[tuple[str, TopicCounts]]) -> dict[str, dict[str, int]]:
    """Sent, received and dropped (every cause) per topic, summed over the counts."""
    out: dict[str, dict[str, int]] = {}
    for topic, c in counts:
        total = out.setdefault(topic, {"sent": 0, "received": 0, "dropped": 0})
        total["sent"] += c.sent
        total["received"] += c.received
        total["dropped"] += c.dropped_loss + c.dropped_range + c.dropped_radio + c.dropped_queue
    return dict(sorted(out.items()))


def map_png(grid: OccupancyGrid) -> bytes:
    """The map as a PNG, north up: walls dark, free space white (one pixel per cell)."""
    pixels = np.where(grid.occupied, 60, 255).astype(np.uint8)[::-1]
    out = io.BytesIO()
    Image.fromarray(pixels, mode="L").save(out, format="PNG")
    return out.getvalue()


def _hex(color: tuple[float, float, float, float]) -> str:
    return "#" + "".join(f"{round(c * 255):02x}" for c in color[:3])


class Pixels:
    """Map metres <-> image pixels (row 0 at the top)."""

    def __init__(self, grid: OccupancyGrid) -> None:
        self.x0, self.y0 = grid.origin
        self.scale = 1.0 / grid.resolution
        self.height = grid.height

    def to_px(self, x: float, y: float) -> tuple[float, float]:
        return (x - self.x0) * self.scale, self.height - (y - self.y0) * self.scale

    def to_map(self, px: float, py: float) -> tuple[float, float]:
        return px / self.scale + self.x0, (self.height - py) / self.scale + self.y0


def svg(view: ConsoleView, pixels: Pixels, *, truth: bool, selected_task: str = "") -> str:
    """The overlay: links, tasks, robots (as known; with ``truth`` also where they are)."""
    parts: list[str] = []
    where = {r.id: r.truth for r in view.robots}
    if truth:
        # Out-of-range pairs are drawn only in small teams: in a large one they hide
        # the links that exist.
        few = len(view.robots) <= SMALL_TEAM_LINKS
        for pair, state in view.links.items():
            if state == "disconnected" and not few:
                continue
            a, b = pair.split("-", 1)
            (ax, ay), (bx, by) = pixels.to_px(*where[a]), pixels.to_px(*where[b])
            colour = _hex(LINK_COLORS[state])
            parts.append(
                f'<line id="link-{pair}" data-state="{state}" x1="{ax:.1f}" y1="{ay:.1f}" '
                f'x2="{bx:.1f}" y2="{by:.1f}" stroke="{colour}" stroke-width="2" '
                'stroke-opacity="0.7" />'
            )
    for task in view.tasks:
        px, py = pixels.to_px(task.x, task.y)
        if truth:  # green: the assigner has it; yellow: done, status lost (so far)
            ok, lost = task.received, task.done and not task.received
        else:  # what the operator heard
            ok, lost = task.heard, False
        colour = "#1fa83a" if ok else ("#f0b400" if lost else "#888888")
        stroke = ' stroke="#000" stroke-width="2"' if task.id == selected_task else ""
        parts.append(
            f'<rect id="task-{escape(task.id)}" pointer-events="all" '
            f'data-heard="{str(task.heard).lower()}" data-done="{str(task.done).lower()}" '
            f'data-received="{str(task.received).lower()}" '
            f'x="{px - 7:.1f}" y="{py - 7:.1f}" width="14" height="14" fill="{colour}"{stroke} />'
            f'<text x="{px + 9:.1f}" y="{py + 4:.1f}" font-size="12">{escape(task.id)}</text>'
        )
    known = {r.id: r.known for r in view.robots if r.known is not None}
    for robot in view.robots:  # LF groups: each follower to its leader, as they said
        if robot.leader in known and robot.id in known:
            (fx, fy), (lx, ly) = (pixels.to_px(*known[r][:2]) for r in (robot.id, robot.leader))
            parts.append(
                f'<line id="follows-{robot.id}" x1="{fx:.1f}" y1="{fy:.1f}" x2="{lx:.1f}" '
                f'y2="{ly:.1f}" stroke="#6a3d9a" stroke-width="2" stroke-dasharray="6 3" />'
            )
    for i, robot in enumerate(view.robots):
        colour = _hex(ROBOT_COLORS[i % len(ROBOT_COLORS)])
        if truth:
            tx, ty = pixels.to_px(*robot.truth)
            parts.append(
                f'<circle id="truth-{robot.id}" cx="{tx:.1f}" cy="{ty:.1f}" r="6" '
                f'fill="none" stroke="{colour}" stroke-dasharray="3 2" />'
            )
        if robot.known is None:
            continue
        kx, ky = pixels.to_px(robot.known[0], robot.known[1])
        stale = robot.age is not None and robot.age > STALE_AFTER
        opacity = "0.35" if stale else "1"
        age = f"{robot.age:.1f}" if robot.age is not None else ""
        role = f" · {escape(robot.role)}" if robot.role not in ("", "na") else ""
        parts.append(
            f'<circle id="robot-{robot.id}" data-age="{age}" cx="{kx:.1f}" cy="{ky:.1f}" r="7" '
            f'fill="{colour}" fill-opacity="{opacity}" />'
            f'<text x="{kx + 9:.1f}" y="{ky - 8:.1f}" font-size="12" fill="{colour}" '
            f'fill-opacity="{opacity}">{robot.id}{role}{" (" + age + " s)" if stale else ""}</text>'
        )
    return "".join(parts)


def operator_snapshot(
    operator: Operator, now: float, events: list[str], counters: dict[str, dict[str, int]]
) -> ConsoleView:
    """The console's view where only the operator's knowledge exists (live mode: no
    ground truth in the operator's process)."""
    robots = tuple(
        RobotMark(
            rid,
            (pose.x, pose.y, pose.theta) if pose is not None else None,
            now - pose.stamp if pose is not None else None,
            (pose.x, pose.y) if pose is not None else (math.nan, math.nan),
            "",
            pose.role if pose is not None else "",
            pose.leader if pose is not None else "",
        )
        for rid in operator.robots
        for pose in [operator.poses.get(rid)]
    )
    own = operator.ownership
    tasks = tuple(
        TaskMark(task_id, task.x, task.y, own.owner[task_id],
                 (task_id, own.owner[task_id]) in operator.successes, False, False)
        for task_id, task in own.tasks.items()
    )  # fmt: skip
    return ConsoleView(
        now=now, robots=robots, tasks=tasks, links={}, events=tuple(events[-EVENTS_KEPT:]),
        events_total=len(events), counters=counters,
        commands=tuple(operator.summary()["commands"]),
    )  # fmt: skip
