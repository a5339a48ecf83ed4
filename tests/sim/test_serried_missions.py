"""serried on whole S1 missions: successful under AH + SLT at SPL 0-50 over five seeds,
the team kept together (no pair ever out of the 8 m range)."""

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
