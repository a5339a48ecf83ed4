"""The console without a browser: what it shows of a mission (the operator's knowledge
against ground truth, a lost status, stale poses faded) and how the session applies
commands between steps and keeps a mission with lost statuses open."""

from __future__ import annotations

import math
import re

import pytest

from mrcomm.console.session import ConsoleSession
from mrcomm.console.view import STALE_AFTER, Pixels, map_png, snapshot, svg
from mrcomm.run.config import make_config
from mrcomm.run.resources import ScenarioResources
from tests import needs
from tests.conftest import S1_PATH

needs.module("PIL")


def _session(spl: float, seed: int, network: str = "wlan") -> ConsoleSession:
    config = make_config(None, scenario=S1_PATH, network=network, behaviour="nb", spl=spl,
                         seed=seed)  # fmt: skip
    return ConsoleSession(config, ScenarioResources.load(S1_PATH), None, speed=math.inf)


def test_pixels_round_trip_and_the_map_image_is_the_grid() -> None:
    grid = ScenarioResources.load(S1_PATH).scenario.grid
    pixels = Pixels(grid)
    x, y = pixels.to_map(*pixels.to_px(12.3, 4.5))
    assert (x, y) == pytest.approx((12.3, 4.5))
    assert pixels.to_px(0.0, 0.0) == (0.0, grid.height)  # the map origin: bottom left
    assert map_png(grid)[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_lost_status_and_stale_poses_are_visible() -> None:
    # WLAN · NB · SPL 50, seed 3: the statuses of tasks 1, 3, 4 and 7 never arrive.
    session = _session(50, 3)
    mission = session.mission
    while not mission.finished:
        mission.step()
    view = snapshot(mission, session.operator, [])
    tasks = {t.id: t for t in view.tasks}
    lost = sorted(t.id for t in view.tasks if t.done and not t.received)
    assert lost == ["1", "3", "4", "7"]
    drawn = svg(view, Pixels(mission.resources.scenario.grid), truth=True)
    for task_id in lost:
        assert re.search(rf'id="task-{task_id}"[^>]*fill="#f0b400"', drawn)  # yellow
    assert tasks["2"].received and 'id="task-2"' in drawn
    # Without ground truth, only what the operator heard is shown.
    plain = svg(view, Pixels(mission.resources.scenario.grid), truth=False)
    assert "#f0b400" not in plain and "truth-" not in plain and "link-" not in plain


def test_a_robot_out_of_range_fades_with_its_age() -> None:
    session = _session(0, 1, network="ah")
    mission = session.mission
    while mission.now < 120:
        mission.step()
    view = snapshot(mission, session.operator, [])
    ages = {r.id: r.age for r in view.robots}
    stale = [rid for rid, age in ages.items() if age is not None and age > STALE_AFTER]
    assert stale  # on AH someone is out of the operator's range by now
    drawn = svg(view, Pixels(mission.resources.scenario.grid), truth=True)
    for rid in stale:
        assert re.search(rf'id="robot-{rid}"[^>]*fill-opacity="0.35"', drawn)


def test_commands_apply_between_steps_refusals_are_noted_and_end_closes() -> None:
    session = _session(50, 3)
    session.submit("reassign", "robot_9", "4")  # no such robot: refused, noted
    session.submit("pause", "robot_1")
    session.submit("resume", "robot_1")
    session.submit("end")  # the operator will not send anyone back: end when done
    result = session.run()
    assert session.notes and "unknown robot 'robot_9'" in session.notes[0]
    commands = result.operator["commands"]
    assert [(c["command"], c["robot"]) for c in commands] == [
        ("pause", "robot_1"), ("resume", "robot_1")]  # fmt: skip
    assert not result.mission["successful"] and not result.mission["timed_out"]
    assert session.view.ended and session.view.successful is False


def test_a_console_keeps_a_mission_with_lost_statuses_open_until_the_limit() -> None:
    config = make_config(None, scenario=S1_PATH, network="wlan", behaviour="nb", spl=50,
                         seed=3, max_time=400)  # fmt: skip
    session = ConsoleSession(config, None, None, speed=math.inf)
    result = session.run()
    assert result.sim_time_s == pytest.approx(400.0)  # robots done at ~180 s
    assert result.mission["failed_tasks"] == ["1", "3", "4", "7"]


def test_lf_groups_are_drawn_as_their_poses_tell_the_operator() -> None:
    config = make_config(None, scenario=S1_PATH, network="ah", behaviour="lf",
                         threshold="slt", seed=1)  # fmt: skip
    session = ConsoleSession(config, ScenarioResources.load(S1_PATH), None, speed=math.inf)
    mission, operator = session.mission, session.operator
    while not any(p.role == "follower" for p in operator.poses.values()):
        mission.step()
        assert mission.now < 300, "no LF group formed"
    view = snapshot(mission, operator, [])
    follower = next(r for r in view.robots if r.role == "follower")
    drawn = svg(view, Pixels(mission.resources.scenario.grid), truth=False)
    assert f'id="follows-{follower.id}"' in drawn and "· follower" in drawn


def test_a_page_cannot_flood_the_operator() -> None:
    """Commands are taken at a person's pace, with few waiting and a bound per
    mission; the rest is refused, said and counted (5,000 clicks once took the run
    process from 141 MB to 2.6 GB)."""
    from mrcomm.console import desk as d

    clock = [0.0]
    session = ConsoleSession(make_config(None, scenario=S1_PATH))
    session.desk = desk = d.OperatorDesk(session.operator, clock=lambda: clock[0])
    taken = sum(desk.submit("pause", "robot_1") for _ in range(5000))
    assert taken == d.BURST  # a burst, then the rate
    assert desk.refused == {f"more than {d.RATE:g} commands a second": 5000 - d.BURST}
    assert len(desk.notes) == d.MAX_NOTES
    taken = 0
    for _ in range(100):  # at the allowed pace: the queue (not yet sent) is the bound
        clock[0] += 1.0
        taken += desk.submit("resume", "robot_1")
    assert taken == d.QUEUE_BOUND - d.BURST
    assert desk.refused[f"{d.QUEUE_BOUND} commands already waiting"] == 100 - taken
    desk.apply(0.0)  # sent: the queue empties
    for minute in range(2, 400):
        clock[0] = 60.0 * minute
        for _ in range(d.BURST):
            desk.submit("pause", "robot_1")
        desk.apply(0.0)
    assert desk._accepted == d.MAX_COMMANDS
    assert desk.refused[f"more than {d.MAX_COMMANDS} commands in a mission"] > 0
