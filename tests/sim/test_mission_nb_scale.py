"""Whole S2 missions (10 robots, office, clustered start) with NB that jammed until the
collision resolution scaled (BENCHMARKS.md "Do large teams complete?"): each used to
reach the 1800 s time limit, with robots yielding to poses heard long ago (SPL 0 seed 1)
or knotted at a door (SPL 25 seed 4)."""

from __future__ import annotations

import pytest

from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission
from tests.conftest import ROOT

S2_PATH = ROOT / "data" / "scenarios" / "s2" / "s2.yaml"


@pytest.mark.slow
@pytest.mark.parametrize(("spl", "seed"), [(0, 1), (25, 4)])
def test_formerly_jammed_s2_nb_run_completes_within_the_limit(spl: int, seed: int) -> None:
    config = make_config(
        None, scenario=S2_PATH, behaviour="nb", network="ah", threshold="slt",
        spl=spl, seed=seed, max_time=1800,
    )  # fmt: skip
    mission = run_mission(config).summary()["mission"]
    assert not mission["timed_out"]
    assert mission["tasks_completed"] == mission["tasks_total"] == 20
