"""The operator console end to end, in headless Chromium driven by Selenium (Debian's
chromium and chromium-driver, installed by ``make system-deps``): ``mrcomm run
--console`` serves the page, the robots move on it, a task clicked on the map is
reassigned to another robot (which completes it, and its status reaches the task
assigner), and robots sent back for statuses lost at SPL 50 make the mission successful.
Loopback only. Waits are Selenium's explicit waits on what the page shows."""

from __future__ import annotations

import json
import os
import shutil
import socket
import subprocess
import sys
from collections.abc import Iterator
from typing import Any

import pytest

from tests.conftest import ROOT, S1_PATH

webdriver = pytest.importorskip("selenium.webdriver", reason="selenium not installed")
pytest.importorskip("nicegui", reason="the console extra (nicegui) is not installed")
CHROMIUM = shutil.which("chromium")
DRIVER = shutil.which("chromedriver")
if CHROMIUM is None or DRIVER is None:
    pytest.skip("chromium and chromium-driver are not installed (make system-deps)",
                allow_module_level=True)  # fmt: skip

from selenium.common.exceptions import StaleElementReferenceException  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.support.ui import WebDriverWait  # noqa: E402

MRCOMM = [sys.executable, "-c", "from mrcomm.cli.main import app; app()"]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture
def browser() -> Iterator[Any]:
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1600,1000"):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=webdriver.ChromeService(DRIVER), options=options)
    yield driver
    driver.quit()


def _console(*options: str) -> tuple[subprocess.Popen[str], str]:
    port = _free_port()
    args = [*MRCOMM, "run", str(S1_PATH), "--console", "--port", str(port), "--json", *options]
    # Without pytest's marker: NiceGUI would take the run for its own screen tests.
    env = {k: v for k, v in os.environ.items() if k != "PYTEST_CURRENT_TEST"}
    proc = subprocess.Popen(args, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=env)  # fmt: skip
    return proc, f"http://127.0.0.1:{port}/"


def _open(driver: Any, url: str, proc: subprocess.Popen[str]) -> None:
    """Load the page once the server answers (it starts within seconds)."""

    def loaded(d: Any) -> bool:
        assert proc.poll() is None, proc.stderr.read() if proc.stderr else ""
        try:
            d.get(url)
        except Exception:
            return False
        return bool(d.find_elements(By.ID, "clock"))

    WebDriverWait(driver, 60, poll_frequency=0.5).until(loaded)


def _attr(driver: Any, css: str, name: str) -> str | None:
    try:
        found = driver.find_elements(By.CSS_SELECTOR, css)
        return found[0].get_attribute(name) if found else None
    except StaleElementReferenceException:  # redrawn meanwhile
        return None


def _click(driver: Any, css: str) -> None:
    """Click an element of the map, which the page redraws four times a second: found
    and clicked again if it was replaced in between."""

    def clicked(d: Any) -> bool:
        try:
            d.find_element(By.CSS_SELECTOR, css).click()
        except StaleElementReferenceException:
            return False
        return True

    WebDriverWait(driver, 10, poll_frequency=0.05).until(clicked)


def _result(proc: subprocess.Popen[str]) -> dict[str, Any]:
    out, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err
    return json.loads(out)


def test_robots_move_and_a_clicked_task_is_reassigned(browser: Any) -> None:
    proc, url = _console("--network", "wlan", "--speed", "10")
    try:
        _open(browser, url, proc)
        wait = WebDriverWait(browser, 60, poll_frequency=0.2)
        wait.until(lambda d: _attr(d, "#robot-robot_1", "cx"))
        first = (_attr(browser, "#robot-robot_1", "cx"), _attr(browser, "#robot-robot_1", "cy"))
        wait.until(lambda d: (_attr(d, "#robot-robot_1", "cx"),
                              _attr(d, "#robot-robot_1", "cy")) != first)  # fmt: skip
        # Task 7 is robot_1's last; click it on the map, pick robot_3, reassign.
        _click(browser, "#task-7")
        wait.until(lambda d: "task 7" in d.find_element(By.ID, "selection").text)
        _click(browser, "#pick-robot_3")
        _click(browser, "#cmd-reassign")
        wait.until(lambda d: "reassign" in d.find_element(By.ID, "commands").text)
        result = _result(proc)
    finally:
        proc.kill()
    (command,) = result["operator"]["commands"]
    assert (command["command"], command["task_id"], command["robot"], command["former"]) == (
        "reassign", "7", "robot_3", "robot_1")  # fmt: skip
    assert result["robots"]["robot_3"]["tasks_assigned"] == 3
    assert result["robots"]["robot_3"]["tasks_completed"] == 3  # it did task 7 ...
    assert result["mission"]["successful"]  # ... and its status reached the assigner


def test_robots_sent_back_for_lost_statuses_end_the_mission_successful(browser: Any) -> None:
    # NB sends each status once: at SPL 50 some are lost. The console keeps the mission
    # open once the robots are done; the operator sends a robot back for every task
    # shown done but not received, until every status has arrived.
    proc, url = _console("--network", "wlan", "--spl", "50", "--seed", "3", "--speed", "20")
    try:
        _open(browser, url, proc)
        wait = WebDriverWait(browser, 120, poll_frequency=0.2,
                             ignored_exceptions=(StaleElementReferenceException,))  # fmt: skip
        lost = 'rect[data-done="true"][data-received="false"]'

        def ids(d: Any, css: str) -> list[str]:
            # Read in one script: the map is redrawn four times a second, so elements
            # found in one call may be gone by the next.
            script = "return Array.from(document.querySelectorAll(arguments[0])).map(e => e.id)"
            return list(d.execute_script(script, css))

        def finished_redos(d: Any) -> int:
            rows = d.find_element(By.ID, "commands").text.splitlines()
            return sum(" redo " in f" {r} " and not r.rstrip().endswith("-") for r in rows)

        def lost_or_ended(d: Any) -> list[str] | bool:
            return True if proc.poll() is not None else (ids(d, lost) or False)

        redone = 0
        while proc.poll() is None:
            found = wait.until(lost_or_ended)
            if found is True:
                break  # the mission ended
            for task in found:
                _click(browser, f"#{task}")
                _click(browser, "#cmd-redo")
                redone += 1
                # Until every command sent has finished (AON: every member has it): the
                # robot may do the task again within a step, so "not done" may never show.
                wait.until(lambda d, n=redone: proc.poll() is not None
                           or finished_redos(d) >= n)  # fmt: skip
        result = _result(proc)
    finally:
        proc.kill()
    assert redone >= 1
    commands = result["operator"]["commands"]
    assert {c["command"] for c in commands} == {"redo"}
    assert result["mission"]["successful"] and result["mission"]["failed_tasks"] == []
