"""MCAP recordings: a recorded mission reads back with the expected channels and message
counts, its foxglove messages decode with the schemas the Foxglove SDK publishes (and
mrcomm's own with their JSON schemas), times are on the wall clock, and recording does
not change the mission."""

from __future__ import annotations

import base64
import json
import time
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from foxglove import messages as fg
from google.protobuf.json_format import MessageToDict
from mcap.decoder import DecoderFactory as McapDecoderFactory
from mcap.reader import make_reader
from mcap.records import Schema
from mcap_protobuf.decoder import DecoderFactory

from mrcomm.errors import InputError
from mrcomm.experiment import recording_scene as scene
from mrcomm.experiment.recording import run_and_record
from mrcomm.experiment.recording_reader import read_recording
from mrcomm.net.links import LinkState
from mrcomm.run.config import RunConfig, make_config
from mrcomm.run.result import MissionResult
from mrcomm.sim.mission import Mission, run_mission
from mrcomm.world.geometry import Pose
from mrcomm.world.occupancy import OccupancyGrid
from tests.conftest import S1_PATH

ROBOTS = ("robot_1", "robot_2", "robot_3")
CHANNELS = {
    "/map",
    "/scene",
    "/links",
    "/messages",
    "/publications",
    "/roles",
    "/events",
    "/result",
    *(f"/robots/{r}/pose" for r in ROBOTS),
}


#: The channels of the SDK's message types, and those types.
FOXGLOVE: dict[str, Any] = {
    "/map": fg.Grid,
    "/scene": fg.SceneUpdate,
    "/events": fg.Log,
    **{f"/robots/{r}/pose": fg.PoseInFrame for r in ROBOTS},
}
_DECODERS = DecoderFactory()


class _JsonDecoders(McapDecoderFactory):
    """Decodes mrcomm's JSON channels."""

    def decoder_for(self, message_encoding: str, schema: Schema | None) -> Any:
        return json.loads if message_encoding == "json" else None


def as_dict(proto: Any) -> dict[str, Any]:
    """A decoded protobuf message as JSON-like data (bytes base64, enums by name)."""
    return MessageToDict(
        proto, preserving_proto_field_name=True, always_print_fields_with_no_presence=True
    )


def decode_sdk(message: Any) -> Any:
    """An SDK message encoded by the SDK, decoded with the schema it publishes."""
    schema = type(message).get_schema()
    record = Schema(id=1, name=schema.name, encoding=schema.encoding, data=schema.data)
    decoder = _DECODERS.decoder_for("protobuf", record)
    assert decoder is not None
    return decoder(message.encode())


class Recording:
    """A recorded run, decoded: topic -> [(mission time s, message as data)], the
    decoded protobuf messages of the foxglove channels, plus the schemas."""

    def __init__(self, path: Path, result: MissionResult) -> None:
        self.path = path
        self.result = result
        self.messages: dict[str, list[tuple[float, Any]]] = {}
        self.protos: dict[str, list[tuple[int, Any]]] = {}  # topic -> [(log time ns, msg)]
        self.schemas: dict[str, tuple[str, str, bytes]] = {}
        self.encodings: dict[str, str] = {}
        with path.open("rb") as stream:
            reader = make_reader(
                stream, validate_crcs=True, decoder_factories=[_DECODERS, _JsonDecoders()]
            )
            (meta,) = [m.metadata for m in reader.iter_metadata() if m.name == "mrcomm"]
            self.epoch_ns = int(meta["epoch_ns"])
            for _schema, channel, message, decoded in reader.iter_decoded_messages(
                log_time_order=True
            ):
                t = (message.log_time - self.epoch_ns) / 1e9
                if channel.message_encoding == "protobuf":
                    self.protos.setdefault(channel.topic, []).append((message.log_time, decoded))
                    decoded = as_dict(decoded)
                self.messages.setdefault(channel.topic, []).append((t, decoded))
            summary = reader.get_summary()
            assert summary is not None
            for channel in summary.channels.values():
                sch = summary.schemas[channel.schema_id]
                self.schemas[channel.topic] = (sch.name, sch.encoding, sch.data)
                self.encodings[channel.topic] = channel.message_encoding

    def payloads(self, topic: str) -> list[Any]:
        return [m for _, m in self.messages.get(topic, [])]


def _rgba(color: scene.Color) -> dict[str, float]:
    return dict(zip("rgba", color, strict=True))


