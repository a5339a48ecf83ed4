"""MCAP recordings of simulated missions that Foxglove opens (``--record``).

:func:`run_and_record` builds a :class:`~mrcomm.sim.mission.Mission`, steps it to its end
itself and writes one MCAP file through the Foxglove SDK (``foxglove-sdk``), with these
channels:

* ``/map`` — ``foxglove.Grid``, once at the start;
* ``/robots/<id>/pose`` — ``foxglove.PoseInFrame``, at the scene rate;
* ``/scene`` — ``foxglove.SceneUpdate``: robots, tasks (by state), links coloured by
  state (green ok, orange warning, red disconnected), at the scene rate (5 Hz) plus a
  final one at the end;
* ``/events`` — ``foxglove.Log``: the robots' timeline events and the statuses the
  assigner received;
* mrcomm's own JSON channels (``jsonschema`` schemas in :mod:`recording_scene`):
  ``/links`` — link matrices (distance, connected, warning, line of sight, RSSI), at
  the scene rate; ``/messages`` — every delivery decision of the network (received /
  dropped_loss / dropped_range): exactly the network's per-topic bookkeeping;
  ``/publications`` — every message published; ``/roles`` — every robot's behaviour
  state and LF role, whenever one changes; ``/result`` — the mission summary
  (``mrcomm run --json``), once at the end.

The ``foxglove.*`` channels are encoded by the SDK with the schemas it publishes
(protobuf), so Foxglove decodes them as its own. Times are wall-clock: mission time 0
is when the run started (its epoch in the file's ``mrcomm`` metadata, ``epoch_ns``);
mrcomm's channels also carry mission seconds (``t``).

Recording only observes (the network's delivery observer, read-only state after each
step): the mission, and so its result, is the same as without recording. The file is
written to a temporary name and renamed into place, so it is complete or absent. With
``serve`` the same channels also go to the SDK's WebSocket server, live, for the
Foxglove app (``mrcomm run --foxglove``).
"""

from __future__ import annotations

import dataclasses
import math
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import foxglove
import msgspec
from foxglove.channels import GridChannel, LogChannel, PoseInFrameChannel, SceneUpdateChannel
from foxglove.mcap import MCAPWriteOptions
from foxglove.websocket import ChannelView, Client, ServerListener

import mrcomm
from mrcomm.errors import InputError
from mrcomm.experiment import recording_scene as scene
from mrcomm.fileio import atomic_write
from mrcomm.messaging.messages import Message
from mrcomm.metrics.timeline import ROLE
from mrcomm.net.links import LinkState
from mrcomm.run.config import RunConfig
from mrcomm.run.operator_plan import OperatorPlan
from mrcomm.run.resources import ScenarioResources
from mrcomm.run.result import MissionResult
from mrcomm.sim.mission import Mission
from mrcomm.world.geometry import Pose
from mrcomm.world.occupancy import OccupancyGrid

TOPIC_MAP = "/map"
TOPIC_SCENE = "/scene"
TOPIC_LINKS = "/links"
TOPIC_MESSAGES = "/messages"
TOPIC_PUBLICATIONS = "/publications"
TOPIC_ROLES = "/roles"
TOPIC_EVENTS = "/events"
TOPIC_RESULT = "/result"
METADATA_NAME = "mrcomm"


def pose_topic(robot: str) -> str:
    return f"/robots/{robot}/pose"


#: The foxglove message channels: topic (or a robot's pose topic) -> SDK channel class.
_TYPED_CHANNELS: dict[str, type[Any]] = {
    TOPIC_MAP: GridChannel,
    TOPIC_SCENE: SceneUpdateChannel,
    TOPIC_EVENTS: LogChannel,
}


#: A latched message (the map) is sent again to new subscribers at most this often (s of
#: wall time): subscribing and unsubscribing in a loop once had it re-sent 11,449 times
#: in 15 s, the process grown to 2.4 GB and the recording to 180 MB.
RESEND_PERIOD = 2.0
#: Messages queued for one WebSocket client that does not read (the SDK's default is
#: 1,024: with the 2.5 MB map that was 2.6 GB a client).
CLIENT_BACKLOG = 64


