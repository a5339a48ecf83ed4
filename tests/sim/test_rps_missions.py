"""rps on whole S1 missions: successful under AH + SLT at SPL 0-50 over five seeds (the
statuses lost out of range reach the assigner at the rendezvous)."""

from __future__ import annotations

import pytest

from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission

pytestmark = pytest.mark.slow


@pytest.mark.parametrize("spl", [0.0, 25.0, 50.0])
def test_rps_succeeds_on_s1_over_five_seeds(spl: float) -> None:
    for seed in range(1, 6):
        config = make_config(
            scenario="data/scenarios/s1.yaml", network="ah", threshold="slt",
            behaviour="rps", spl=spl, seed=seed,
        )  # fmt: skip
        mission = run_mission(config).mission
        assert mission["successful"] and not mission["timed_out"], (spl, seed)
        assert mission["rendezvous_time"] > 0


def test_without_rendezvous_nb_loses_the_statuses_rps_brings_home() -> None:
    # The same mission as NB: statuses sent where nobody hears them are lost for good.
    nb = make_config(scenario="data/scenarios/s1.yaml", network="ah", threshold="slt",
                     behaviour="nb", seed=1)  # fmt: skip
    assert run_mission(nb).mission["failed_tasks"] == ["1", "6"]


def test_on_s2_a_robot_that_finished_early_passes_its_statuses_to_later_arrivals() -> None:
    """S2 (10 robots, the assigner on robot_1): robot_7 finishes first, gathers alone and
    idles at the meeting point before robot_1 comes. It used to keep its two statuses (7
    and 17 failed on every seed); an idle robot now gives every mate that arrives its
    statuses, and every task reaches the assigner."""
    for seed in range(1, 5):
        config = make_config(
            scenario="data/scenarios/s2/s2.yaml", network="ah", threshold="slt",
            behaviour="rps", spl=0.0, seed=seed,
        )  # fmt: skip
        mission = run_mission(config).mission
        assert mission["successful"] and mission["failed_tasks"] == [], seed