def _config(**fields: Any) -> RunConfig:
    return make_config(None, scenario=S1_PATH, **fields)


NB_FIELDS: dict[str, Any] = {"network": "wlan", "spl": 25, "behaviour": "nb", "max_time": 60}
NB_FIELDS["seed"] = 3
LF_FIELDS: dict[str, Any] = {"network": "ah", "spl": 25, "threshold": "slt", "behaviour": "lf"}
LF_FIELDS["seed"] = 3


@pytest.fixture(scope="module")
def nb_recording(s1_resources: Any, tmp_path_factory: pytest.TempPathFactory) -> Recording:
    path = tmp_path_factory.mktemp("rec") / "nb.mcap"
    return Recording(path, run_and_record(_config(**NB_FIELDS), s1_resources, path))


@pytest.fixture(scope="module")
def lf_recording(s1_resources: Any, tmp_path_factory: pytest.TempPathFactory) -> Recording:
    """A whole LF mission on AH with SLT (it finishes; links do cross the warning)."""
    path = tmp_path_factory.mktemp("rec") / "lf.mcap"
    return Recording(path, run_and_record(_config(**LF_FIELDS), s1_resources, path))


def _without_wall_time(summary: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in summary.items() if k != "wall_time_s"}


# -- channels and counts -----------------------------------------------------------------
def test_recording_has_the_expected_channels_and_schemas(nb_recording: Recording) -> None:
    rec = nb_recording
    assert set(rec.schemas) == CHANNELS
    assert set(rec.messages) == CHANNELS  # every channel has messages
    for topic, (name, encoding, data) in rec.schemas.items():
        if topic in FOXGLOVE:  # the SDK's own schema, byte for byte
            published = FOXGLOVE[topic].get_schema()
            assert (name, encoding, data) == (published.name, "protobuf", published.data)
            assert rec.encodings[topic] == "protobuf"
        else:
            assert rec.encodings[topic] == "json" and encoding == "jsonschema"
            assert json.loads(data)["title"] == name and name.startswith("mrcomm.")
    # Written in mission-time order (to within one step: an event raised by a message
    # handler carries the agent's previous step time), so players can stream the file.
    with rec.path.open("rb") as stream:
        reader = make_reader(stream)
        times = np.array([m.log_time for _, _, m in reader.iter_messages(log_time_order=False)])
    assert np.all(times >= np.maximum.accumulate(times) - 100_000_000)
    assert times.max() == times[-1] == rec.epoch_ns + round(rec.result.sim_time_s * 1e9)


def test_times_are_on_the_wall_clock(s1_resources: Any, tmp_path: Path) -> None:
    before = time.time_ns()
    path = tmp_path / "clock.mcap"
    rec = Recording(
        path, run_and_record(_config(**{**NB_FIELDS, "max_time": 5}), s1_resources, path)
    )
    assert before <= rec.epoch_ns <= time.time_ns()  # mission time 0: when the run started
    summary = read_recording(path)  # ... and replay still reads mission seconds
    scenes = summary.channel("/scene")
    assert scenes is not None and scenes.start == 0.0 and scenes.end == pytest.approx(5.0)


def test_messages_channel_matches_the_network_bookkeeping(nb_recording: Recording) -> None:
    rec = nb_recording
    events = rec.payloads("/messages")
    expected = rec.result.messages
    assert len(events) == sum(
        c["received"] + c["dropped_loss"] + c["dropped_range"] for c in expected.values()
    )
    got = Counter((e["topic"], e["outcome"]) for e in events)
    for topic, counts in expected.items():
        for outcome in ("received", "dropped_loss", "dropped_range"):
            assert got[(topic, outcome)] == counts[outcome], (topic, outcome)
    assert got[("pose", "dropped_loss")] > 0  # SPL 25 did drop poses
    assert all(e["sender"] != e["receiver"] for e in events)
    # Delivery happens at the step after publication.
    assert all(e["t"] > e["stamp"] for e in events)


