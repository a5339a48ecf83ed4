"""Team-scale metrics of whole missions: work rate, time connected to the assigner and
the largest connected group, from the same facts in every mode."""

from __future__ import annotations

import pytest

from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission
from tests.conftest import ROOT, S1_PATH

S2 = ROOT / "data" / "scenarios" / "s2" / "s2.yaml"


@pytest.mark.slow
def test_an_ad_hoc_team_that_splits_up_is_measured_as_split() -> None:
    result = run_mission(
        make_config(
            None, scenario=S2, network="ah", threshold="slt", behaviour="nb", seed=1, spl=0,
            max_time=200,
        )
    )  # fmt: skip
    m = result.summary()["mission"]
    # Ten robots scattered to their tasks over a 60 x 40 m office with an 8 m range.
    assert 0.0 < m["largest_group_min"] < m["largest_group_mean"] < 1.0
    assert 0.0 < m["assigner_connected"] < 1.0
    # The same fraction from the per-pair link summaries, recomputed here; robot_1
    # hosts the assigner (always connected to it).
    end = result.sim_time_s
    fractions = [
        1 - result.links[f"{rid}->assigner"]["time_disconnected"] / end if rid != "robot_1" else 1.0
        for rid in result.robots
    ]
    assert m["assigner_connected"] == pytest.approx(sum(fractions) / len(fractions), abs=1e-6)


def test_a_wlan_team_is_always_one_group_and_reaches_its_assigner(s1_resources) -> None:  # type: ignore[no-untyped-def]
    config = make_config(None, scenario=S1_PATH, network="wlan", seed=1)
    result = run_mission(config, s1_resources)
    m = result.summary()["mission"]
    assert m["largest_group_mean"] == m["largest_group_min"] == 1.0
    assert m["assigner_connected"] == 1.0
    minutes = m["execution_phase_time"] / 60
    assert m["tasks_per_minute"] == pytest.approx(m["tasks_completed"] / minutes, rel=1e-5)
