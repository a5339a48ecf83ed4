"""Which mates a live agent treats as gone (``live.mates``): a vanished token, or a
mate silent past the link lease while its token stays (a hung process); neither a
pause of the whole team nor of the watching process itself makes a mate silent."""

from __future__ import annotations

from mrcomm.live.mates import STEP_GAP_CAP, MateWatch


def steps(watch: MateWatch, start: float, end: float, samples: dict[str, int]) -> float:
    """Step ``watch`` every 0.1 wall s from ``start`` to ``end``; returns ``end``."""
    wall = start
    while wall < end - 1e-9:
        wall = round(wall + 0.1, 6)
        watch.step(wall, samples)
    return wall


def test_a_mate_silent_past_the_window_is_gone_until_heard_again() -> None:
    watch = MateWatch(["robot_2", "robot_3"], window=10.0)
    present = {"robot_2": {1}, "robot_3": {1}}
    samples = {"robot_2": 1, "robot_3": 1}
    wall = steps(watch, 0.0, 1.0, samples)  # both heard at the first step (clock 0)
    assert watch.changes(present) == [] and not watch.silent
    # robot_3 keeps publishing, robot_2 falls silent (its token stays).
    while watch.clock < 10.0 - 1e-6:
        samples["robot_3"] += 1
        wall = steps(watch, wall, wall + 0.1, samples)
    assert watch.silent == set()  # 10 s of silence: not yet past the window
    samples["robot_3"] += 1
    wall = steps(watch, wall, wall + 0.1, samples)
    assert watch.silent == {"robot_2"}
    assert watch.changes(present) == [("robot_2", False)]
    assert watch.changes(present) == []  # reported once
    samples["robot_2"] += 1  # heard again
    steps(watch, wall, wall + 0.1, samples)
    assert watch.changes(present) == [("robot_2", True)] and not watch.gone


def test_a_vanished_token_is_gone_and_an_unseen_mate_is_not_judged() -> None:
    watch = MateWatch(["robot_2", "robot_3"], window=10.0)
    present: dict[str, set[int]] = {"robot_2": {7}}
    assert watch.changes(present) == []  # robot_3 never seen: not judged
    present["robot_2"] = set()
    assert watch.changes(present) == [("robot_2", False)]
    present["robot_2"] = {7}
    assert watch.changes(present) == [("robot_2", True)]
    # A mate never heard (no assignment yet: no poses) is not silent, however long.
    steps(watch, 0.0, 60.0, {})
    assert not watch.silent


def test_pauses_of_the_team_or_of_the_watcher_make_no_mate_silent() -> None:
    """No step for 30 s (the world stopped, or this process stopped) adds at most
    STEP_GAP_CAP to the active clock."""
    watch = MateWatch(["robot_2"], window=10.0)
    samples = {"robot_2": 1}
    wall = steps(watch, 0.0, 5.0, samples)
    before = watch.clock
    watch.step(wall + 30.0, samples)  # the first step after a 30 s pause
    assert watch.clock - before == STEP_GAP_CAP
    assert not watch.silent
    watch.step(wall + 29.0, samples)  # a wall clock read out of order counts nothing
    assert watch.clock - before == STEP_GAP_CAP
