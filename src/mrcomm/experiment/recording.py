"""MCAP recordings of simulated missions that Foxglove opens (``--record``).

:func:`run_and_record` builds a :class:`~mrcomm.sim.mission.Mission`, steps it to its end
itself and writes one MCAP file (JSON message encoding, ``jsonschema`` schemas, log time
= simulated time in nanoseconds) with these channels:

* ``/map`` — ``foxglove.Grid``, once at t = 0;
* ``/robots/<id>/pose`` — ``foxglove.PoseInFrame``, at the scene rate;
* ``/scene`` — ``foxglove.SceneUpdate``: robots, tasks (by state), links coloured by
  state (green ok, orange warning, red disconnected), at the scene rate (5 Hz) plus a
  final one at the end;
* ``/links`` — link matrices (distance, connected, warning, line of sight, RSSI), at the
  scene rate;
* ``/messages`` — every delivery decision of the network (received / dropped_loss /
  dropped_range): exactly the network's per-topic bookkeeping;
* ``/publications`` — every message published, as it is published;
* ``/roles`` — every robot's behaviour state and LF role, whenever one changes;
* ``/events`` — ``foxglove.Log``: the robots' timeline events and the statuses the
  assigner received;
* ``/result`` — the mission summary (``mrcomm run --json``), once at the end.

Recording only observes (the network's delivery observer, read-only state after each
step): the mission, and so its result, is the same as without recording. The file is
written to a temporary name and renamed into place, so it is complete or absent.
"""

from __future__ import annotations

import dataclasses
import json
import time
from collections import Counter
from pathlib import Path
from typing import IO, Any

import msgspec
from mcap.writer import CompressionType, Writer

import mrcomm
from mrcomm.errors import InputError
from mrcomm.experiment import recording_scene as scene
from mrcomm.experiment.recording_schemas import (
    Schema,
    grid_schema,
    log_schema,
    pose_in_frame_schema,
    scene_update_schema,
)
from mrcomm.fileio import atomic_write
from mrcomm.messaging.messages import Message
from mrcomm.metrics.timeline import ROLE
from mrcomm.run.config import RunConfig
from mrcomm.run.resources import ScenarioResources
from mrcomm.run.result import MissionResult
from mrcomm.sim.mission import Mission
from mrcomm.world.geometry import Pose

TOPIC_MAP = "/map"
TOPIC_SCENE = "/scene"
TOPIC_LINKS = "/links"
TOPIC_MESSAGES = "/messages"
TOPIC_PUBLICATIONS = "/publications"
TOPIC_ROLES = "/roles"
TOPIC_EVENTS = "/events"
TOPIC_RESULT = "/result"
PROFILE = ""  # no ROS profile: plain JSON channels
METADATA_NAME = "mrcomm"


def pose_topic(robot: str) -> str:
    return f"/robots/{robot}/pose"


class JsonMcapWriter:
    """MCAP channels carrying JSON messages described by JSON schemas."""

    def __init__(self, stream: IO[bytes]) -> None:
        self._writer = Writer(stream, compression=CompressionType.ZSTD)
        self._writer.start(profile=PROFILE, library=f"mrcomm {mrcomm.__version__}")
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, int] = {}
        self._sequence: Counter[str] = Counter()
        self._encode = msgspec.json.Encoder().encode  # NaN/inf -> null: always valid JSON

    def add_channel(self, topic: str, schema: Schema) -> None:
        name = schema["title"]
        schema_id = self._schemas.get(name)
        if schema_id is None:
            data = json.dumps(schema).encode()
            schema_id = self._schemas[name] = self._writer.register_schema(
                name=name, encoding="jsonschema", data=data
            )
        self._channels[topic] = self._writer.register_channel(
            topic=topic, message_encoding="json", schema_id=schema_id
        )

    def write(self, topic: str, t: float, payload: Any) -> None:
        ns = scene.to_ns(t)
        self._sequence[topic] += 1
        self._writer.add_message(
            channel_id=self._channels[topic],
            log_time=ns,
            publish_time=ns,
            data=self._encode(payload),
            sequence=self._sequence[topic],
        )

    def metadata(self, name: str, data: dict[str, str]) -> None:
        self._writer.add_metadata(name, data)

    def finish(self) -> None:
        self._writer.finish()


