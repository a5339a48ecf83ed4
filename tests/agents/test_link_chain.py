"""Path quality (:mod:`mrcomm.agents.link_chain`): the best chain of good links to a
mate, judged by the robot's own sensor rule, and LF's trigger and hold acting on it."""

from __future__ import annotations

import numpy as np
import pytest

from mrcomm.agents.lf import LeaderFollowerExecutor
from mrcomm.agents.lf_machine import LfParams
from mrcomm.agents.link_chain import chain_links
from mrcomm.net.link_sensors import DistanceSensor, MeasuredSensor, ModelSensor, NoSensor
from mrcomm.net.signal.bundled import default_model
from mrcomm.net.signal.table import RssiTable
from mrcomm.world.geometry import Pose
from mrcomm.world.occupancy import OccupancyGrid

from .fakes import Harness, pose_of, task

ORIGIN = Pose(0.0, 0.0)
SLT = DistanceSensor(4.0)


def test_a_mate_in_direct_good_contact_is_one_link_away() -> None:
    assert chain_links(SLT, ORIGIN, "b", {"b": (3.0, 0.0)}, 4, 0.0) == 1


def test_a_chain_through_the_mate_between_counts_its_links() -> None:
    line = {"b": (3.5, 0.0), "c": (7.0, 0.0), "d": (10.5, 0.0)}
    assert chain_links(SLT, ORIGIN, "c", line, 4, 0.0) == 2
    assert chain_links(SLT, ORIGIN, "d", line, 4, 0.0) == 3
    # The hop limit: a chain longer than it does not count.
    assert chain_links(SLT, ORIGIN, "d", line, 2, 0.0) is None
    assert chain_links(SLT, ORIGIN, "c", line, 1, 0.0) is None


def test_the_fewest_links_win_and_a_broken_chain_is_none() -> None:
    # Two ways to e: over b, c (3 links) or over d (2 links).
    mates = {"b": (3.5, 0.0), "c": (7.0, 0.0), "d": (3.4, 1.9), "e": (7.0, 3.5)}
    assert chain_links(SLT, ORIGIN, "e", mates, 8, 0.0) == 2
    gap = {"b": (3.5, 0.0), "c": (8.0, 0.0)}  # b-c 4.5 m: in warning
    assert chain_links(SLT, ORIGIN, "c", gap, 8, 0.0) is None
    assert chain_links(SLT, ORIGIN, "x", gap, 8, 0.0) is None  # unknown mate


def test_no_sensor_never_warns_and_a_measured_sensor_judges_only_its_own_links() -> None:
    far = {"b": (100.0, 0.0), "c": (200.0, 0.0)}
    assert chain_links(NoSensor(), ORIGIN, "c", far, 2, 0.0) == 1
    measured = MeasuredSensor(-41.0)
    measured.update("b", -30.0, 0.0)  # good
    measured.update("c", -60.0, 0.0)  # in warning; b-c cannot be judged
    assert chain_links(measured, ORIGIN, "b", far, 4, 0.0) == 1
    assert chain_links(measured, ORIGIN, "c", far, 4, 0.0) is None


def test_the_signal_model_sees_the_wall_on_links_between_mates() -> None:
    # 10 m x 4 m, a wall across x = 5 m from y = 0 to 3 m (a gap at the top).
    occupied = np.zeros((80, 200), dtype=bool)
    occupied[:60, 99:101] = True
    sensor = ModelSensor(
        OccupancyGrid(occupied, 0.05), RssiTable.from_model(default_model()), -42.0
    )
    own = Pose(4.0, 2.0)
    assert sensor.warning("b", own, 6.0, 2.0, 0.0)  # 2 m behind the wall
    # The mate in the gap sees both: the chain goes round the wall.
    assert chain_links(sensor, own, "b", {"b": (6.0, 2.0), "c": (5.0, 3.6)}, 2, 0.0) == 2
    assert sensor.warning_between(4.0, 2.0, 6.0, 2.0) is True
    assert sensor.warning_between(5.0, 3.6, 6.0, 2.0) is False


def _lf(chain_hops: int) -> Harness:
    return Harness(LeaderFollowerExecutor, link_sensor=SLT, params=LfParams(chain_hops=chain_hops))


@pytest.mark.parametrize(("chain_hops", "expected"), [(1, "assigning"), (2, "na_navigating")])
def test_lf_triggers_only_when_no_good_chain_reaches_the_mate(
    chain_hops: int, expected: str
) -> None:
    h = _lf(chain_hops)
    h.assign([task("t", 10.0, 0.0), task("u", -10.0, 0.0)], team=("robot_1", "robot_2", "robot_3"))
    h.step()
    h.hear(pose_of("robot_2", 6.0, 0.0))  # 6 m: the direct link warns ...
    h.hear(pose_of("robot_3", 3.0, 0.0))  # ... robot_3 between: 3 m each side
    assert h.step(times=3) == expected
    # The mate between moves away: no chain is left, and LF triggers whatever the limit.
    h.hear(pose_of("robot_3", -3.0, 0.0))
    assert h.step(times=3) == "assigning"
