"""The avoidance part on its own: right of way, waiting until clear, and the grace
that doubles with each repeated conflict with the same mate."""

from __future__ import annotations

import math

from mrcomm.agents.avoidance import Avoidance
from mrcomm.agents.collision import MateState
from mrcomm.agents.executor_params import ExecutorParams
from mrcomm.world.geometry import Pose

HERE = Pose(0.0, 0.0, 0.0)
RANK = {"robot_1": 0.0, "robot_2": 1.0}.__getitem__


def coming(goal_dist: float) -> MateState:
    return MateState("robot_2", 0.8, 0.0, math.pi, 0.3, goal_dist)


def test_right_of_way_goes_to_the_robot_closer_to_its_goal() -> None:
    mine = Avoidance("robot_1", ExecutorParams(), RANK)
    conflict = mine.detect(HERE, [coming(goal_dist=9.0)], 0.0, lambda: 1.0)
    assert conflict is not None and conflict.mate == "robot_2" and not conflict.repeat
    assert mine.right_of_way  # 1 m to go against the mate's 9 m
    theirs = Avoidance("robot_1", ExecutorParams(), RANK)
    theirs.detect(HERE, [coming(goal_dist=0.5)], 0.0, lambda: 1.0)
    assert not theirs.right_of_way


def test_without_right_of_way_it_waits_until_the_mate_is_clear() -> None:
    params = ExecutorParams()
    avoidance = Avoidance("robot_1", params, RANK)
    mate = coming(goal_dist=0.5)
    avoidance.detect(HERE, [mate], 0.0, lambda: 5.0)
    mates = {"robot_2": mate}
    assert not avoidance.may_resume(lambda: HERE, mates, params.collision_pause + 0.1, 0.0)
    gone = {"robot_2": MateState("robot_2", 0.8, 3.0, math.pi / 2, 0.3, 0.5)}
    t = params.collision_pause + 0.2
    assert not avoidance.may_resume(lambda: HERE, gone, t, 0.0)  # clear only just now
    assert avoidance.may_resume(lambda: HERE, gone, t + params.clear_time, 0.0)


def test_the_grace_doubles_with_each_repeat() -> None:
    params = ExecutorParams()
    avoidance = Avoidance("robot_1", params, RANK)
    mate, now, graces = coming(goal_dist=9.0), 0.0, []
    for _ in range(3):
        conflict = avoidance.detect(HERE, [mate], now, lambda: 1.0)
        assert conflict is not None
        now += params.collision_pause
        assert avoidance.may_resume(lambda: HERE, {"robot_2": mate}, now, now - 1.0)
        # Within the grace the same mate is not a conflict again.
        assert avoidance.detect(HERE, [mate], now + 0.1, lambda: 1.0) is None
        graces.append(avoidance._grace_until["robot_2"] - now)
        now = avoidance._grace_until["robot_2"] + 0.1  # the next conflict, right after
    # 3 s, then doubled for a repeat within the 5 s window; the next comes after the
    # 6 s grace, outside the window: back to 3 s.
    assert graces == [params.resume_grace, 2 * params.resume_grace, params.resume_grace]


def test_a_pose_already_moved_on_from_does_not_stop_the_robot_again() -> None:
    """A mate last heard long ago stops the robot once; the same pose (nothing newer
    heard) never again, however often the grace runs out; news of it does."""
    params = ExecutorParams()
    avoidance = Avoidance("robot_1", params, RANK)
    ghost = coming(goal_dist=0.5)._replace(stamp=5.0)  # heard at 5 s, not since
    assert avoidance.detect(HERE, [ghost], 100.0, lambda: 9.0) is not None
    assert not avoidance.right_of_way
    mates = {"robot_2": ghost}
    moved_on = 100.0 + params.give_way_timeout
    assert avoidance.may_resume(lambda: HERE, mates, moved_on, 100.0)  # gave up waiting
    after_grace = moved_on + params.max_grace + 1.0
    assert avoidance.detect(HERE, [ghost], after_grace, lambda: 9.0) is None
    heard_again = ghost._replace(stamp=after_grace - 0.1)
    assert avoidance.detect(HERE, [heard_again], after_grace, lambda: 9.0) is not None


