"""``mrcomm run --foxglove``: the run is streamed live to a Foxglove WebSocket server
(the Foxglove SDK's), read here by a client speaking the Foxglove WebSocket protocol as
the Foxglove app does — channels advertised, the scene and the map decoded on
subscription — on loopback only."""

from __future__ import annotations

import contextlib
import json
import socket
import struct
import threading
from pathlib import Path
from typing import Any

import pytest
from foxglove import messages as fg
from mcap.records import Schema
from mcap_protobuf.decoder import DecoderFactory
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect
from websockets.typing import Subprotocol

from mrcomm.errors import InputError
from mrcomm.experiment.recording import run_and_record
from mrcomm.run.config import make_config
from tests.cli.test_report_cli import in_process
from tests.conftest import S1_PATH

SUBPROTOCOL = Subprotocol("foxglove.sdk.v1")  # the SDK server speaks this version of the protocol
MESSAGE_DATA = 1  # binary opcode: subscription id (u32), log time (u64), payload


class Client:
    """A Foxglove client in its own thread, as the app is: it connects, waits for
    ``topics`` to be advertised, subscribes to each with its id, then reads every frame
    (so the server never waits on it) until the server closes the connection."""

    def __init__(self, port: int, topics: dict[str, int]) -> None:
        self.port, self.topics = port, topics
        self.channels: dict[str, Any] = {}
        self.frames: list[tuple[int, int, bytes]] = []  # (subscription, log time, data)
        self.subscribed = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()
        assert self.subscribed.wait(timeout=30), "no subscription"

    def _run(self) -> None:
        url = f"ws://127.0.0.1:{self.port}"
        with (
            contextlib.suppress(ConnectionClosed, TimeoutError),
            # max_size: the map's frame is 2.5 MB (the Foxglove app takes any size).
            connect(url, subprotocols=[SUBPROTOCOL], open_timeout=10, max_size=None) as ws,
        ):
            while not set(self.topics) <= set(self.channels):
                message = json.loads(ws.recv(timeout=10))
                if message["op"] == "advertise":
                    self.channels |= {c["topic"]: c for c in message["channels"]}
            subscriptions = [
                {"id": sid, "channelId": self.channels[t]["id"]} for t, sid in self.topics.items()
            ]
            ws.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))
            self.subscribed.set()
            while True:
                frame = ws.recv(timeout=30)
                if isinstance(frame, bytes) and frame[0] == MESSAGE_DATA:
                    sid, log_time = struct.unpack_from("<IQ", frame, 1)
                    self.frames.append((sid, log_time, frame[13:]))


def test_a_run_streams_its_scene_and_map_to_a_foxglove_client(s1_resources: Any) -> None:
    config = make_config(None, scenario=S1_PATH, network="ah", behaviour="nb", max_time=8)
    clients: list[Client] = []

    def on_serving(port: int) -> None:
        clients.append(Client(port, {"/scene": 1, "/map": 2}))

    # Paced at 4x real time (2 s): the client is subscribed before the mission starts.
    result = run_and_record(
        config, s1_resources, None, serve=("127.0.0.1", 0), speed=4.0, on_serving=on_serving
    )
    assert result.sim_time_s == 8.0
    (client,) = clients
    client.thread.join(timeout=30)  # the server closed the connection at the end
    assert not client.thread.is_alive()
    frames, channels = client.frames, client.channels
    assert channels["/scene"]["encoding"] == "protobuf"
    assert channels["/scene"]["schemaName"] == "foxglove.SceneUpdate"
    schema = fg.SceneUpdate.get_schema()
    decode = DecoderFactory().decoder_for(
        "protobuf", Schema(id=1, name=schema.name, encoding="protobuf", data=schema.data)
    )
    assert decode is not None
    scenes = [decode(data) for sid, _, data in frames if sid == 1]
    # One scene per 0.2 s of the 8 s mission (and the final one); robots in each.
    assert len(scenes) >= 35
    robots = {e.id for e in scenes[-1].entities if e.id.startswith("robot/")}
    assert robots == {"robot/robot_1", "robot/robot_2", "robot/robot_3"}
    # The map was logged before the client subscribed: it is sent again on subscription.
    assert [sid for sid, _, _ in frames].count(2) >= 1
    times = [t for sid, t, _ in frames if sid == 1]
    # In mission order, 0.2 s apart (the first may go before the subscription is
    # processed: the server handles it on its own thread).
    assert times == sorted(times) and 7.0e9 <= times[-1] - times[0] <= 8.0e9


