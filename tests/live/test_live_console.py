"""The operator console on a live mission: ``mrcomm live --console`` serves the page
from the operator's own team process; in headless Chromium the robots appear as the
operator hears them over Zenoh, and a task clicked on the map is reassigned to another
robot, which does it."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests import needs
from tests.conftest import ROOT

pytestmark = pytest.mark.slow
needs.module("nicegui", extra="console")
needs.module("selenium.webdriver")

from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.support.ui import WebDriverWait  # noqa: E402

from tests.console.chromium import (  # noqa: E402
    MISSING,
    attr,
    click,
    console_url,
    free_port,
    mrcomm_process,
    open_page,
    start_browser,
)

if MISSING is not None:
    pytest.skip(MISSING, allow_module_level=True)


def test_the_live_console_shows_the_robots_and_reassigns_a_task(tmp_path: Path) -> None:
    port = free_port("127.0.0.1")
    proc = mrcomm_process(
        "live", str(ROOT / "data" / "scenarios" / "s1.yaml"), "--network", "wlan",
        "--behaviour", "nb", "--seed", "1", "--speed", "4", "--json",
        "--record-dir", str(tmp_path / "records"), "--console", "--port", str(port),
    )  # fmt: skip
    driver = start_browser()
    try:
        open_page(driver, console_url(proc), proc)
        wait = WebDriverWait(driver, 90, poll_frequency=0.2)
        for robot in ("robot_1", "robot_2", "robot_3"):  # heard over Zenoh
            wait.until(lambda d, r=robot: attr(d, f"#robot-{r}", "cx"))
        assert not driver.find_elements(By.CSS_SELECTOR, "[id^=truth-]")  # none in live
        click(driver, "#task-7")
        wait.until(lambda d: "task 7" in d.find_element(By.ID, "selection").text)
        click(driver, "#pick-robot_3")
        click(driver, "#cmd-reassign")
        wait.until(lambda d: "robot_1, robot_2, robot_3" in d.find_element(By.ID, "commands").text)
        out, err = proc.communicate(timeout=300)
    finally:
        driver.quit()
        proc.kill()
    assert proc.returncode == 0, err[-2000:]
    result = json.loads(out)
    (command,) = result["operator"]["commands"]
    assert (command["command"], command["task_id"], command["robot"]) == (
        "reassign", "7", "robot_3")  # fmt: skip
    assert result["robots"]["robot_3"]["tasks_completed"] == 3
    assert result["mission"]["successful"]