class MissionRecorder:
    """Observes a mission while it is stepped and writes what it sees."""

    def __init__(self, mission: Mission, out: JsonMcapWriter, scene_period: float) -> None:
        if not scene_period > 0.0:
            raise ValueError("scene_period must be positive")
        self.mission = mission
        self.out = out
        self.scene_period = scene_period
        scenario = mission.resources.scenario
        self._robot_radius = scenario.robot_radius
        self._colors = {rid: scene.robot_color(i) for i, rid in enumerate(mission.robot_ids)}
        # Which robots carry each task (a task may need several): fixed at assignment.
        agenda = mission.assigner.agenda
        self._task_robots = {
            t.task_id: tuple(r for r in mission.robot_ids if t in agenda[r]) for t in scenario.tasks
        }
        self._next_scene = 0  # index k of the next scene, due at k * scene_period
        self._event_index = dict.fromkeys(mission.robot_ids, 0)
        self._status_index = 0
        self._last_states: dict[str, str] = {}
        self._last_roles: dict[str, str | None] = {}
        for topic, schema in (
            (TOPIC_MAP, grid_schema()),
            (TOPIC_SCENE, scene_update_schema()),
            (TOPIC_LINKS, scene.links_schema()),
            (TOPIC_MESSAGES, scene.message_event_schema()),
            (TOPIC_PUBLICATIONS, scene.publication_schema()),
            (TOPIC_ROLES, scene.roles_schema()),
            (TOPIC_EVENTS, log_schema()),
            (TOPIC_RESULT, scene.result_schema()),
        ):
            out.add_channel(topic, schema)
        for rid in mission.robot_ids:
            out.add_channel(pose_topic(rid), pose_in_frame_schema())
        out.metadata(
            METADATA_NAME,
            {
                "mrcomm_version": mrcomm.__version__,
                "label": mission.config.label(),
                "scenario": scenario.name,
                "seed": str(mission.config.seed),
                "scene_period": repr(scene_period),
                "config": mission.config.model_dump_json(),
            },
        )
        out.write(TOPIC_MAP, 0.0, scene.grid_message(scenario.grid, 0.0))
        mission.network.observer = self._on_delivery
        mission.network.publish_observer = self._on_publish

    # -- driving -----------------------------------------------------------------------
    def step(self) -> None:
        """One mission step. Poses are taken before it, so that they match the link
        state the step evaluates from them (``mission.last_links``)."""
        m = self.mission
        now = m.now
        due = now >= self._next_scene * self.scene_period - 1e-9
        poses = {rid: b.true_pose for rid, b in m.bases.items()} if due else None
        m.step()
        self._roles(now)
        self._events()
        if poses is not None:
            self._scene(now, poses, final=False)
            self._next_scene = int(now / self.scene_period + 1e-9) + 1

    def finish(self, result: MissionResult) -> None:
        """Final scene (failed tasks in red) and the mission summary."""
        m = self.mission
        end = result.sim_time_s
        self._events()
        self._scene(end, {rid: b.true_pose for rid, b in m.bases.items()}, final=True)
        self.out.write(TOPIC_RESULT, end, result.summary())

    # -- observers -----------------------------------------------------------------------
    def _on_delivery(
        self, now: float, topic: str, sender: str, receiver: str, message: Message, outcome: str
    ) -> None:
        self.out.write(
            TOPIC_MESSAGES,
            now,
            {
                "t": now,
                "topic": topic,
                "sender": sender,
                "receiver": receiver,
                "outcome": outcome,
                "seq": message.seq,
                "stamp": message.stamp,
            },
        )

    def _on_publish(self, stamp: float, topic: str, sender: str, message: Message) -> None:
        self.out.write(
            TOPIC_PUBLICATIONS,
            stamp,
            {
                "t": stamp,
                "topic": topic,
                "sender": sender,
                "seq": message.seq,
                "kind": type(message).__name__,
            },
        )

    def _roles(self, now: float) -> None:
        m = self.mission
        states = {rid: e.state for rid, e in m.executors.items()}
        roles = {rid: m.timelines[rid].state(ROLE) for rid in m.robot_ids}
        if states == self._last_states and roles == self._last_roles:
            return
        changed = [
            rid
            for rid in m.robot_ids
            if rid not in self._last_states
            or states[rid] != self._last_states[rid]
            or roles[rid] != self._last_roles[rid]
        ]
        self._last_states, self._last_roles = states, roles
        payload = {"t": now, "states": states, "roles": roles, "changed": changed}
        self.out.write(TOPIC_ROLES, now, payload)

    def _events(self) -> None:
        m = self.mission
        for rid, timeline in m.timelines.items():
            start = self._event_index[rid]
            for event in timeline.events[start:]:
                msg = scene.log_message(event.time, rid, event.label, event.data)
                self.out.write(TOPIC_EVENTS, event.time, msg)
            self._event_index[rid] = len(timeline.events)
        log = m.assigner.status_log
        for t, status in log[self._status_index :]:
            data = {"task": status.task_id, "robot": status.robot, "state": str(status.state)}
            msg = scene.log_message(t, m.assigner.agent_id, "status_received", data)
            self.out.write(TOPIC_EVENTS, t, msg)
        self._status_index = len(log)

    def _scene(self, t: float, poses: dict[str, Pose], *, final: bool) -> None:
        m = self.mission
        robots = [
            scene.RobotView(
                rid,
                poses[rid],
                self._colors[rid],
                m.executors[rid].state,
                m.timelines[rid].state(ROLE),
            )
            for rid in m.robot_ids
        ]
        update = scene.scene_update(
            t, robots, self._tasks(final), m.last_links, robot_radius=self._robot_radius
        )
        self.out.write(TOPIC_SCENE, t, update)
        for rid in m.robot_ids:
            self.out.write(pose_topic(rid), t, scene.pose_message(t, poses[rid]))
        if m.last_links is not None:
            self.out.write(TOPIC_LINKS, t, scene.links_message(t, m.last_links))

    def _tasks(self, final: bool) -> list[scene.TaskView]:
        m = self.mission
        received = m.assigner.success_received
        goals = {e.goal.task_id for e in m.executors.values() if e.goal is not None}
        views = []
        for task in m.resources.scenario.tasks:
            robots = self._task_robots[task.task_id]
            if robots and all((task.task_id, r) in received for r in robots):
                state = "communicated"
            elif final:
                state = "failed"  # the assigner never learnt it (a failed task)
            elif any(task.task_id in m.executors[r].completed for r in robots):
                state = "completed"
            elif task.task_id in goals:
                state = "active"
            else:
                state = "pending"
            views.append(scene.TaskView(task.task_id, task.x, task.y, state, robots))
        return views


def run_and_record(
    config: RunConfig,
    resources: ScenarioResources | None,
    path: Path,
    *,
    scene_period: float = 0.2,
) -> MissionResult:
    """Simulate one mission, recording it to the MCAP file ``path``; return its results
    (identical to :func:`~mrcomm.sim.mission.run_mission` except for wall time)."""
    path = Path(path).expanduser()
    if not path.parent.is_dir():
        raise InputError(f"directory {path.parent} does not exist", file=path, field="--record")
    if not scene_period > 0.0:
        raise InputError("must be positive", field="scene_period")
    mission = Mission(config, resources)
    results: list[MissionResult] = []

    def record(tmp: Path) -> None:
        with tmp.open("wb") as stream:
            out = JsonMcapWriter(stream)
            recorder = MissionRecorder(mission, out, scene_period)
            start = time.perf_counter()
            while not mission.done:
                recorder.step()
            wall = time.perf_counter() - start
            result = dataclasses.replace(mission.result(), wall_time_s=wall)
            recorder.finish(result)
            out.finish()
            results.append(result)

    atomic_write(path, record)
    return results[0]
