"""LF in groups: a round of more members than a group elects several leaders, each
member follows the nearest; a round of at most ``group_size`` is the original rule."""

from __future__ import annotations

from mrcomm.agents.lf_groups import nearest_leader, round_leaders
from mrcomm.agents.role_round import RoleRound

RANK = {f"robot_{i}": float(i) for i in range(1, 11)}.__getitem__


def test_a_round_of_ten_in_groups_of_four_elects_the_three_best() -> None:
    scores = {f"robot_{i}": 0.1 * i for i in range(1, 11)}
    assert round_leaders(scores, RANK, 4) == ["robot_10", "robot_9", "robot_8"]
    assert round_leaders(scores, RANK, 5) == ["robot_10", "robot_9"]
    assert round_leaders(scores, RANK, 10) == ["robot_10"]


def test_members_without_work_never_lead() -> None:
    scores = {"robot_1": 0.0, "robot_2": 0.5, "robot_3": 0.0, "robot_4": 0.0, "robot_5": 0.0}
    assert round_leaders(scores, RANK, 2) == ["robot_2"]
    assert round_leaders({"robot_1": 0.0, "robot_2": 0.0}, RANK, 1) == []


def test_ties_go_to_the_lower_rank() -> None:
    scores = {"robot_3": 0.5, "robot_2": 0.5, "robot_1": 0.2, "robot_4": 0.5}
    assert round_leaders(scores, RANK, 2) == ["robot_2", "robot_3"]


def test_one_group_is_the_original_rule() -> None:
    """With no more members than a group, the one leader is RoleRound.best's."""
    rnd = RoleRound("robot_1")
    rnd.open(1, 0.3, 0.0)
    rnd.hear_utility("robot_2", 0.5)
    rnd.hear_utility("robot_3", 0.5)
    best, _ = rnd.best(RANK)
    assert round_leaders(rnd.scores, RANK, 3) == [best] == ["robot_2"]


def test_a_member_follows_the_nearest_leader() -> None:
    positions = {"robot_8": (10.0, 0.0), "robot_9": (2.0, 1.0), "robot_10": (-3.0, 0.0)}
    leaders = ["robot_10", "robot_9", "robot_8"]
    assert nearest_leader(leaders, positions, (0.0, 0.0), RANK) == "robot_9"
    assert nearest_leader(leaders, positions, (9.0, 0.0), RANK) == "robot_8"
    # A leader never heard of comes last; equal distances go to the lower rank.
    assert nearest_leader(["robot_5", "robot_8"], positions, (0.0, 0.0), RANK) == "robot_8"
    tie = {"robot_4": (1.0, 0.0), "robot_3": (-1.0, 0.0)}
    assert nearest_leader(["robot_4", "robot_3"], tie, (0.0, 0.0), RANK) == "robot_3"