def test_a_pose_of_unknown_age_is_always_news() -> None:
    avoidance = Avoidance("robot_1", ExecutorParams(), RANK)
    mate = coming(goal_dist=9.0)  # no stamp
    assert avoidance.detect(HERE, [mate], 0.0, lambda: 1.0) is not None
    assert avoidance.may_resume(lambda: HERE, {"robot_2": mate}, 1.0, 0.0)
    assert avoidance.detect(HERE, [mate], 1.0 + 30.0, lambda: 1.0) is not None


def test_pauses_in_a_row_for_alternating_mates_make_a_knot_whose_grace_grows() -> None:
    """Waiting in turn for two mates, each pause starting as the robot moves on from
    the last: no mate repeats within its window, but the robot's run of pauses makes a
    knot, and the grace doubles for each pause beyond ``knot_pauses``."""
    params = ExecutorParams()
    rank = {"robot_1": 2.0, "robot_2": 0.0, "robot_3": 1.0}.__getitem__
    avoidance = Avoidance("robot_1", params, rank)
    ahead = {
        "robot_2": MateState("robot_2", 0.8, 0.1, math.pi, 0.0, 2.0),
        "robot_3": MateState("robot_3", 0.8, -0.1, math.pi, 0.0, 3.0),
    }
    now, graces, repeats = 0.0, [], []
    for _ in range(params.knot_pauses + 4):
        conflict = avoidance.detect(HERE, list(ahead.values()), now, lambda: 9.0)
        while conflict is None:  # both mates in their grace: free to move a while
            now += 0.1
            conflict = avoidance.detect(HERE, list(ahead.values()), now, lambda: 9.0)
        assert not avoidance.right_of_way
        repeats.append(conflict.repeat)
        since, now = now, now + params.give_way_timeout  # the mate never clears
        assert avoidance.may_resume(lambda: HERE, ahead, now, since)
        graces.append(avoidance.grace())
    assert not any(repeats)  # the per-mate rule alone would never grow the grace
    base = params.resume_grace
    assert graces[: params.knot_pauses] == [base] * params.knot_pauses
    assert graces[params.knot_pauses :] == [2 * base, 4 * base, 8 * base, params.max_grace]


def test_a_pause_long_after_moving_on_starts_a_new_run() -> None:
    params = ExecutorParams()
    avoidance = Avoidance("robot_1", params, RANK)
    mate = coming(goal_dist=9.0)
    now = 0.0
    for _ in range(params.knot_pauses + 2):
        assert avoidance.detect(HERE, [mate], now, lambda: 1.0) is not None
        now += params.collision_pause
        assert avoidance.may_resume(lambda: HERE, {"robot_2": mate}, now, now - 1.0)
        now = max(avoidance._grace_until["robot_2"], now + params.repeat_window) + 0.1
    assert avoidance.pauses_in_row == 1


