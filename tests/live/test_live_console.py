"""The operator console on a live mission: ``mrcomm live --console`` serves the page
from the operator's own team process; in headless Chromium the robots appear as the
operator hears them over Zenoh, and a task clicked on the map is reassigned to another
robot, which does it."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import ROOT

pytestmark = pytest.mark.slow
pytest.importorskip("nicegui", reason="the console extra (nicegui) is not installed")
webdriver = pytest.importorskip("selenium.webdriver", reason="selenium not installed")
if shutil.which("chromium") is None or shutil.which("chromedriver") is None:
    pytest.skip("chromium and chromium-driver are not installed (make system-deps)",
                allow_module_level=True)  # fmt: skip

from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.support.ui import WebDriverWait  # noqa: E402

from tests.console.test_console_browser import _attr, _click, _free_port, _open  # noqa: E402


def test_the_live_console_shows_the_robots_and_reassigns_a_task(tmp_path: Path) -> None:
    port = _free_port()
    args = [
        "live", str(ROOT / "data" / "scenarios" / "s1.yaml"), "--network", "wlan",
        "--behaviour", "nb", "--seed", "1", "--speed", "4", "--json",
        "--record-dir", str(tmp_path / "records"), "--console", "--port", str(port),
    ]  # fmt: skip
    env = {k: v for k, v in os.environ.items() if k != "PYTEST_CURRENT_TEST"}
    proc = subprocess.Popen(
        [sys.executable, "-c", "from mrcomm.cli.main import app; app()", *args],
        cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    options = webdriver.ChromeOptions()
    options.binary_location = shutil.which("chromium")
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1600,1000"):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=webdriver.ChromeService(shutil.which("chromedriver")),
                              options=options)  # fmt: skip
    try:
        _open(driver, f"http://127.0.0.1:{port}/", proc)
        wait = WebDriverWait(driver, 90, poll_frequency=0.2)
        for robot in ("robot_1", "robot_2", "robot_3"):  # heard over Zenoh
            wait.until(lambda d, r=robot: _attr(d, f"#robot-{r}", "cx"))
        assert not driver.find_elements(By.CSS_SELECTOR, "[id^=truth-]")  # none in live
        _click(driver, "#task-7")
        wait.until(lambda d: "task 7" in d.find_element(By.ID, "selection").text)
        _click(driver, "#pick-robot_3")
        _click(driver, "#cmd-reassign")
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
