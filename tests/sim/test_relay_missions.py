"""Relaying on whole missions: off by default (results unchanged), on with
``network.relay``: copies cross several hops in a 10-robot ad-hoc team, LF's AON works
through it, and a status crosses a line of three robots only with it."""

from __future__ import annotations

import subprocess
import sys

import pytest

from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission
from tests.conftest import ROOT, S1_PATH

S2 = ROOT / "data" / "scenarios" / "s2" / "s2.yaml"
LINE = ROOT / "tests" / "data" / "line" / "line.yaml"


@pytest.mark.slow
def test_a_ten_robot_team_relays_statuses_over_several_hops() -> None:
    config = make_config(
        None, scenario=S2, network="ah", behaviour="nb", spl=0, seed=3, max_time=900,
        params={"network": {"relay": True}},
    )  # fmt: skip
    summary = run_mission(config).summary()
    total = summary["relay"]["total"]
    hops = {int(h): n for h, n in total["hops"].items()}
    assert max(hops) >= 3 and total["received_copies"] > 0 and total["passed_on"] > 0
    # No node's agents got a message twice through relaying: every copy that reached a
    # node which had the message is counted as a duplicate, not delivered.
    assert total["duplicates"] > 0
    assert (
        "relay"
        not in run_mission(
            make_config(None, scenario=S2, network="ah", behaviour="nb", seed=2, max_time=60)
        ).summary()
    )


@pytest.mark.slow
@pytest.mark.parametrize("spl", [0, 25, 50])
def test_lf_with_relaying_succeeds_on_s1(spl: int, s1_resources) -> None:  # type: ignore[no-untyped-def]
    for seed in range(1, 6):
        config = make_config(
            None, scenario=S1_PATH, network="ah", threshold="slt", behaviour="lf", spl=spl,
            seed=seed, params={"network": {"relay": True}},
        )  # fmt: skip
        assert run_mission(config, s1_resources).summary()["mission"]["successful"], seed


def test_a_status_crosses_a_line_of_three_robots_only_with_relaying() -> None:
    # tests/data/line: robot_1's task is 13 m from the assigner on robot_3 (range 8 m);
    # robot_2, in the middle, hears it and passes it on.
    def mission(relay: bool) -> dict[str, object]:
        config = make_config(
            scenario=str(LINE), network="ah", threshold="none", behaviour="nb", seed=1,
            params={"network": {"relay": relay}},
        )  # fmt: skip
        return run_mission(config).summary()

    assert mission(False)["mission"]["failed_tasks"] == ["1"]
    relayed = mission(True)
    assert relayed["mission"]["successful"]
    assert relayed["relay"]["nodes"]["robot_3"]["hops"].get("2", 0) >= 1


@pytest.mark.slow
def test_store_and_forward_delivers_the_statuses_sent_out_of_range(s1_resources) -> None:  # type: ignore[no-untyped-def]
    # S1 · AH · NB at SPL 0: tasks 1 and 6 are completed where no mate can hear them;
    # relaying alone cannot help (seeds 1-10: 20 failed tasks with and without it), a
    # stored status travels with the robots to the assigner (0 failed).
    def failed(seed: int, **network: bool) -> list[str]:
        config = make_config(
            None, scenario=S1_PATH, network="ah", threshold="slt", behaviour="nb",
            spl=0.0, seed=seed, params={"network": network},
        )  # fmt: skip
        return run_mission(config, s1_resources).mission["failed_tasks"]

    for seed in (1, 2, 3):
        assert failed(seed, relay=True) == ["1", "6"]
        assert failed(seed, relay=True, relay_store=True) == []


def test_live_mode_refuses_store_and_forward_in_one_line(tmp_path) -> None:  # type: ignore[no-untyped-def]
    done = subprocess.run(
        [sys.executable, "-c", "from mrcomm.cli.main import app; app()", "live",
         str(S1_PATH), "--network", "ah", "--set", "network.relay=true",
         "--set", "network.relay_store=true", "--record-dir", str(tmp_path / "rec")],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert done.returncode == 2
    assert done.stderr.strip() == (
        "mrcomm: error: network.relay_store: store and forward is simulated only "
        "(live mode relays without it)"
    )
    assert not (tmp_path / "rec").exists()