def test_scene_poses_and_links_at_the_scene_rate(nb_recording: Recording) -> None:
    rec = nb_recording
    sim_time = rec.result.sim_time_s
    scenes = rec.messages["/scene"]
    # One scene per 0.2 s of simulated time, plus the final one at the end.
    assert abs(len(scenes) - (sim_time / 0.2 + 1)) <= 1
    assert scenes[0][0] == 0.0 and scenes[-1][0] == pytest.approx(sim_time)
    steps = np.diff([t for t, _ in scenes])
    assert np.all(steps <= 0.2 + 1e-6)
    for r in ROBOTS:
        poses = rec.messages[f"/robots/{r}/pose"]
        assert len(poses) == len(scenes)
        for _, pose in poses:
            assert pose["frame_id"] == "map"
        for log_time, proto in rec.protos[f"/robots/{r}/pose"]:
            assert proto.timestamp.ToNanoseconds() == log_time
    # Final poses are the robots' last trajectory samples.
    for r in ROBOTS:
        _, last = rec.messages[f"/robots/{r}/pose"][-1]
        _, x, y = rec.result.trajectories[r][-1]
        assert last["pose"]["position"]["x"] == pytest.approx(x, abs=1e-3)
        assert last["pose"]["position"]["y"] == pytest.approx(y, abs=1e-3)
    assert len(rec.messages["/links"]) == len(scenes)
    links = rec.payloads("/links")[0]
    assert links["ids"] == [*ROBOTS, "assigner"]
    assert np.array(links["distance"]).shape == (4, 4)


def test_map_is_the_scenario_grid(nb_recording: Recording, s1_resources: Any) -> None:
    grid = s1_resources.scenario.grid
    (t, msg), *rest = nb_recording.messages["/map"]
    assert t == 0.0 and rest == []
    assert msg["column_count"] == grid.width
    assert msg["cell_size"] == {"x": grid.resolution, "y": grid.resolution}
    cells = np.frombuffer(base64.b64decode(msg["data"]), dtype=np.uint8)
    assert cells.size == msg["row_stride"] * grid.height
    occupancy_offset = next(f["offset"] for f in msg["fields"] if f["name"] == "occupancy")
    rows = cells.reshape(grid.height, msg["row_stride"])
    occupancy = rows[:, occupancy_offset :: msg["cell_stride"]]
    assert occupancy.shape == grid.occupied.shape
    assert np.array_equal(occupancy == 100, grid.occupied)
    assert {f["name"] for f in msg["fields"]} >= {"red", "green", "blue", "alpha"}


def test_result_and_events(nb_recording: Recording, lf_recording: Recording) -> None:
    for rec in (nb_recording, lf_recording):
        ((t, result),) = rec.messages["/result"]
        assert t == pytest.approx(rec.result.sim_time_s)
        assert result == json.loads(json.dumps(rec.result.summary()))
        # Every timeline event of every robot is on /events, in the robot's name.
        logs = rec.payloads("/events")
        for r in ROBOTS:
            expected = [e.label for e in rec.result.timelines[r].events]
            got = [m["message"].split()[0] for m in logs if m["name"] == r]
            assert got == expected
        # And the assigner's receipts: at least one SUCCESS per communicated task.
        receipts = [m for m in logs if m["name"] == "assigner"]
        assert sum("state=SUCCESS" in m["message"] for m in receipts) >= (
            result["mission"]["tasks_completed"] - len(result["mission"]["failed_tasks"])
        )


# -- determinism -------------------------------------------------------------------------
@pytest.mark.parametrize("fields", [NB_FIELDS, LF_FIELDS], ids=["nb", "lf"])
def test_recording_does_not_change_the_mission(
    fields: dict[str, Any], s1_resources: Any, nb_recording: Recording, lf_recording: Recording
) -> None:
    rec = nb_recording if fields is NB_FIELDS else lf_recording
    plain = run_mission(_config(**fields), s1_resources)
    assert _without_wall_time(rec.result.summary()) == _without_wall_time(plain.summary())
    (recorded,) = rec.payloads("/result")
    assert _without_wall_time(recorded) == json.loads(
        json.dumps(_without_wall_time(plain.summary()))
    )


def test_ssd_recording_carries_rssi_and_line_of_sight(s1_resources: Any, tmp_path: Path) -> None:
    fields = {**LF_FIELDS, "threshold": "ssd", "max_time": 60}
    config = _config(**fields)
    path = tmp_path / "ssd.mcap"
    rec = Recording(path, run_and_record(config, s1_resources, path))
    plain = run_mission(config, s1_resources)
    assert _without_wall_time(rec.result.summary()) == _without_wall_time(plain.summary())
    links = rec.payloads("/links")
    assert all(m["rssi"] is not None and m["line_of_sight"] is not None for m in links)
    rssi = np.array(links[-1]["rssi"][:3], dtype=float)[:, :3]
    off_diagonal = rssi[~np.eye(3, dtype=bool)]
    assert np.all(np.isnan(off_diagonal) | (off_diagonal < -20.0))