class _Latch(ServerListener):
    """The WebSocket server's listener: a new subscriber gets the latched messages
    (only marked here, on the server's thread: the mission's thread sends them)."""

    def __init__(self, sink: RecordingSink) -> None:
        self._sink = sink

    def on_subscribe(self, client: Client, channel: ChannelView) -> None:
        self._sink.want_resend(channel.topic)


class RecordingSink:
    """The channels of one recording on their own Foxglove SDK context (so that two
    recordings in one process never mix), written to an MCAP file and, with
    :meth:`serve`, to a live WebSocket server too. Messages are logged at wall-clock
    times from ``clock``."""

    def __init__(self, path: Path | None, clock: scene.RecordingClock) -> None:
        """``path``: the MCAP file (None: no file, e.g. only a live server). The file
        and the live server have a context each, so that what clients do (subscribe)
        never reaches the file: it depends on the mission alone."""
        self.clock = clock
        self.context = foxglove.Context()  # the file's
        self.live_context = foxglove.Context()  # the server's
        self._live: dict[str, Any] = {}
        self._pending: set[str] = set()  # latched topics a client subscribed to
        self._pending_lock = threading.Lock()
        self._resent: dict[str, float] = {}  # topic -> when it was last sent again
        options = MCAPWriteOptions(profile="")  # no ROS profile; zstd chunks
        self._mcap = (
            foxglove.open_mcap(
                path, allow_overwrite=True, context=self.context, writer_options=options
            )
            if path is not None
            else None
        )
        self._channels: dict[str, Any] = {}
        self._server: Any = None
        self._latched: dict[str, tuple[float, Any]] = {}
        self._encode = msgspec.json.Encoder().encode  # NaN/inf -> null: always valid JSON

    def add_typed(self, topic: str, channel_class: type[Any]) -> None:
        """A channel of one of the SDK's message types (encoded by the SDK)."""
        self._channels[topic] = channel_class(topic, context=self.context)
        self._live[topic] = channel_class(topic, context=self.live_context)

    def add_json(self, topic: str, schema: scene.Schema) -> None:
        """One of mrcomm's own channels: JSON messages described by a JSON schema."""
        self._channels[topic] = foxglove.Channel(topic, schema=schema, context=self.context)
        self._live[topic] = foxglove.Channel(topic, schema=schema, context=self.live_context)

    def write(self, topic: str, t: float, message: Any) -> None:
        """Log ``message`` (an SDK message, or a JSON-able payload for a JSON channel)
        at mission time ``t``, to the file and to the live server's subscribers."""
        if isinstance(message, dict):
            message = self._encode(message)
        ns = self.clock.ns(t)
        self._channels[topic].log(message, log_time=ns)
        live = self._live[topic]
        if live.has_sinks():
            live.log(message, log_time=ns)

    def write_scene(
        self,
        t: float,
        robots: list[scene.RobotView],
        tasks: list[scene.TaskView],
        links: LinkState | None,
        robot_radius: float,
    ) -> None:
        """The scene at mission time ``t``, each robot's pose and the link matrices
        (first the latched messages new subscribers are due)."""
        self.resend_due()
        when = self.clock.timestamp(t)
        update = scene.scene_update(when, robots, tasks, links, robot_radius=robot_radius)
        self.write(TOPIC_SCENE, t, update)
        for robot in robots:
            self.write(pose_topic(robot.id), t, scene.pose_message(when, robot.pose))
        if links is not None:
            self.write(TOPIC_LINKS, t, scene.links_message(t, links))

    def metadata(self, name: str, data: dict[str, str]) -> None:
        if self._mcap is not None:
            self._mcap.write_metadata(name, data)

    def serve(self, host: str, port: int) -> int:
        """Also send every channel to a Foxglove WebSocket server (live view in the
        Foxglove app); returns the port it listens on. Messages sent once (the map)
        are sent again to the server when a client subscribes to their channel, as a
        latched ROS topic would be (at most every ``RESEND_PERIOD`` s; never to the
        file); at most ``CLIENT_BACKLOG`` messages wait for a client that reads slowly."""
        try:
            self._server = foxglove.start_server(
                name="mrcomm",
                host=host,
                port=port,
                context=self.live_context,
                server_listener=_Latch(self),
                message_backlog_size=CLIENT_BACKLOG,
            )
        except RuntimeError as err:  # the SDK's FoxgloveError, e.g. the port in use
            message = str(err).removeprefix("FoxgloveError: ")
            raise InputError(message, field="--foxglove-port") from None
        return int(self._server.port)

    def latch(self, topic: str, t: float, message: Any) -> None:
        """Write ``message`` and keep it to send again to new subscribers."""
        self._latched[topic] = (t, message)
        self.write(topic, t, message)

    def want_resend(self, topic: str) -> None:
        """A client subscribed to ``topic`` (any thread): send it its latched message."""
        if topic in self._latched:
            with self._pending_lock:
                self._pending.add(topic)

    def resend_due(self) -> None:
        """Send the latched messages clients asked for to the live server, each at
        most once every ``RESEND_PERIOD`` s (the mission's thread calls this)."""
        if not self._pending:
            return
        now = time.monotonic()
        with self._pending_lock:
            due = {
                t for t in self._pending if now - self._resent.get(t, -math.inf) >= RESEND_PERIOD
            }
            self._pending -= due
        for topic in sorted(due):
            self._resent[topic] = now
            t, message = self._latched[topic]
            self._live[topic].log(message, log_time=self.clock.ns(t))

    def close(self) -> None:
        if self._mcap is not None:
            self._mcap.close()
        if self._server is not None:
            self._server.stop()


