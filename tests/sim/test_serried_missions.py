"""serried on whole S1 missions: successful under AH + SLT at SPL 0-50 over five seeds,
the team kept together (no pair ever out of the 8 m range); in groups on S2 and S3,
every task completed."""

from __future__ import annotations

import pytest

from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission

pytestmark = pytest.mark.slow


@pytest.mark.parametrize("spl", [0.0, 25.0, 50.0])
def test_serried_succeeds_on_s1_over_five_seeds(spl: float) -> None:
    for seed in range(1, 6):
        config = make_config(
            scenario="data/scenarios/s1.yaml", network="ah", threshold="slt",
            behaviour="serried", spl=spl, seed=seed,
        )  # fmt: skip
        mission = run_mission(config).mission
        assert mission["successful"] and not mission["timed_out"], (spl, seed)
        # NB's robots end up 40 m apart; the group stays within communication range
        # (8 m), mostly within about the warning distance (the leader holds once a
        # mate's link warns): 4.2-7.6 m at the furthest over these runs.
        assert mission["max_separation"] < 8.0, (spl, seed, mission["max_separation"])


def test_serried_does_not_hold_for_ever_under_a_signal_threshold() -> None:
    # With SSD a wall between two close robots warns: the leader's hold would never end
    # (seeds 1-3 at SPL 25 timed out before holds gave way after hold_timeout).
    for seed in (1, 2, 3):
        config = make_config(
            scenario="data/scenarios/s1.yaml", network="ah", threshold="ssd",
            behaviour="serried", spl=25.0, seed=seed,
        )  # fmt: skip
        mission = run_mission(config).mission
        assert mission["successful"] and not mission["timed_out"], seed


@pytest.mark.parametrize("scenario, tasks, seed", [("s2", 20, 1), ("s2", 20, 3), ("s3", 60, 1)])
def test_serried_in_groups_completes_the_large_teams(scenario: str, tasks: int, seed: int) -> None:
    """S2 (10 robots) and S3 (30) · AH + SLT · SPL 25: every task completed before the
    limit (one group of ten completed 1 of S2's 20 tasks in 1,800 s; in S2's seed 3 the
    three groups jammed at the start area until a stopped follower made way for other
    groups' robots too: 2 of 20)."""
    config = make_config(
        scenario=f"data/scenarios/{scenario}/{scenario}.yaml", network="ah",
        threshold="slt", behaviour="serried", spl=25.0, seed=seed,
    )  # fmt: skip
    mission = run_mission(config).mission
    assert mission["tasks_completed"] == tasks and not mission["timed_out"]