def _static_knot(knot_pauses: int, seconds: float = 300.0) -> dict[str, float]:
    """Three robots standing within each other's event horizon, each with a goal
    (closest to its goal: robot_1, then robot_2, then robot_3), stepping only their
    avoidance: navigating (judging conflicts) or paused. The longest stretch each one
    spends free to move (navigating, no conflict), in seconds."""
    params = ExecutorParams(knot_pauses=knot_pauses)
    poses = {
        "robot_1": Pose(0.0, 0.0, 0.0),
        "robot_2": Pose(0.4, 0.0, math.pi),
        "robot_3": Pose(0.2, 0.3, -math.pi / 2),
    }
    goal = {"robot_1": 1.0, "robot_2": 2.0, "robot_3": 3.0}
    rank = {"robot_1": 0.0, "robot_2": 1.0, "robot_3": 2.0}.__getitem__
    robots = {r: Avoidance(r, params, rank) for r in poses}
    paused_since: dict[str, float | None] = dict.fromkeys(poses)
    free_since = dict.fromkeys(poses, 0.0)
    longest = dict.fromkeys(poses, 0.0)
    for tick in range(int(seconds * 10)):
        now = tick / 10
        for r, avoidance in robots.items():
            mates = {
                m: MateState(m, p.x, p.y, p.theta, 0.0, goal[m], now)
                for m, p in poses.items()
                if m != r
            }
            since = paused_since[r]
            if since is None:
                if avoidance.detect(poses[r], mates.values(), now, lambda r=r: goal[r]):
                    paused_since[r] = now
                    longest[r] = max(longest[r], now - free_since[r])
            elif avoidance.may_resume(lambda r=r: poses[r], mates, now, since):
                paused_since[r] = None
                free_since[r] = now
    return longest


def test_a_knot_of_three_frees_each_robot_for_a_while() -> None:
    """Without the knot rule (``knot_pauses`` never reached) the robot yielding to both
    others waits in turn for each, 10 s at a time, never free to move; with it, the
    graces grow until they overlap and every robot gets time to move (its base can then
    re-plan around the others)."""
    params = ExecutorParams()
    before = _static_knot(knot_pauses=10**6)
    assert before["robot_3"] < 1.0  # stopped again at once, for the other mate
    after = _static_knot(knot_pauses=params.knot_pauses)
    assert min(after.values()) >= 2 * params.resume_grace


def _mate(x: float, stamp: float) -> MateState:
    """robot_2 coming head-on at ``x`` m ahead, from a pose sent at ``stamp``."""
    return MateState("robot_2", x, 0.0, math.pi, 0.3, 9.0, stamp)


def test_on_receipt_a_pose_is_judged_once_when_it_arrives() -> None:
    """The original robots checked a mate in their pose callback (thesis line 798): a
    pose judged when it came is not judged again, so a mate whose later poses are lost
    never stops the robot on an old one. Every step (the default) it does."""
    every_step = Avoidance("robot_1", ExecutorParams(), RANK)
    on_receipt = Avoidance("robot_1", ExecutorParams(judge_poses="on_receipt"), RANK)
    assert on_receipt.on_receipt and not every_step.on_receipt
    far = _mate(3.0, stamp=0.0)  # heard 3 m ahead: no conflict
    for avoidance in (every_step, on_receipt):
        assert avoidance.detect(HERE, [far], 0.0, lambda: 1.0) is None
    # The robot drives 2.4 m on; nothing new is heard, so the old pose is 0.6 m ahead.
    closer = Pose(2.4, 0.0, 0.0)
    assert every_step.detect(closer, [far], 5.0, lambda: 1.0) is not None
    assert on_receipt.detect(closer, [far], 5.0, lambda: 1.0) is None
    # A new pose of the mate in the danger zone is judged as it arrives.
    assert on_receipt.detect(closer, [_mate(3.0, stamp=4.9)], 5.0, lambda: 1.0) is not None


def test_on_receipt_a_pose_that_came_during_the_grace_is_not_judged_after_it() -> None:
    params = ExecutorParams(judge_poses="on_receipt")
    avoidance = Avoidance("robot_1", params, RANK)
    mate = _mate(0.8, stamp=0.0)
    assert avoidance.detect(HERE, [mate], 0.0, lambda: 1.0) is not None
    assert avoidance.may_resume(lambda: HERE, {"robot_2": mate}, 1.0, 0.0)
    during = _mate(0.8, stamp=1.5)  # heard within the 3 s grace
    assert avoidance.detect(HERE, [during], 1.6, lambda: 1.0) is None
    assert avoidance.detect(HERE, [during], 10.0, lambda: 1.0) is None  # grace over: no news