class MissionRecorder:
    """Observes a mission while it is stepped and writes what it sees."""

    def __init__(self, mission: Mission, out: RecordingSink, scene_period: float) -> None:
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
        self._command_index = 0
        self._last_states: dict[str, str] = {}
        self._last_roles: dict[str, str | None] = {}
        for topic, channel_class in _TYPED_CHANNELS.items():
            out.add_typed(topic, channel_class)
        for topic, schema in (
            (TOPIC_LINKS, scene.links_schema()),
            (TOPIC_MESSAGES, scene.message_event_schema()),
            (TOPIC_PUBLICATIONS, scene.publication_schema()),
            (TOPIC_ROLES, scene.roles_schema()),
            (TOPIC_RESULT, scene.result_schema()),
        ):
            out.add_json(topic, schema)
        for rid in mission.robot_ids:
            out.add_typed(pose_topic(rid), PoseInFrameChannel)
        out.metadata(
            METADATA_NAME,
            {
                "mrcomm_version": mrcomm.__version__,
                "label": mission.config.label(),
                "scenario": scenario.name,
                "seed": str(mission.config.seed),
                "scene_period": repr(scene_period),
                "epoch_ns": str(out.clock.epoch_ns),
                "config": mission.config.model_dump_json(),
            },
        )
        out.latch(TOPIC_MAP, 0.0, scene.grid_message(scenario.grid, out.clock.timestamp(0.0)))
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
                when = self.out.clock.timestamp(event.time)
                msg = scene.log_message(when, rid, event.label, event.data)
                self.out.write(TOPIC_EVENTS, event.time, msg)
            self._event_index[rid] = len(timeline.events)
        log = m.assigner.status_log
        for t, status in log[self._status_index :]:
            data = {"task": status.task_id, "robot": status.robot, "state": str(status.state)}
            when = self.out.clock.timestamp(t)
            msg = scene.log_message(when, m.assigner.agent_id, "status_received", data)
            self.out.write(TOPIC_EVENTS, t, msg)
        self._status_index = len(log)
        operator = m.operator
        if operator is not None:
            for record in operator.log[self._command_index :]:
                data = {"command": str(record.command), "robot": record.robot,
                        "task": record.task_id}  # fmt: skip
                when = self.out.clock.timestamp(record.time)
                msg = scene.log_message(when, operator.agent_id, "command_sent", data)
                self.out.write(TOPIC_EVENTS, record.time, msg)
            self._command_index = len(operator.log)

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
        self.out.write_scene(t, robots, self._tasks(final), m.last_links, self._robot_radius)

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


