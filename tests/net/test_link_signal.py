"""Link state under signal thresholds (issue 3): line of sight picks the SVR model,
SSD/SLT/ESD warnings are recorded in missions, runs stay deterministic."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from mrcomm.net.link_sensors import MeasuredSensor, ModelSensor
from mrcomm.net.links import LinkModel
from mrcomm.net.network import AdHoc, AdHocParams
from mrcomm.net.signal.bundled import default_model
from mrcomm.net.signal.table import RssiTable
from mrcomm.net.signal_thresholds import ModelThreshold
from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission
from mrcomm.world.geometry import Pose
from mrcomm.world.occupancy import OccupancyGrid
from tests.conftest import ROOT, S1_PATH

TRACE = ROOT / "data" / "traces" / "s1_synthetic_esd.csv"


@pytest.fixture(scope="module")
def table() -> RssiTable:
    return RssiTable.from_model(default_model())


def _walled_room() -> OccupancyGrid:
    """10 m x 4 m at 5 cm, with a wall across x = 5 m from y = 0 to y = 3 m (a gap at
    the top), so two robots either side of it see each other only over the gap."""
    occupied = np.zeros((80, 200), dtype=bool)
    occupied[:60, 99:101] = True
    return OccupancyGrid(occupied, 0.05)


def test_a_wall_between_two_robots_switches_to_the_obstructed_model(table: RssiTable) -> None:
    grid = _walled_room()
    ids = ("a", "b")
    model = LinkModel(ids, grid, AdHoc(AdHocParams()), ModelThreshold(table, -42.0))
    behind_wall = model.update(np.array([[4.0, 1.0], [6.0, 1.0]]), 0.0)
    assert behind_wall.line_of_sight is not None and behind_wall.rssi is not None
    assert not behind_wall.line_of_sight[0, 1] and not behind_wall.line_of_sight[1, 0]
    assert behind_wall.rssi[0, 1] == pytest.approx(table.rssi_at(2.0, False))
    assert behind_wall.warning[0, 1]  # obstructed at 2 m: below -42 dBm
    # The same 2 m, both robots above the wall's end: line of sight, no warning.
    in_sight = model.update(np.array([[4.0, 3.5], [6.0, 3.5]]), 1.0)
    assert in_sight.line_of_sight is not None and in_sight.rssi is not None
    assert in_sight.line_of_sight[0, 1]
    assert in_sight.rssi[0, 1] == pytest.approx(table.rssi_at(2.0, True))
    assert not in_sight.warning[0, 1]
    assert in_sight.rssi[0, 1] > behind_wall.rssi[0, 1] + 2.0


def test_the_agent_side_sensor_agrees_with_the_network_model(table: RssiTable) -> None:
    grid = _walled_room()
    sensor = ModelSensor(grid, table, -42.0)
    assert sensor.warning("b", Pose(4.0, 1.0), 6.0, 1.0, 0.0)
    assert not sensor.warning("b", Pose(4.0, 3.5), 6.0, 3.5, 0.0)
    assert sensor.rssi("b", Pose(4.0, 1.0), 6.0, 1.0, 0.0) == pytest.approx(
        table.rssi_at(2.0, False)
    )


def test_measured_rssi_goes_stale() -> None:
    sensor = MeasuredSensor(-41.0, stale_after=5.0)
    assert not sensor.warning("b", Pose(0, 0), 0, 0, 0.0)  # no reading yet
    sensor.update("b", -50.0, 1.0)
    assert sensor.warning("b", Pose(0, 0), 0, 0, 3.0)
    assert not sensor.warning("b", Pose(0, 0), 0, 0, 7.0)  # pulse silent for 6 s


@pytest.mark.parametrize(
    "options",
    [
        {"network": "ah", "threshold": "slt"},
        {"network": "wlan", "threshold": "slt"},
        {"network": "ah", "threshold": "ssd"},
        {"network": "ah", "threshold": "esd", "rssi_trace": TRACE},
    ],
    ids=["ah-slt", "wlan-slt", "ah-ssd", "ah-esd"],
)
def test_nb_missions_record_warnings_deterministically(
    s1_resources, options: dict[str, object]
) -> None:  # type: ignore[no-untyped-def]
    def run(seed: int) -> dict[str, object]:
        config = make_config(None, scenario=S1_PATH, behaviour="nb", spl=25, seed=seed, **options)
        summary = run_mission(config, s1_resources).summary()
        summary.pop("wall_time_s")
        return summary

    a, b = run(4), run(4)
    assert json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)
    links = a["links"]
    assert isinstance(links, dict)
    robot_pairs = {k: v for k, v in links.items() if "assigner" not in k}
    assert sum(v["warnings"] for v in robot_pairs.values()) > 0
    assert sum(v["time_in_warning"] for v in robot_pairs.values()) > 0
    if options["threshold"] != "slt":
        assert all(v["min_rssi"] is not None for v in robot_pairs.values())
    if options["threshold"] == "ssd":
        # NB robots drift far apart: some pair saturates near the model's far value.
        assert min(v["min_rssi"] for v in robot_pairs.values()) < -55
    if options["network"] == "wlan":
        assert all(v["time_disconnected"] == 0 for v in links.values())


def test_slt_warning_time_matches_the_distance_record(s1_resources) -> None:  # type: ignore[no-untyped-def]
    result = run_mission(
        make_config(None, scenario=S1_PATH, network="ah", threshold="slt", seed=2), s1_resources
    )
    for pair, summary in result.links.items():
        if summary["max_distance"] is not None and summary["max_distance"] <= 4.0:
            assert summary["time_in_warning"] == 0, pair
        if summary["max_distance"] is not None and summary["max_distance"] > 8.0:
            assert summary["time_disconnected"] > 0, pair
    assert not math.isnan(result.mission["max_separation"])
