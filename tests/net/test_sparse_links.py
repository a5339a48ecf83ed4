"""Teams of more than 30 robots get sparse per-pair link summaries: every link of the
task assigner, and the robot pairs that came within 10 m or whose link warned."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import mrcomm.net.links as links_module
from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission

ROOT = Path(__file__).resolve().parents[2]


def test_a_large_team_keeps_the_pairs_that_met(monkeypatch: pytest.MonkeyPatch) -> None:
    config = make_config(
        None,
        scenario=ROOT / "data" / "scenarios" / "s4" / "s4.yaml",
        network="wlan",
        spl=25,
        seed=1,
        max_time=20,
    )
    sparse = run_mission(config).summary()
    monkeypatch.setattr(links_module, "SPARSE_FROM", 10**6)
    full = run_mission(config).summary()
    robots = [f"robot_{i}" for i in range(1, 101)]
    assert len(full["links"]) == 101 * 100
    kept = sparse["links"]
    # Every pair kept is as the full summary has it, and is one that should be kept.
    for pair, summary in kept.items():
        assert full["links"][pair] == summary
        a, b = pair.split("->")
        if a in robots and b in robots:
            assert summary["min_distance"] <= 10.0 or summary["warnings"] > 0
    # Every pair left out is one of two robots that never came within 10 m.
    for pair, summary in full["links"].items():
        if pair not in kept:
            a, b = pair.split("->")
            assert a in robots and b in robots and summary["min_distance"] > 10.0
    assert all(f"{r}->assigner" in kept and f"assigner->{r}" in kept for r in robots)
    assert 0 < len(kept) < len(full["links"]) / 3
    # Nothing else changes: metrics (the assigner's links among them) and counts.
    assert {k: v for k, v in sparse.items() if k not in ("links", "wall_time_s")} == {
        k: v for k, v in full.items() if k not in ("links", "wall_time_s")
    }
    assert len(json.dumps(sparse)) < len(json.dumps(full)) / 2


def test_small_teams_keep_every_pair() -> None:
    config = make_config(
        None,
        scenario=ROOT / "data" / "scenarios" / "s3" / "s3.yaml",
        network="ah",
        threshold="slt",
        seed=1,
        max_time=5,
    )
    assert len(run_mission(config).summary()["links"]) == 31 * 30


def test_pair_sums_are_made_when_a_step_first_adds_to_them() -> None:
    """A run whose links never warn, break or measure a signal (a WLAN) holds no
    per-pair sums (3.2 GB of them for 10,000 robots), and its summaries read zeros;
    the first step that warns makes them, counting its warnings as onsets."""
    import numpy as np

    from mrcomm.net.links import LinkRecorder, LinkState

    ids = ("a", "b", "c")
    recorder = LinkRecorder(ids, robots=3)
    distance = np.array([[0.0, 3.0, 4.0], [3.0, 0.0, 5.0], [4.0, 5.0, 0.0]])
    quiet = np.zeros((3, 3), dtype=np.bool_)
    linked = np.ones((3, 3), dtype=np.bool_)
    for step in range(3):
        recorder.record(LinkState(ids, distance, None, None, quiet, linked), 0.1, 0.1 * step)
    assert recorder._time_warning is None and recorder._time_disconnected is None
    assert recorder._min_rssi is None
    assert recorder.summaries()["a->b"] == {
        "min_distance": 3.0, "max_distance": 3.0, "min_rssi": None, "time_in_warning": 0.0,
        "warnings": 0, "time_disconnected": 0.0,
    }  # fmt: skip
    warned = quiet.copy()
    warned[0, 1] = True
    for step in range(3, 6):
        recorder.record(LinkState(ids, distance, None, None, warned, linked), 0.1, 0.1 * step)
    summary = recorder.summaries()["a->b"]
    assert summary["warnings"] == 1 and summary["time_in_warning"] == pytest.approx(0.3)
    assert recorder._time_disconnected is None
