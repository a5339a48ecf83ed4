"""``mrcomm console --replay``: a recording's frames as the console draws them — robots
where they were, task states, link states, events until the chosen time — and the page
in headless Chromium, played forward."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from mrcomm.console.replay import load_replay
from mrcomm.errors import InputError
from mrcomm.experiment.recording import run_and_record
from mrcomm.run.config import make_config
from mrcomm.run.resources import ScenarioResources
from tests import needs
from tests.conftest import S1_PATH

needs.module("mcap_protobuf", extra="console")


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any]:
    path = tmp_path_factory.mktemp("replay") / "run.mcap"
    config = make_config(None, scenario=S1_PATH, network="wlan", spl=50, behaviour="nb", seed=3)
    return path, run_and_record(config, ScenarioResources.load(S1_PATH), path)


def test_frames_are_the_recorded_mission(recording: tuple[Path, Any]) -> None:
    path, result = recording
    replay = load_replay(path)
    assert replay.label == "WLAN_NB_SPL50" and replay.end == pytest.approx(result.sim_time_s)
    assert (
        replay.grid.occupied.shape == ScenarioResources.load(S1_PATH).scenario.grid.occupied.shape
    )
    start = replay.at(0.0)
    assert {r.id for r in start.robots} == {"robot_1", "robot_2", "robot_3"}
    assert start.events_total == 0 or all(line.split()[0] == "0.0" for line in start.events)
    # The last frame: the lost statuses are tasks done but not communicated.
    end = replay.at(replay.end)
    lost = sorted(t.id for t in end.tasks if not t.received)
    assert lost == sorted(result.mission["failed_tasks"])
    # The robots where the trajectories put them at the end.
    for robot in end.robots:
        _, x, y = result.trajectories[robot.id][-1]
        assert robot.truth == pytest.approx((x, y), abs=1e-3)
    # Events up to the frame's time only.
    middle = replay.at(60.0)
    assert 0 < middle.events_total < end.events_total
    assert set(middle.links.values()) <= {"ok", "warning", "disconnected"}


def test_a_file_that_is_not_a_recording_is_one_line(tmp_path: Path) -> None:
    bad = tmp_path / "x.mcap"
    bad.write_text("hello")
    with pytest.raises(InputError, match="not an MCAP file"):
        load_replay(bad)


def test_the_replay_page_plays_the_mission(recording: tuple[Path, Any]) -> None:
    needs.module("selenium.webdriver")
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    from tests.console.chromium import (
        MISSING,
        console_url,
        free_port,
        mrcomm_process,
        open_page,
        start_browser,
    )

    if MISSING is not None:
        pytest.skip(MISSING)
    port = free_port("127.0.0.1")
    proc = mrcomm_process("console", "--replay", str(recording[0]), "--port", str(port))
    driver = start_browser()
    try:
        open_page(driver, console_url(proc), proc)
        wait = WebDriverWait(driver, 30, poll_frequency=0.2)
        wait.until(lambda d: d.find_elements(By.CSS_SELECTOR, "#robot-robot_1"))
        assert driver.find_element(By.ID, "clock").text.startswith("t = 0.0 s")  # spaces collapse
        driver.find_element(By.ID, "play").click()
        wait.until(lambda d: not d.find_element(By.ID, "clock").text.startswith("t = 0.0 s"))
    finally:
        driver.quit()
        proc.kill()
