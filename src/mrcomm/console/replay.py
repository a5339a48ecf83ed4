"""A finished mission in the console: the frames of an MCAP recording (``--record``),
scrubbed with a time slider (``mrcomm console --replay RUN.mcap``).

A recording holds the ground truth the simulation had — every robot where it was,
each task's state (pending, active, completed by its robot, communicated to the task
assigner, failed) and each link's state — at the scene rate, and the events. Each
scene becomes a :class:`~mrcomm.console.view.ConsoleView` drawn like a live one (with
ground truth: a yellow task is one done whose status had not reached the assigner).
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mrcomm.console.view import ConsoleView, RobotMark, TaskMark
from mrcomm.errors import InputError
from mrcomm.experiment.recording import (
    METADATA_NAME,
    TOPIC_EVENTS,
    TOPIC_MAP,
    TOPIC_SCENE,
)
from mrcomm.world.occupancy import OccupancyGrid


@dataclass
class Replay:
    label: str
    grid: OccupancyGrid
    times: list[float]  # mission s of each frame
    frames: list[ConsoleView]
    events: list[tuple[float, str]]

    def at(self, t: float) -> ConsoleView:
        """The last frame at or before ``t``, with the events until then."""
        i = max(0, bisect.bisect_right(self.times, t + 1e-9) - 1)
        shown = [line for when, line in self.events if when <= self.times[i] + 1e-9]
        frame = self.frames[i]
        return ConsoleView(
            now=frame.now, robots=frame.robots, tasks=frame.tasks, links=frame.links,
            events=tuple(shown[-200:]), events_total=len(shown), counters={}, commands=(),
            ended=i == len(self.frames) - 1,
        )  # fmt: skip

    @property
    def end(self) -> float:
        return self.times[-1]


def _yaw(q: Any) -> float:
    return 2.0 * math.atan2(q.z, q.w)


def _meta(entity: Any) -> dict[str, str]:
    return {kv.key: kv.value for kv in entity.metadata}


def _frame(t: float, scene: Any) -> ConsoleView:
    robots, tasks, links = [], [], {}
    for entity in scene.entities:
        meta = _meta(entity)
        if entity.id.startswith("robot/"):
            body, arrow = entity.cylinders[0].pose, entity.arrows[0].pose
            x, y = body.position.x, body.position.y
            robots.append(RobotMark(entity.id.removeprefix("robot/"),
                                    (x, y, _yaw(arrow.orientation)), 0.0, (x, y),
                                    meta.get("state", ""), meta.get("role", "")))  # fmt: skip
        elif entity.id.startswith("task/"):
            state = meta.get("state", "")
            cube = entity.cubes[0].pose.position
            tasks.append(TaskMark(
                entity.id.removeprefix("task/"), cube.x, cube.y, meta.get("robots", ""),
                heard=state == "communicated", done=state in ("completed", "communicated"),
                received=state == "communicated",
            ))  # fmt: skip
        elif entity.id == "links":
            links = meta
    return ConsoleView(now=t, robots=tuple(robots), tasks=tuple(tasks), links=links,
                       events=(), events_total=0, counters={}, commands=())  # fmt: skip


def _grid(message: Any) -> OccupancyGrid:
    stride, width = message.cell_stride, message.column_count
    cells = np.frombuffer(message.data, dtype=np.uint8)
    rows = cells.size // message.row_stride
    occupancy = cells.reshape(rows, message.row_stride)[:, : width * stride : stride]
    origin = (message.pose.position.x, message.pose.position.y)
    return OccupancyGrid(occupancy >= 50, message.cell_size.x, origin)


def load_replay(path: Path) -> Replay:
    """Read a recording's map, scenes and events (one-line InputError when it is not
    an MCAP recording of mrcomm's)."""
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory

    from mrcomm.experiment.recording_reader import read_recording

    summary = read_recording(path)  # refuses what is not a readable MCAP file
    meta = summary.metadata.get(METADATA_NAME, {})
    epoch = int(meta.get("epoch_ns", "0"))
    grid: OccupancyGrid | None = None
    times: list[float] = []
    frames: list[ConsoleView] = []
    events: list[tuple[float, str]] = []
    with path.open("rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        topics = [TOPIC_MAP, TOPIC_SCENE, TOPIC_EVENTS]
        for _schema, channel, message, decoded in reader.iter_decoded_messages(
            topics=topics, log_time_order=True
        ):
            t = (message.log_time - epoch) / 1e9
            if channel.topic == TOPIC_MAP:
                grid = _grid(decoded)
            elif channel.topic == TOPIC_SCENE:
                times.append(t)
                frames.append(_frame(t, decoded))
            else:
                events.append((t, f"{t:7.1f} {decoded.name} {decoded.message}"))
    if grid is None or not frames:
        raise InputError("not an mrcomm recording (no /map or no /scene)", file=path)
    return Replay(meta.get("label", "?"), grid, times, frames, events)
