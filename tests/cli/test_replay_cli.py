"""`mrcomm replay` from the command line: the summary read back from a recording, and
one-line errors (exit 2) for files that are missing or not MCAP."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from mrcomm.experiment.recording import run_and_record
from mrcomm.run.config import make_config
from mrcomm.run.result import MissionResult
from tests.conftest import ROOT, S1_PATH

MRCOMM = [sys.executable, "-c", "from mrcomm.cli.main import app; app()"]


def mrcomm(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*MRCOMM, *args], capture_output=True, text=True, cwd=ROOT, timeout=120)


@pytest.fixture(scope="module")
def recorded(
    s1_resources: Any, tmp_path_factory: pytest.TempPathFactory
) -> tuple[Path, MissionResult]:
    path = tmp_path_factory.mktemp("replay") / "s1.mcap"
    config = make_config(None, scenario=S1_PATH, spl=50, seed=5, max_time=30)
    return path, run_and_record(config, s1_resources, path)


def test_replay_json_reports_channels_result_and_outcomes(
    recorded: tuple[Path, MissionResult],
) -> None:
    path, result = recorded
    proc = mrcomm("replay", str(path), "--json")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    channels = {c["topic"]: c for c in out["channels"]}
    assert {"/map", "/scene", "/messages", "/result", "/robots/robot_1/pose"} <= set(channels)
    assert channels["/map"]["count"] == 1 and channels["/map"]["schema"] == "foxglove.Grid"
    assert channels["/scene"]["start"] == 0.0
    assert channels["/scene"]["end"] == pytest.approx(result.sim_time_s)
    assert out["message_count"] == sum(c["count"] for c in out["channels"])
    assert out["result"]["mission"] == result.mission
    assert out["result"]["config"]["label"] == "WLAN_NB_SPL50"
    for topic, counts in result.messages.items():
        expected = {k: counts[k] for k in ("received", "dropped_loss", "dropped_range")}
        assert out["outcomes"][topic] == expected
    assert out["metadata"]["mrcomm"]["seed"] == "5"


def test_replay_prints_a_human_summary(recorded: tuple[Path, MissionResult]) -> None:
    path, result = recorded
    proc = mrcomm("replay", str(path))
    assert proc.returncode == 0, proc.stderr
    text = proc.stdout
    assert "WLAN_NB_SPL50" in text
    assert "/robots/robot_2/pose" in text and "foxglove.SceneUpdate" in text
    pose = result.messages["pose"]
    assert str(pose["dropped_loss"]) in text and str(pose["received"]) in text


def test_replay_of_a_file_that_is_not_mcap_exits_2(tmp_path: Path) -> None:
    bogus = tmp_path / "notes.mcap"
    bogus.write_text("hello, I am not a recording\n")
    proc = mrcomm("replay", str(bogus))
    assert proc.returncode == 2
    assert proc.stderr.strip() == f"mrcomm: error: {bogus}: not an MCAP file (bad magic bytes)"
    assert "Traceback" not in proc.stderr


def test_replay_of_a_missing_or_truncated_file_exits_2(
    tmp_path: Path, recorded: tuple[Path, MissionResult]
) -> None:
    missing = tmp_path / "missing.mcap"
    proc = mrcomm("replay", str(missing))
    assert proc.returncode == 2
    assert proc.stderr.strip() == f"mrcomm: error: {missing}: no such file"
    truncated = tmp_path / "truncated.mcap"
    data = recorded[0].read_bytes()
    truncated.write_bytes(data[: len(data) // 2])
    proc = mrcomm("replay", str(truncated), "--json")
    assert proc.returncode == 2
    assert "corrupt or truncated MCAP file" in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1 and proc.stdout == ""
