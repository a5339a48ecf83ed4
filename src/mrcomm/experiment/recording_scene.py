"""The messages of an MCAP recording, built from plain data: the map as a
``foxglove.Grid``, robot poses as ``foxglove.PoseInFrame``, the 3D scene (robots, tasks,
links coloured by state) as ``foxglove.SceneUpdate``, timeline events as
``foxglove.Log`` — the Foxglove SDK's own message types, which it encodes with their
published schemas — and the JSON schemas of mrcomm's own channels.

Pure functions, no simulator: :mod:`mrcomm.experiment.recording` gathers the data from a
running mission and hands it here with the time of the message (a
:class:`RecordingClock` turns mission seconds into wall-clock time). Everything is in
the ``map`` frame, so Foxglove's 3D panel needs no transforms (set its display frame to
``map``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from foxglove import messages as fg

from mrcomm.net.delivery import OUTCOMES
from mrcomm.net.links import LinkState
from mrcomm.world.geometry import Pose
from mrcomm.world.occupancy import OccupancyGrid

Schema = dict[str, Any]

FRAME = "map"
ROBOT_HEIGHT = 0.3  # m, only for drawing
TASK_SIZE = 0.3  # m, edge of a task cube

Color = tuple[float, float, float, float]

#: Robot colours (cycled); chosen away from the green/orange/red of link and task states.
ROBOT_COLORS: tuple[Color, ...] = (
    (0.12, 0.47, 0.71, 1.0),  # blue
    (0.58, 0.40, 0.74, 1.0),  # purple
    (0.09, 0.75, 0.81, 1.0),  # cyan
    (0.55, 0.34, 0.29, 1.0),  # brown
    (0.89, 0.47, 0.76, 1.0),  # pink
    (0.74, 0.74, 0.13, 1.0),  # olive
    (0.10, 0.10, 0.45, 1.0),  # navy
    (0.40, 0.40, 0.40, 1.0),  # dark grey
)
LINK_COLORS: dict[str, Color] = {
    "ok": (0.10, 0.75, 0.20, 0.9),
    "warning": (1.00, 0.55, 0.00, 0.9),
    "disconnected": (0.90, 0.10, 0.10, 0.9),
}
#: pending: not started; active: some robot's current goal; completed: done by the robot
#: but its status has not reached the assigner (yet); communicated: the assigner has it;
#: failed: the mission ended without the assigner knowing (a failed task).
TASK_COLORS: dict[str, Color] = {
    "pending": (0.60, 0.60, 0.60, 0.8),
    "active": (0.20, 0.50, 1.00, 0.9),
    "completed": (1.00, 0.85, 0.10, 0.9),
    "communicated": (0.10, 0.75, 0.20, 0.9),
    "failed": (0.90, 0.10, 0.10, 0.9),
}
TASK_STATES = tuple(TASK_COLORS)

# Occupancy values of the ROS convention; RGBA makes the 3D panel draw the map as an
# image (dark walls, transparent free space) without any panel settings.
_FREE, _OCCUPIED = 0, 100
_WALL_RGBA = (40, 40, 40, 255)
_FREE_RGBA = (255, 255, 255, 40)


@dataclass(frozen=True)
class RecordingClock:
    """Mission time -> recording time: nanoseconds since the Unix epoch, counted from
    ``epoch_ns`` (the wall-clock time the mission started), so recordings line up
    with other logs of the same day; the mission's own seconds stay in the payloads of
    mrcomm's channels (``t``) and the epoch in the file's metadata."""

    epoch_ns: int = 0

    def ns(self, t: float) -> int:
        return self.epoch_ns + round(t * 1e9)

    def timestamp(self, t: float) -> fg.Timestamp:
        ns = self.ns(t)
        return fg.Timestamp(ns // 1_000_000_000, ns % 1_000_000_000)


def _position(x: float, y: float, z: float = 0.0) -> fg.Vector3:
    return fg.Vector3(x=x, y=y, z=z)


def _point(x: float, y: float, z: float = 0.0) -> fg.Point3:
    return fg.Point3(x=x, y=y, z=z)


def yaw_quaternion(theta: float) -> tuple[float, float, float, float]:
    """(x, y, z, w) of a rotation by ``theta`` about z."""
    half = theta / 2.0
    return (0.0, 0.0, math.sin(half), math.cos(half))


def _pose(x: float, y: float, z: float = 0.0, theta: float = 0.0) -> fg.Pose:
    qx, qy, qz, qw = yaw_quaternion(theta)
    return fg.Pose(position=_position(x, y, z), orientation=fg.Quaternion(x=qx, y=qy, z=qz, w=qw))


def _rgba(color: Color) -> fg.Color:
    return fg.Color(r=color[0], g=color[1], b=color[2], a=color[3])


def robot_color(index: int) -> Color:
    return ROBOT_COLORS[index % len(ROBOT_COLORS)]


# -- map and poses ------------------------------------------------------------------------
GRID_FIELDS = ("occupancy", "red", "green", "blue", "alpha")


def grid_cells(grid: OccupancyGrid) -> np.ndarray:
    """The map's cells, rows from the map origin upwards as in :class:`OccupancyGrid`
    (so no flip): per cell ``occupancy`` (uint8, 0 free / 100 occupied) then ``red,
    green, blue, alpha``."""
    occupied = grid.occupied
    cells = np.empty((*occupied.shape, len(GRID_FIELDS)), dtype=np.uint8)
    cells[..., 0] = np.where(occupied, _OCCUPIED, _FREE)
    cells[..., 1:] = np.where(occupied[..., None], _WALL_RGBA, _FREE_RGBA)
    return cells


def grid_message(grid: OccupancyGrid, when: fg.Timestamp) -> fg.Grid:
    """foxglove.Grid of the occupancy map (:func:`grid_cells`)."""
    stride = len(GRID_FIELDS)
    uint8 = fg.PackedElementFieldNumericType.Uint8
    return fg.Grid(
        timestamp=when,
        frame_id=FRAME,
        pose=_pose(grid.origin[0], grid.origin[1]),
        column_count=grid.width,
        cell_size=fg.Vector2(x=grid.resolution, y=grid.resolution),
        row_stride=grid.width * stride,
        cell_stride=stride,
        fields=[
            fg.PackedElementField(name=n, offset=i, type=uint8) for i, n in enumerate(GRID_FIELDS)
        ],
        data=grid_cells(grid).tobytes(),
    )


def pose_message(when: fg.Timestamp, pose: Pose) -> fg.PoseInFrame:
    """foxglove.PoseInFrame of one robot (true pose, map frame)."""
    return fg.PoseInFrame(
        timestamp=when, frame_id=FRAME, pose=_pose(pose.x, pose.y, 0.0, pose.theta)
    )


# -- the scene ----------------------------------------------------------------------------
class HasId(Protocol):
    @property
    def id(self) -> str: ...


@dataclass(frozen=True)
class RobotView:
    """What the scene shows of one robot."""

    id: str
    pose: Pose
    color: Color
    state: str
    role: str | None = None


@dataclass(frozen=True)
class TaskView:
    id: str
    x: float
    y: float
    state: str  # one of TASK_STATES
    robots: tuple[str, ...] = ()


def link_state(links: LinkState, i: int, j: int) -> str:
    """State of the undirected link i-j: the worse of both directions."""
    if not (links.connected[i, j] and links.connected[j, i]):
        return "disconnected"
    if links.warning[i, j] or links.warning[j, i]:
        return "warning"
    return "ok"


def _entity(
    when: fg.Timestamp, entity_id: str, metadata: Mapping[str, Any], **primitives: Any
) -> fg.SceneEntity:
    return fg.SceneEntity(
        timestamp=when,
        frame_id=FRAME,
        id=entity_id,
        lifetime=fg.Duration(0, 0),  # until replaced
        frame_locked=False,
        metadata=[fg.KeyValuePair(key=k, value=str(v)) for k, v in metadata.items()],
        **primitives,
    )


def _text(x: float, y: float, z: float, text: str, color: Color) -> fg.TextPrimitive:
    return fg.TextPrimitive(
        pose=_pose(x, y, z),
        billboard=True,
        font_size=14.0,
        scale_invariant=True,  # pixels: readable at any zoom
        color=_rgba(color),
        text=text,
    )


def robot_entity(when: fg.Timestamp, robot: RobotView, radius: float) -> fg.SceneEntity:
    p = robot.pose
    label = robot.id if robot.role in (None, "na") else f"{robot.id} ({robot.role})"
    return _entity(
        when,
        f"robot/{robot.id}",
        {"state": robot.state, "role": robot.role or ""},
        cylinders=[
            fg.CylinderPrimitive(
                pose=_pose(p.x, p.y, ROBOT_HEIGHT / 2),
                size=_position(2 * radius, 2 * radius, ROBOT_HEIGHT),
                bottom_scale=1.0,
                top_scale=1.0,
                color=_rgba(robot.color),
            )
        ],
        arrows=[
            fg.ArrowPrimitive(
                pose=_pose(p.x, p.y, ROBOT_HEIGHT + 0.02, p.theta),
                shaft_length=2 * radius,
                shaft_diameter=0.05,
                head_length=0.12,
                head_diameter=0.12,
                color=_rgba((1.0, 1.0, 1.0, 1.0)),
            )
        ],
        texts=[_text(p.x, p.y, ROBOT_HEIGHT + 0.4, label, robot.color)],
    )


def task_entity(when: fg.Timestamp, task: TaskView) -> fg.SceneEntity:
    color = TASK_COLORS[task.state]
    return _entity(
        when,
        f"task/{task.id}",
        {"state": task.state, "robots": ",".join(task.robots)},
        cubes=[
            fg.CubePrimitive(
                pose=_pose(task.x, task.y, TASK_SIZE / 2),
                size=_position(TASK_SIZE, TASK_SIZE, TASK_SIZE),
                color=_rgba(color),
            )
        ],
        texts=[_text(task.x, task.y, TASK_SIZE + 0.3, f"task {task.id}", color)],
    )


def link_states(robots: Sequence[HasId], links: LinkState) -> dict[str, str]:
    """State of every robot pair ``"a-b"`` (robots are the first rows of ``links``,
    in team order)."""
    return {
        f"{a.id}-{robots[j].id}": link_state(links, i, j)
        for i, a in enumerate(robots)
        for j in range(i + 1, len(robots))
    }


def links_entity(
    when: fg.Timestamp, robots: Sequence[RobotView], links: LinkState
) -> fg.SceneEntity:
    """One line per robot pair, coloured by link state (green ok, orange warning, red
    disconnected)."""
    states = link_states(robots, links)
    where = {r.id: r.pose for r in robots}
    lines = []
    for pair, state in states.items():
        a, b = (where[r] for r in pair.split("-", 1))
        lines.append(
            fg.LinePrimitive(
                type=fg.LinePrimitiveLineType.LineStrip,
                pose=_pose(0.0, 0.0),
                thickness=3.0,
                scale_invariant=True,
                points=[_point(a.x, a.y, ROBOT_HEIGHT), _point(b.x, b.y, ROBOT_HEIGHT)],
                color=_rgba(LINK_COLORS[state]),
            )
        )
    return _entity(when, "links", states, lines=lines)


def scene_update(
    when: fg.Timestamp,
    robots: Sequence[RobotView],
    tasks: Sequence[TaskView],
    links: LinkState | None,
    *,
    robot_radius: float,
) -> fg.SceneUpdate:
    """foxglove.SceneUpdate replacing every entity (same ids each time)."""
    entities = [robot_entity(when, r, robot_radius) for r in robots]
    entities += [task_entity(when, task) for task in tasks]
    if links is not None and len(robots) > 1:
        entities.append(links_entity(when, robots, links))
    return fg.SceneUpdate(deletions=[], entities=entities)


def links_message(t: float, links: LinkState) -> dict[str, Any]:
    """JSON link matrices (row = sender, column = receiver); NaN/inf become null."""

    def matrix(a: np.ndarray | None, digits: int | None = None) -> list[Any] | None:
        if a is None:
            return None
        return (np.round(a, digits) if digits is not None else a).tolist()

    return {
        "t": round(t, 6),
        "ids": list(links.ids),
        "distance": matrix(links.distance, 3),
        "connected": matrix(links.connected),
        "warning": matrix(links.warning),
        "line_of_sight": matrix(links.line_of_sight),
        "rssi": matrix(links.rssi, 2),
    }


_WARNING_EVENTS = frozenset({"near_collision", "nav_aborted", "disconnect_detected"})


def log_message(when: fg.Timestamp, source: str, label: str, data: Mapping[str, Any]) -> fg.Log:
    """foxglove.Log of one timeline event (warnings for collisions and disconnects)."""
    details = " ".join(f"{k}={v}" for k, v in data.items())
    level = fg.LogLevel.Warning if label in _WARNING_EVENTS else fg.LogLevel.Info
    return fg.Log(timestamp=when, level=level, message=f"{label} {details}".strip(), name=source)


# -- schemas of mrcomm's own JSON channels -------------------------------------------------
def _plain(title: str, description: str, properties: Schema) -> Schema:
    return {"title": title, "description": description, "type": "object", "properties": properties}


_MATRIX: Schema = {"type": ["array", "null"], "items": {"type": "array"}}


def links_schema() -> Schema:
    return _plain(
        "mrcomm.Links",
        "Link matrices of every ordered pair of agents (row = sender, column = receiver)",
        {
            "t": {"type": "number", "description": "Simulated time, s"},
            "ids": {"type": "array", "items": {"type": "string"}},
            "distance": _MATRIX,
            "connected": _MATRIX,
            "warning": _MATRIX,
            "line_of_sight": _MATRIX,
            "rssi": _MATRIX,
        },
    )


def message_event_schema() -> Schema:
    return _plain(
        "mrcomm.MessageEvent",
        "One delivery decision of the network: a message offered to one receiver",
        {
            "t": {"type": "number", "description": "Simulated delivery time, s"},
            "topic": {"type": "string"},
            "sender": {"type": "string"},
            "receiver": {"type": "string"},
            "outcome": {"type": "string", "enum": list(OUTCOMES)},
            "seq": {"type": "integer", "description": "The sender's sequence number"},
            "stamp": {"type": "number", "description": "Send time, s"},
        },
    )


def publication_schema() -> Schema:
    return _plain(
        "mrcomm.Publication",
        "One message published by an agent",
        {
            "t": {"type": "number", "description": "Simulated send time, s"},
            "topic": {"type": "string"},
            "sender": {"type": "string"},
            "seq": {"type": "integer"},
            "kind": {"type": "string", "description": "Message type"},
        },
    )


def roles_schema() -> Schema:
    return _plain(
        "mrcomm.Roles",
        "Behaviour state (and LF role) of every robot, sent whenever one changes",
        {
            "t": {"type": "number"},
            "states": {"type": "object", "additionalProperties": {"type": "string"}},
            "roles": {"type": "object"},
            "changed": {"type": "array", "items": {"type": "string"}},
        },
    )


def result_schema() -> Schema:
    sections = ("config", "mission", "robots", "messages", "messages_by_agent", "aon", "links")
    properties: Schema = {key: {"type": "object"} for key in sections}
    properties |= {"sim_time_s": {"type": "number"}, "wall_time_s": {"type": "number"}}
    return _plain(
        "mrcomm.MissionResult", "The mission summary (the JSON of `mrcomm run --json`)", properties
    )
