"""Judged near collisions against ground truth: the recorder of close encounters, the
check of each judgement, and whole runs where stale poses make false alarms."""

from __future__ import annotations

import numpy as np
import pytest

from mrcomm.metrics import labels as L
from mrcomm.metrics.timeline import Timeline
from mrcomm.run.config import make_config
from mrcomm.run.proximity import TOLERANCE, ProximityRecorder, judged_against_truth
from mrcomm.sim.mission import run_mission

ROBOTS = ("a", "b", "c")


def _distances(ab: float, ac: float = 9.0, bc: float = 9.0) -> np.ndarray:
    d = np.array([[0.0, ab, ac, 5.0], [ab, 0.0, bc, 5.0], [ac, bc, 0.0, 5.0], [5.0] * 4])
    return d


def test_the_recorder_keeps_each_close_interval_with_its_closest_approach() -> None:
    recorder = ProximityRecorder(ROBOTS, radius=1.0)
    for t, ab in [(0.0, 3.0), (0.1, 0.9), (0.2, 0.4), (0.3, 0.8), (0.4, 2.0), (0.5, 1.0)]:
        recorder.record(_distances(ab), t)
    assert recorder.encounters(end=0.6) == [("a", "b", 0.1, 0.4, 0.4), ("a", "b", 0.5, 0.6, 1.0)]


def test_the_recorder_names_every_close_pair_at_once() -> None:
    # Several pairs close at once: each interval is its own pair's, in order of start.
    recorder = ProximityRecorder(ROBOTS, radius=1.0)
    recorder.record(_distances(3.0, ac=0.5, bc=0.7), 0.0)
    recorder.record(_distances(0.2, ac=0.6, bc=2.0), 0.1)
    assert recorder.encounters(end=0.2) == [
        ("a", "c", 0.0, 0.2, 0.5),
        ("b", "c", 0.0, 0.1, 0.7),
        ("a", "b", 0.1, 0.2, 0.2),
    ]


def _judged(*events: tuple[float, str]) -> Timeline:
    timeline = Timeline("a")
    for t, mate in events:
        timeline.event(L.NEAR_COLLISION, t, mate=mate, kind="danger_zone", repeat=False)
    return timeline


def test_judgements_are_confirmed_false_or_missing() -> None:
    encounters = [("a", "b", 10.0, 12.0, 0.3), ("a", "c", 20.0, 21.0, 0.8), ("b", "c", 1, 2, 0.1)]
    counts = judged_against_truth(
        _judged((10.0 - TOLERANCE, "b"), (15.0, "b"), (20.5, "b")), encounters, 0.5
    )
    # b at 9.5 is confirmed (within the tolerance); b at 15 and at 20.5 are false alarms;
    # the encounter with c came no closer than 0.8 m: not a missed near collision.
    assert counts == {
        "near_collisions_confirmed": 1,
        "near_collisions_false": 2,
        "near_collisions_missed": 0,
    }
    # Nothing judged: the pass within 0.3 m of b is missed; c at 0.8 m is not; b–c is
    # not this robot's.
    assert judged_against_truth(_judged(), encounters, 0.5)["near_collisions_missed"] == 1


def _mission(**params: object) -> dict[str, object]:
    config = make_config(
        scenario="data/scenarios/s1.yaml",
        network="ah",
        threshold="slt",
        behaviour="lf",
        spl=75,
        seed=1,
        params={"behaviour": params} if params else {},
    )
    return run_mission(config).summary()


@pytest.mark.slow
def test_under_heavy_loss_old_poses_cause_false_alarms_that_aged_knowledge_removes() -> None:
    original = _mission()
    aged = _mission(mate_max_age=0.5, mate_extrapolation=0.5)
    for summary in (original, aged):
        mission = summary["mission"]
        assert mission["near_collisions"] == (
            mission["near_collisions_confirmed"] + mission["near_collisions_false"]
        )
        robots = summary["robots"].values()
        assert mission["near_collisions_false"] == sum(r["near_collisions_false"] for r in robots)
    # At SPL 75 three poses in four are lost: acting on the last one however old, many
    # judgements are of mates no longer within the danger radius (seeds 1-3: 48 of 120);
    # poses expiring after 0.5 s and moved on for their age, none (0 of 81).
    assert original["mission"]["near_collisions_false"] >= 10
    assert aged["mission"]["near_collisions_false"] <= 1
    assert aged["mission"]["near_collisions_confirmed"] >= 10


def test_a_large_team_s_close_pairs_are_those_of_every_pair_gathered() -> None:
    """The recorder reads the distance matrix's upper triangle a block of rows at a
    time; its encounters are those of gathering every pair in team order at once."""
    from mrcomm.net.links import distance_matrix
    from mrcomm.run.proximity import PROXIMITY_ROWS

    n = 2 * PROXIMITY_ROWS + 37
    robots = tuple(f"r{k}" for k in range(n))
    rng = np.random.default_rng(3)
    at = rng.uniform(0.0, 30.0, size=(n + 1, 2))  # and a last node that is not a robot
    recorder = ProximityRecorder(robots, radius=0.5)
    first, second = np.triu_indices(n, k=1)
    since: dict[int, float] = {}
    closest: dict[int, float] = {}
    expected: list[tuple[str, str, float, float, float]] = []
    for step in range(12):
        now = round(0.1 * step, 1)
        at[:n] += rng.normal(0.0, 0.3, size=(n, 2))
        distance = distance_matrix(at)
        recorder.record(distance, now)
        d = distance[first, second]
        near = np.flatnonzero(d <= 0.5).tolist()
        for k in [k for k in since if k not in set(near)]:
            expected.append(
                (robots[first[k]], robots[second[k]], since.pop(k), now, round(closest.pop(k), 4))
            )
        for k in near:
            if k not in since:
                since[k], closest[k] = now, float(d[k])
            closest[k] = min(closest[k], float(d[k]))
    expected += [
        (robots[first[k]], robots[second[k]], s, 1.2, round(closest[k], 4))
        for k, s in since.items()
    ]
    expected.sort(key=lambda e: (e[2], e[0], e[1]))
    assert len(expected) > 50
    assert recorder.encounters(end=1.2) == expected
