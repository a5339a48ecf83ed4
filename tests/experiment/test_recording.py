"""MCAP recordings: a recorded mission reads back with the expected channels and message
counts, its messages conform to the foxglove schemas, and recording does not change the
mission."""

from __future__ import annotations

import base64
import json
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mcap.reader import make_reader

from mrcomm.errors import InputError
from mrcomm.experiment import recording_scene as scene
from mrcomm.experiment.recording import run_and_record
from mrcomm.experiment.recording_reader import read_recording
from mrcomm.experiment.recording_schemas import (
    grid_schema,
    log_schema,
    pose_in_frame_schema,
    scene_update_schema,
)
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


class Recording:
    """A recorded run, decoded: topic -> [(log time s, message)], plus its schemas."""

    def __init__(self, path: Path, result: MissionResult) -> None:
        self.path = path
        self.result = result
        self.messages: dict[str, list[tuple[float, Any]]] = {}
        self.schemas: dict[str, tuple[str, str, dict[str, Any]]] = {}
        self.encodings: dict[str, str] = {}
        with path.open("rb") as stream:
            reader = make_reader(stream, validate_crcs=True)
            for _schema, channel, message in reader.iter_messages(log_time_order=True):
                self.messages.setdefault(channel.topic, []).append(
                    (message.log_time / 1e9, json.loads(message.data))
                )
            summary = reader.get_summary()
            assert summary is not None
            for channel in summary.channels.values():
                sch = summary.schemas[channel.schema_id]
                self.schemas[channel.topic] = (sch.name, sch.encoding, json.loads(sch.data))
                self.encodings[channel.topic] = channel.message_encoding

    def payloads(self, topic: str) -> list[Any]:
        return [m for _, m in self.messages.get(topic, [])]


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
    assert all(enc == "json" for enc in rec.encodings.values())
    assert all(enc == "jsonschema" for _, enc, _ in rec.schemas.values())
    names = {topic: name for topic, (name, _, _) in rec.schemas.items()}
    assert names["/map"] == "foxglove.Grid"
    assert names["/scene"] == "foxglove.SceneUpdate"
    assert names["/events"] == "foxglove.Log"
    assert {names[f"/robots/{r}/pose"] for r in ROBOTS} == {"foxglove.PoseInFrame"}
    for name, _, schema in rec.schemas.values():
        assert schema["title"] == name
    # Written in simulated-time order (to within one step: an event raised by a message
    # handler carries the agent's previous step time), so players can stream the file.
    with rec.path.open("rb") as stream:
        reader = make_reader(stream)
        times = np.array([m.log_time for _, _, m in reader.iter_messages(log_time_order=False)])
    assert np.all(times >= np.maximum.accumulate(times) - scene.to_ns(0.1))
    assert times.max() == times[-1] == scene.to_ns(rec.result.sim_time_s)


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
        for t, pose in poses:
            assert pose["frame_id"] == "map"
            assert pose["timestamp"]["sec"] + pose["timestamp"]["nsec"] / 1e9 == pytest.approx(t)
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
    try:
        config = _config(**fields)
    except InputError:
        pytest.skip("the SSD threshold is not available yet")
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
    colours = {state: scene._rgba(c) for state, c in scene.LINK_COLORS.items()}
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
            assert entity["cubes"][0]["color"] == scene._rgba(scene.TASK_COLORS[state])


# -- conformance to the foxglove schemas ----------------------------------------------------
_JSON_TYPES: dict[str, tuple[type, ...]] = {
    "number": (int, float),
    "integer": (int,),
    "string": (str,),
    "boolean": (bool,),
    "array": (list,),
    "object": (dict,),
}


def _conforms(value: Any, schema: dict[str, Any], where: str = "") -> None:
    """Minimal JSON Schema check: types, known properties, enum consts, array items."""
    if "oneOf" in schema:
        assert value in [c["const"] for c in schema["oneOf"]], where
        return
    kind = schema.get("type")
    if kind is not None:
        assert isinstance(value, _JSON_TYPES[kind]), f"{where}: {value!r} is not {kind}"
        assert not (kind in ("number", "integer") and isinstance(value, bool)), where
    if kind == "object" and "properties" in schema:
        for key, item in value.items():
            assert key in schema["properties"], f"{where}.{key} is not in the schema"
            _conforms(item, schema["properties"][key], f"{where}.{key}")
    if kind == "array":
        for i, item in enumerate(value):
            _conforms(item, schema["items"], f"{where}[{i}]")


def test_messages_conform_to_the_foxglove_schemas(nb_recording: Recording) -> None:
    rec = nb_recording
    checks = {
        "/map": grid_schema(),
        "/scene": scene_update_schema(),
        "/events": log_schema(),
        "/robots/robot_1/pose": pose_in_frame_schema(),
    }
    for topic, schema in checks.items():
        assert rec.schemas[topic][2] == schema
        for payload in rec.payloads(topic)[:50]:
            _conforms(payload, schema, topic)
    grid = grid_schema()["properties"]
    assert grid["data"] == {
        "type": "string",
        "contentEncoding": "base64",
        "description": "Grid cell data, interpreted using `fields`, in row-major (y-major) order",
    }
    primitives = scene_update_schema()["properties"]["entities"]["items"]["properties"]
    assert {"arrows", "cubes", "spheres", "cylinders", "lines", "triangles", "texts"} <= set(
        primitives
    )
    assert primitives["lines"]["items"]["title"] == "foxglove.LinePrimitive"


# -- scene builders ------------------------------------------------------------------------
def test_stamps_quaternions_and_link_states() -> None:
    assert scene.to_ns(1.5) == 1_500_000_000
    assert scene.stamp(2.25) == {"sec": 2, "nsec": 250_000_000}
    q = scene.pose_message(0.0, Pose(1.0, 2.0, np.pi / 2))["pose"]["orientation"]
    assert q["z"] == pytest.approx(np.sqrt(0.5)) and q["w"] == pytest.approx(np.sqrt(0.5))
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
    msg = scene.grid_message(OccupancyGrid(occupied, 0.5, (1.0, -2.0)))
    cells = np.frombuffer(base64.b64decode(msg["data"]), dtype=np.uint8).reshape(2, 3, 5)
    assert cells[0, 2, 0] == 100 and cells[:, :, 0].sum() == 100
    assert msg["pose"]["position"] == {"x": 1.0, "y": -2.0, "z": 0.0}
    assert msg["column_count"] == 3 and msg["row_stride"] == 15


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