# -- a whole LF mission ---------------------------------------------------------------------
def test_lf_recording_shows_roles_links_and_task_outcomes(lf_recording: Recording) -> None:
    rec = lf_recording
    assert not rec.result.mission["timed_out"]
    # A finished mission delivered everything: one publication per message sent.
    sent = sum(c["sent"] for c in rec.result.messages.values())
    assert len(rec.messages["/publications"]) == sent
    assert "aon" in {p["topic"] for p in rec.payloads("/publications")}
    roles = rec.payloads("/roles")
    assert set(roles[0]["states"]) == set(ROBOTS)
    seen_roles = {role for m in roles for role in m["roles"].values()}
    assert {"leader", "follower"} <= seen_roles
    assert all(m["changed"] for m in roles)
    # Link lines are coloured from the link matrices of the same instant.
    colours = {state: _rgba(c) for state, c in scene.LINK_COLORS.items()}
    seen_states = set()
    for (t, update), (t2, links) in zip(
        rec.messages["/scene"], rec.messages["/links"], strict=True
    ):
        assert t == t2
        (entity,) = [e for e in update["entities"] if e["id"] == "links"]
        connected = np.array(links["connected"])
        warning = np.array(links["warning"])
        k = 0
        for i in range(3):
            for j in range(i + 1, 3):
                if not (connected[i, j] and connected[j, i]):
                    state = "disconnected"
                elif warning[i, j] or warning[j, i]:
                    state = "warning"
                else:
                    state = "ok"
                assert entity["lines"][k]["color"] == colours[state]
                seen_states.add(state)
                k += 1
    assert {"ok", "warning"} <= seen_states
    # Final scene: communicated tasks green, failed ones red.
    _, final = rec.messages["/scene"][-1]
    failed = set(rec.result.mission["failed_tasks"])
    for entity in final["entities"]:
        if entity["id"].startswith("task/"):
            task_id = entity["id"].removeprefix("task/")
            state = "failed" if task_id in failed else "communicated"
            assert entity["cubes"][0]["color"] == _rgba(scene.TASK_COLORS[state])


# -- conformance to the schemas --------------------------------------------------------------
_JSON_TYPES: dict[str, tuple[type, ...]] = {
    "number": (int, float),
    "integer": (int,),
    "string": (str,),
    "boolean": (bool,),
    "array": (list,),
    "object": (dict,),
}


def _conforms(value: Any, schema: dict[str, Any], where: str = "") -> None:
    """Minimal JSON Schema check: types (one or a list), known properties, enums, array
    items."""
    kinds = schema.get("type")
    if kinds is not None:
        kinds = [kinds] if isinstance(kinds, str) else kinds
        allowed = tuple(t for k in kinds if k != "null" for t in _JSON_TYPES[k])
        assert (value is None and "null" in kinds) or isinstance(value, allowed), where
        if isinstance(value, bool):
            assert "boolean" in kinds, where
    if "enum" in schema:
        assert value in schema["enum"], where
    if isinstance(value, dict) and "properties" in schema:
        for key, item in value.items():
            assert key in schema["properties"], f"{where}.{key} is not in the schema"
            _conforms(item, schema["properties"][key], f"{where}.{key}")
    if isinstance(value, list) and "items" in schema:
        for i, item in enumerate(value):
            _conforms(item, schema["items"], f"{where}[{i}]")


def test_mrcomm_channels_conform_to_their_json_schemas(nb_recording: Recording) -> None:
    rec = nb_recording
    for topic in CHANNELS - set(FOXGLOVE):
        schema = json.loads(rec.schemas[topic][2])
        for payload in rec.payloads(topic)[:200]:
            _conforms(payload, schema, topic)


def test_foxglove_messages_decode_with_the_sdks_schemas(nb_recording: Recording) -> None:
    # Decoding (done while reading) fails on data that does not match the schema; the
    # decoded scene has the primitives it was built with.
    _, first = nb_recording.protos["/scene"][0]
    kinds = {f.name for e in first.entities for f, _ in e.ListFields()}
    assert {"cylinders", "arrows", "texts", "cubes", "lines"} <= kinds
    (entity,) = [e for e in first.entities if e.id == "links"]
    assert all(line.type == 0 for line in entity.lines)  # LINE_STRIP
    levels = {proto.level for _, proto in nb_recording.protos["/events"]}
    assert levels <= {2, 3}  # INFO, WARNING


