"""Whole missions through a one-lane corridor (two halls joined by a 1 m lane, robots
scattered over both, tasks on both sides): robots crossing both ways used to meet in
the lane and jam for good; queueing at the lane's ends (the generated scenario's
``one_lane_width``) lets one end through at a time."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission
from mrcomm.world.generate.make import Request, make_scenario


@pytest.fixture(scope="module")
def corridor(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("corridor") / "lane"
    request = Request("corridor", 24.0, 8.0, 8, 16, "scattered", "virtual", 1, "lane")
    return make_scenario(request, out)


def without_queueing(scenario: Path) -> Path:
    """The same scenario with no one-lane passages."""
    data = yaml.safe_load(scenario.read_text())
    assert data["one_lane_width"] == 1.3  # what the generator writes
    data["one_lane_width"] = 0
    path = scenario.with_name("lane_no_queue.yaml")
    path.write_text(yaml.safe_dump(data))
    return path


def mission(scenario: Path, behaviour: str, **options: object) -> dict:
    config = make_config(None, scenario=scenario, behaviour=behaviour, **options)
    result = run_mission(config)
    summary = result.summary()
    queued = sum(robot["queued"] for robot in summary["robots"].values())
    return {**summary["mission"], "queued": queued}


@pytest.mark.parametrize("seed", [1, 2])
def test_nb_crosses_a_one_lane_corridor_both_ways_by_queueing(corridor: Path, seed: int) -> None:
    queued = mission(corridor, "nb", network="wlan", seed=seed, max_time=600)
    assert queued["tasks_completed"] == queued["tasks_total"] == 16
    assert not queued["timed_out"] and queued["end_time"] < 150
    assert queued["queued"] > 0
    jammed = mission(without_queueing(corridor), "nb", network="wlan", seed=seed, max_time=600)
    assert jammed["timed_out"] and jammed["tasks_completed"] < 10  # met in the lane


def test_lf_completes_through_a_one_lane_corridor(corridor: Path) -> None:
    result = mission(corridor, "lf", network="ah", threshold="slt", spl=25, seed=1, max_time=900)
    assert result["tasks_completed"] == 16 and result["successful"]
    assert result["queued"] > 0
