"""LF acting on geometry rather than on the arrival of messages: a robot carried past
the communication limit regroups and rejoins; with predicted follower positions and
aged poses, leader holds no longer grow with message loss."""

from __future__ import annotations

import math
from statistics import mean
from typing import Any

import pytest

from mrcomm.metrics.timeline import ROLE
from mrcomm.run.config import make_config
from mrcomm.sim.mission import Mission, run_mission

pytestmark = pytest.mark.slow

S1 = "data/scenarios/s1.yaml"
#: LF with aged knowledge: holds judged on predicted follower positions, the leader's
#: position moved on for its age, mates' poses expiring after 1 s for collision avoidance.
AGED = {"hold_prediction": 2.0, "mate_extrapolation": 2.0, "mate_max_age": 1.0}


def _config(spl: float, seed: int, **params: Any) -> Any:
    behaviour = {"behaviour": params} if params else {}
    return make_config(
        scenario=S1, network="ah", threshold="slt", behaviour="lf", spl=spl, seed=seed,
        params=behaviour,
    )  # fmt: skip


def test_a_robot_carried_out_of_range_regroups_at_the_teams_last_known_position() -> None:
    mission = Mission(_config(0, 1))
    while mission.now < 90.0:  # seed 1: all three without roles, driving to tasks
        mission.step()
    assert all(e.state == "na_navigating" for e in mission.executors.values())
    mates_then = {r: mission.bases[r].true_xy for r in ("robot_1", "robot_2")}
    start = (16.39, 17.75)  # the start room, ~28 m from the team: beyond the 8 m range
    mission.bases["robot_3"].carry(*start)
    carried = mission.now
    regroup_target = None
    while not mission.done:
        mission.step()
        robot_3 = mission.executors["robot_3"]
        if robot_3.state == "regrouping" and regroup_target is None:
            mission.step()
            regroup_target = robot_3.navigation_target()
    result = mission.result()
    roles = [(i.label, i.start, i.end) for i in result.timelines["robot_3"].intervals
             if i.track == ROLE and i.start >= carried]  # fmt: skip
    labels = [label for label, _, _ in roles]
    # Its link monitor sees the team beyond the threshold, nobody answers its round, so
    # it drives back to where it last knew a mate to be ...
    assert labels[:2] == ["assigning", "regrouping"]
    assert regroup_target is not None
    assert min(math.dist(regroup_target, p) for p in mates_then.values()) < 1.0
    regrouping_end = roles[1][2]
    back = result.trajectories["robot_3"]
    where = min(back, key=lambda s: abs(s[0] - regrouping_end))
    assert min(math.dist(where[1:], p) for p in mates_then.values()) < 8.0
    # ... then rejoins the team in a role and the mission ends successfully.
    assert "follower" in labels or "leader" in labels
    assert result.mission["successful"] and not result.mission["timed_out"]


def _leader_disconnect(spl: float, **params: Any) -> float:
    runs = [run_mission(_config(spl, seed, **params)) for seed in (1, 2, 3, 4)]
    return mean(r.mission["leader_disconnect_time"] for r in runs)


def test_leader_holds_do_not_grow_with_loss_when_judged_on_geometry() -> None:
    # Seeds 1-10 (BENCHMARKS-style measurement in the closing note): the original LF
    # holds 38.8 s at SPL 0 and 132.7 s at SPL 75; with AGED 33.2 s and 40.2 s.
    original = _leader_disconnect(75) / _leader_disconnect(0)
    aged = _leader_disconnect(75, **AGED) / _leader_disconnect(0, **AGED)
    assert original > 2.5
    assert aged < 1.6


def test_with_a_hold_grace_the_team_stretches_past_the_limit_and_regroups() -> None:
    def run(seed: int, **params: Any) -> Any:
        return run_mission(_config(0, seed, **params))

    # The original LF holds at the first warning: the team never reaches the 8 m limit.
    assert all(run(seed).mission["max_separation"] < 8.0 for seed in (1, 2, 3))
    # Followers may stay in warning 30 s: seed 3 stretches to 16.7 m, a robot past the
    # limit regroups (drives back to its team's last known position), and the mission
    # still succeeds.
    stretched = run(3, hold_grace=30.0)
    assert stretched.mission["max_separation"] > 8.0
    regrouped = [
        rid
        for rid, tl in stretched.timelines.items()
        if any(i.track == ROLE and i.label == "regrouping" for i in tl.intervals)
    ]
    assert regrouped
    assert stretched.mission["successful"]


def test_with_path_quality_the_team_spreads_over_relay_chains_and_completes() -> None:
    # Seeds 1-10 at SPL 0 (closing note): direct links only 5.1 m furthest pair, 124.5 s
    # of NA movement, 329.5 s execution; chain_hops=3 with relaying 7.7 m, 279.4 s,
    # 293.6 s — the trigger fires only when no chain of good links reaches a mate.
    def run(seed: int, hops: int) -> Any:
        config = make_config(
            scenario=S1, network="ah", threshold="slt", behaviour="lf", spl=0, seed=seed,
            params={"behaviour": {"chain_hops": hops}, "network": {"relay": True}},
        )  # fmt: skip
        return run_mission(config).mission

    direct = [run(seed, 1) for seed in (1, 2, 3)]
    chained = [run(seed, 3) for seed in (1, 2, 3)]
    assert all(m["successful"] for m in direct + chained)
    assert (
        mean(m["max_separation"] for m in chained) > mean(m["max_separation"] for m in direct) + 1
    )
    assert mean(m["na_movement_time"] for m in chained) > 1.5 * mean(
        m["na_movement_time"] for m in direct
    )
