"""Relaying in live mode: three robot processes in a line (the ends out of range), the
middle one passes the far robot's status on over Zenoh, and every agent gets it once."""

from __future__ import annotations

import json
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest

from .helpers import ROOT, journal

pytestmark = pytest.mark.slow

LINE = ROOT / "tests" / "data" / "line" / "line.yaml"


def live(record_dir: Path, relay: bool) -> dict:  # type: ignore[type-arg]
    args = [
        "live", str(LINE), "--network", "ah", "--threshold", "none", "--behaviour", "nb",
        "--seed", "1", "--speed", "5", "--json", "--record-dir", str(record_dir),
        "--set", f"network.relay={'true' if relay else 'false'}",
    ]  # fmt: skip
    done = subprocess.run(
        [sys.executable, "-c", "from mrcomm.cli.main import app; app()", *args],
        capture_output=True, text=True, timeout=240,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout)


def test_the_middle_robot_relays_a_status_to_the_assigner_out_of_range(tmp_path: Path) -> None:
    result = live(tmp_path / "relay", relay=True)
    mission = result["mission"]
    assert mission["successful"], mission["failed_tasks"]
    relay = result["relay"]
    # robot_1's status reached the assigner's host after two links, through robot_2.
    assert relay["nodes"]["robot_2"]["passed_on"] >= 1
    assert relay["nodes"]["assigner"]["hops"].get("2", 0) >= 1
    assert relay["total"]["duplicates"] >= 1  # copies of messages already had: dropped
    # The assigner was handed each status once, original or copy.
    received = Counter(
        (line["task_id"], line["robot"])
        for line in journal(tmp_path / "relay", "robot_3")
        if line.get("k") == "status_rx" and line.get("state") == "SUCCESS"
    )
    assert received == {("1", "robot_1"): 1, ("2", "robot_2"): 1, ("3", "robot_3"): 1}


def test_without_relaying_the_far_status_is_lost(tmp_path: Path) -> None:
    result = live(tmp_path / "plain", relay=False)
    assert result["mission"]["failed_tasks"] == ["1"]
    assert not result.get("relay")
