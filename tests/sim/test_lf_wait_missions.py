"""lf-wait on whole S1 missions: successful under AH + SLT at SPL 0-50, and followers
really do tasks on detours while their leader waits."""

from __future__ import annotations

import pytest

from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission

pytestmark = pytest.mark.slow


@pytest.mark.parametrize("spl", [0.0, 25.0, 50.0])
def test_lf_wait_succeeds_on_s1_over_five_seeds(spl: float) -> None:
    detour_tasks = 0
    for seed in range(1, 6):
        config = make_config(
            scenario="data/scenarios/s1.yaml", network="ah", threshold="slt",
            behaviour="lf-wait", spl=spl, seed=seed,
        )  # fmt: skip
        mission = run_mission(config).mission
        assert mission["successful"] and not mission["timed_out"], (spl, seed)
        detour_tasks += mission["detour_tasks"]
        assert mission["leader_detour_wait_time"] >= 0
    assert detour_tasks >= 5  # S1's tasks 3 and 6 lie on the group's way
