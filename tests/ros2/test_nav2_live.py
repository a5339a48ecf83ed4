"""A live S1 mission with every robot's agent on the Nav2 base (``mrcomm live --base
nav2``: ``mrcomm world --ros2`` serves the robots as Nav2 robots over real ROS 2, each
agent process sends NavigateToPose goals and reads amcl_pose / odom) completes and
matches the same mission simulated, within the live conformance tolerances
(tests/live/test_live_conformance.py), for NB and LF."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.live.helpers import journal
from tests.live.test_live_conformance import CASES, assert_matches_simulation, live_run

from .helpers import needs_ros2

pytestmark = [needs_ros2, pytest.mark.slow]


@pytest.mark.parametrize("name", sorted(CASES))
def test_nav2_mission_matches_simulation(name: str, tmp_path: Path) -> None:
    options = CASES[name]
    live = live_run(options, tmp_path, "--base", "nav2")
    assert_matches_simulation(live, options)
    # Every goal went over ROS 2 (none as a Zenoh base command): the world's journal
    # counts what its action servers took and how each goal ended.
    lines = journal(tmp_path, "world")
    served = next(e for e in lines if e["k"] == "base_server")
    assert served["server"] == "nav2"
    outcomes = served["outcomes"]
    assert served["goals"] >= 7 and outcomes.get("succeeded", 0) >= 7
    assert sum(outcomes.values()) <= served["goals"]
    assert next(e for e in lines if e["k"] == "end")["base_commands"] == 0