# -- scene builders ------------------------------------------------------------------------
def test_clock_quaternions_and_link_states() -> None:
    clock = scene.RecordingClock(epoch_ns=1_700_000_000_000_000_000)
    assert clock.ns(1.5) == 1_700_000_001_500_000_000
    assert decode_sdk(fg.Log(timestamp=clock.timestamp(2.25))).timestamp.ToNanoseconds() == (
        1_700_000_002_250_000_000
    )
    pose = decode_sdk(scene.pose_message(clock.timestamp(0.0), Pose(1.0, 2.0, np.pi / 2)))
    q = pose.pose.orientation
    assert q.z == pytest.approx(np.sqrt(0.5)) and q.w == pytest.approx(np.sqrt(0.5))
    n = 3
    connected = np.ones((n, n), dtype=bool)
    warning = np.zeros((n, n), dtype=bool)
    warning[0, 1] = True  # one direction is enough
    connected[2, 0] = False
    links = LinkState(("a", "b", "c"), np.zeros((n, n)), None, None, warning, connected)
    assert scene.link_state(links, 0, 1) == "warning"
    assert scene.link_state(links, 0, 2) == "disconnected"
    assert scene.link_state(links, 1, 2) == "ok"
    message = scene.links_message(1.0, links)
    assert message["rssi"] is None and message["connected"][2][0] is False


def test_grid_rows_start_at_the_map_origin() -> None:
    occupied = np.zeros((2, 3), dtype=bool)
    occupied[0, 2] = True  # bottom row (at the origin), right column
    grid = decode_sdk(
        scene.grid_message(OccupancyGrid(occupied, 0.5, (1.0, -2.0)), fg.Timestamp(0))
    )
    cells = np.frombuffer(grid.data, dtype=np.uint8).reshape(2, 3, 5)
    assert cells[0, 2, 0] == 100 and cells[:, :, 0].sum() == 100
    assert (grid.pose.position.x, grid.pose.position.y) == (1.0, -2.0)
    assert grid.column_count == 3 and grid.row_stride == 15


# -- options and failures ---------------------------------------------------------------------
def test_scene_period_sets_the_scene_rate(s1_resources: Any, tmp_path: Path) -> None:
    path = tmp_path / "slow.mcap"
    result = run_and_record(
        _config(**{**NB_FIELDS, "max_time": 20}), s1_resources, path, scene_period=1.0
    )
    summary = read_recording(path)
    scenes = summary.channel("/scene")
    assert scenes is not None and scenes.count == 21  # t = 0, 1, ..., 19 and the end (20)
    assert summary.result is not None
    assert summary.result["sim_time_s"] == result.sim_time_s == 20.0


def test_missing_directory_is_an_input_error(s1_resources: Any, tmp_path: Path) -> None:
    with pytest.raises(InputError, match="does not exist"):
        run_and_record(_config(**NB_FIELDS), s1_resources, tmp_path / "no" / "x.mcap")


def test_nothing_is_left_behind_when_the_run_fails(
    s1_resources: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    calls = 0
    original = Mission.step

    def failing_step(self: Mission) -> None:
        nonlocal calls
        calls += 1
        if calls > 20:
            raise RuntimeError("boom")
        original(self)

    monkeypatch.setattr(Mission, "step", failing_step)
    path = tmp_path / "x.mcap"
    with pytest.raises(RuntimeError, match="boom"):
        run_and_record(_config(**NB_FIELDS), s1_resources, path)
    assert list(tmp_path.iterdir()) == []


def test_the_shipped_foxglove_layout_is_the_generated_one_and_shows_recorded_topics() -> None:
    from mrcomm.experiment.foxglove_layout import SHIPPED, layout_json

    assert SHIPPED.read_text() == layout_json(), "run python -m mrcomm.experiment.foxglove_layout"
    shown = json.dumps(json.loads(SHIPPED.read_text()))
    for topic in ("/map", "/scene", "/events", "/result", "/roles.states.robot_1"):
        assert f'"{topic}' in shown