def test_a_port_in_use_is_a_clear_error_before_the_run(s1_resources: Any) -> None:
    config = make_config(None, scenario=S1_PATH, network="ah", behaviour="nb", max_time=8)
    ports: list[int] = []

    def second_server(port: int) -> None:
        ports.append(port)
        with pytest.raises(InputError, match=r"--foxglove-port.*in use"):
            run_and_record(config, s1_resources, None, serve=("127.0.0.1", port))

    run_and_record(config, s1_resources, None, serve=("127.0.0.1", 0), on_serving=second_server)
    assert ports


def test_the_cli_refuses_a_port_in_use_in_one_line_and_writes_nothing(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        record = tmp_path / "run.mcap"
        args = ["run", str(S1_PATH), "--foxglove", "--foxglove-port", str(port)]
        outcome = in_process(capsys, monkeypatch, *args, "--record", str(record))
    assert outcome.returncode == 2
    assert len(outcome.stderr.strip().splitlines()) == 1 and "--foxglove-port" in outcome.stderr
    assert list(tmp_path.iterdir()) == []


def test_subscription_churn_neither_grows_the_recording_nor_floods_the_server(
    s1_resources: Any, tmp_path: Path
) -> None:
    """A client subscribing to the map and unsubscribing in a loop once had it re-sent
    11,449 times in 15 s (the process at 2.4 GB, the recording at 180 MB): now the file
    holds the map once, whatever clients do, and the server re-sends it at most every
    RESEND_PERIOD s; a client that subscribes afterwards still gets it."""
    from mcap.reader import make_reader

    from mrcomm.experiment import recording

    sent: list[str] = []
    original = recording.RecordingSink.resend_due

    def counting(sink: recording.RecordingSink) -> None:
        before = dict(sink._resent)
        original(sink)
        sent.extend(t for t, when in sink._resent.items() if before.get(t) != when)

    config = make_config(None, scenario=S1_PATH, network="ah", behaviour="nb", max_time=8)
    late: list[Client] = []

    def churn(port: int) -> None:
        with connect(f"ws://127.0.0.1:{port}", subprotocols=[SUBPROTOCOL], open_timeout=10,
                     max_size=None) as ws:  # fmt: skip
            channels: dict[str, Any] = {}
            while "/map" not in channels:
                message = json.loads(ws.recv(timeout=10))
                if message["op"] == "advertise":
                    channels |= {c["topic"]: c for c in message["channels"]}
            for k in range(1000):
                ws.send(json.dumps({"op": "subscribe", "subscriptions": [
                    {"id": k, "channelId": channels["/map"]["id"]}]}))  # fmt: skip
                ws.send(json.dumps({"op": "unsubscribe", "subscriptionIds": [k]}))
        late.append(Client(port, {"/map": 7}))  # after the churn: still gets the map

    path = tmp_path / "churn.mcap"
    recording.RecordingSink.resend_due = counting  # type: ignore[method-assign]
    try:
        run_and_record(config, s1_resources, path, serve=("127.0.0.1", 0), speed=2.0,
                       on_serving=churn)  # fmt: skip
    finally:
        recording.RecordingSink.resend_due = original  # type: ignore[method-assign]
    with path.open("rb") as stream:
        maps = sum(1 for _, channel, _ in make_reader(stream).iter_messages()
                   if channel.topic == "/map")  # fmt: skip
    assert maps == 1
    # 4 s of wall time: at most one re-send every RESEND_PERIOD s (and the late one).
    assert 1 <= sent.count("/map") <= 4 / recording.RESEND_PERIOD + 2, sent
    (client,) = late
    client.thread.join(timeout=30)
    assert [sid for sid, _, _ in client.frames].count(7) >= 1