class GroundTruthStream:
    """A live mission's ground truth on a Foxglove WebSocket server (``mrcomm world
    --foxglove``): what the world process knows — the map, every robot's true pose and
    the links between them — at the scene rate, with the channels and message types of
    a recording (the task states are the agents' and are not in it)."""

    def __init__(
        self,
        grid: OccupancyGrid,
        robot_ids: tuple[str, ...],
        robot_radius: float,
        *,
        scene_period: float = 0.2,
    ) -> None:
        self.out = RecordingSink(None, scene.RecordingClock(time.time_ns()))
        self.robot_radius = robot_radius
        self.scene_period = scene_period
        self._colors = {rid: scene.robot_color(i) for i, rid in enumerate(robot_ids)}
        self._next = 0.0
        for topic, channel_class in ((TOPIC_MAP, GridChannel), (TOPIC_SCENE, SceneUpdateChannel)):
            self.out.add_typed(topic, channel_class)
        self.out.add_json(TOPIC_LINKS, scene.links_schema())
        for rid in robot_ids:
            self.out.add_typed(pose_topic(rid), PoseInFrameChannel)
        self.out.latch(TOPIC_MAP, 0.0, scene.grid_message(grid, self.out.clock.timestamp(0.0)))

    def serve(self, host: str, port: int) -> int:
        return self.out.serve(host, port)

    def __call__(self, now: float, poses: dict[str, Pose], links: LinkState) -> None:
        if now < self._next - 1e-9:
            return
        self._next = now + self.scene_period
        robots = [scene.RobotView(rid, pose, self._colors[rid], "") for rid, pose in poses.items()]
        self.out.write_scene(now, robots, [], links, self.robot_radius)

    def close(self) -> None:
        self.out.close()


def run_and_record(
    config: RunConfig,
    resources: ScenarioResources | None,
    path: Path | None,
    *,
    scene_period: float = 0.2,
    serve: tuple[str, int] | None = None,
    speed: float | None = None,
    on_serving: Callable[[int], None] | None = None,
    operator: OperatorPlan | None = None,
    progress: Callable[[Mission], None] | None = None,
) -> MissionResult:
    """Simulate one mission, recording it to the MCAP file ``path``; return its results
    (identical to :func:`~mrcomm.sim.mission.run_mission` except for wall time).

    ``serve=(host, port)`` also streams the recording live to a Foxglove WebSocket
    server (``on_serving(port)`` is called once it listens; ``path`` may then be None:
    no file); ``speed`` paces the mission at that many times real time (None: as fast
    as possible); ``operator``: an operator in the loop (:mod:`mrcomm.run.operator_plan`);
    ``progress``: as for :meth:`Mission.run`."""
    if path is not None:
        path = Path(path).expanduser()
        if not path.parent.is_dir():
            raise InputError(f"directory {path.parent} does not exist", file=path, field="--record")
    if not scene_period > 0.0:
        raise InputError("must be positive", field="scene_period")
    if speed is not None and not speed > 0.0:
        raise InputError("must be positive", field="--speed")
    mission = Mission(config, resources, operator)
    results: list[MissionResult] = []

    def record(tmp: Path | None) -> None:
        out = RecordingSink(tmp, scene.RecordingClock(time.time_ns()))
        try:
            port = out.serve(*serve) if serve is not None else None
            recorder = MissionRecorder(mission, out, scene_period)  # channels advertised
            if port is not None and on_serving is not None:
                on_serving(port)
            start = time.perf_counter()
            while not mission.done:
                recorder.step()
                if progress is not None:
                    progress(mission)
                if speed is not None:  # pace: mission time runs at speed x wall time
                    ahead = mission.now / speed - (time.perf_counter() - start)
                    if ahead > 0:
                        time.sleep(ahead)
            wall = time.perf_counter() - start
            result = dataclasses.replace(mission.result(), wall_time_s=wall)
            recorder.finish(result)
            results.append(result)
        finally:
            out.close()

    if path is None:
        record(None)
    else:
        atomic_write(path, record)
    return results[0]
