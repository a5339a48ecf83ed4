"""``mrcomm live --foxglove``: the world process streams the mission's ground truth (the
map, every robot's true pose, the links) to a Foxglove WebSocket server while the team
runs, read here by a client speaking the Foxglove protocol."""

from __future__ import annotations

import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from foxglove import messages as fg
from mcap.records import Schema
from mcap_protobuf.decoder import DecoderFactory

from mrcomm.live.launcher import free_port
from tests.experiment.test_foxglove_live import Client

from .helpers import ROOT

pytestmark = pytest.mark.slow


def _listening(port: int, proc: subprocess.Popen[str], seconds: float = 60.0) -> None:
    """Until the server accepts connections (polled; the process must stay up)."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        assert proc.poll() is None, proc.stderr.read() if proc.stderr else ""
        try:
            socket.create_connection(("127.0.0.1", port), timeout=0.2).close()
            return
        except OSError:
            continue
    raise AssertionError("the Foxglove server never listened")


def test_a_live_mission_streams_its_ground_truth_to_foxglove(tmp_path: Path) -> None:
    port = free_port("127.0.0.1")
    args = [
        "live", str(ROOT / "data" / "scenarios" / "s1.yaml"), "--network", "ah",
        "--behaviour", "nb", "--seed", "1", "--speed", "10", "--insecure",
        "--record-dir", str(tmp_path / "records"), "--foxglove", "--foxglove-port", str(port),
    ]  # fmt: skip
    proc = subprocess.Popen(
        [sys.executable, "-c", "from mrcomm.cli.main import app; app()", *args],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        _listening(port, proc)
        client = Client(port, {"/scene": 1, "/map": 2})
        proc.communicate(timeout=300)
        client.thread.join(timeout=30)
    finally:
        proc.kill()
    assert proc.returncode == 0
    schema = fg.SceneUpdate.get_schema()
    decode = DecoderFactory().decoder_for(
        "protobuf", Schema(id=1, name=schema.name, encoding="protobuf", data=schema.data)
    )
    assert decode is not None
    scenes = [decode(data) for sid, _, data in client.frames if sid == 1]
    assert len(scenes) > 100  # 5 Hz of mission time
    ids = {e.id for e in scenes[-1].entities}
    assert ids == {"robot/robot_1", "robot/robot_2", "robot/robot_3", "links"}
    states = {kv.value for s in scenes for e in s.entities if e.id == "links" for kv in e.metadata}
    assert "disconnected" in states  # AH: the robots drove out of each other's range
    assert any(sid == 2 for sid, _, _ in client.frames)  # the map, sent on subscription
