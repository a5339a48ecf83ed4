"""The operator console end to end, in headless Chromium driven by Selenium (Debian's
chromium and chromium-driver, installed by ``make system-deps``): ``mrcomm run
--console`` serves the page, the robots move on it, a task clicked on the map is
reassigned to another robot (which completes it, and its status reaches the task
assigner), and robots sent back for statuses lost at SPL 50 make the mission successful.
Loopback only. Waits are Selenium's explicit waits on what the page shows."""

from __future__ import annotations

import json
import subprocess
from collections.abc import Iterator
from typing import Any

import pytest

from tests import needs
from tests.conftest import S1_PATH

needs.module("selenium.webdriver")
needs.module("nicegui", extra="console")

from selenium.common.exceptions import StaleElementReferenceException  # noqa: E402 (after the skip for a missing package)
from selenium.webdriver.common.by import By  # noqa: E402 (after the skip for a missing package)
from selenium.webdriver.support.ui import WebDriverWait  # noqa: E402 (after the skip for a missing package)

from tests.console.chromium import (  # noqa: E402 (after the skip for a missing package)
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


@pytest.fixture
def browser() -> Iterator[Any]:
    driver = start_browser()
    yield driver
    driver.quit()


def _console(*options: str) -> tuple[subprocess.Popen[str], str]:
    port = free_port("127.0.0.1")
    args = ["run", str(S1_PATH), "--console", "--port", str(port), "--json", *options]
    proc = mrcomm_process(*args)
    return proc, console_url(proc)


def _result(proc: subprocess.Popen[str]) -> dict[str, Any]:
    out, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err
    return json.loads(out)


def test_robots_move_and_a_clicked_task_is_reassigned(browser: Any) -> None:
    proc, url = _console("--network", "wlan", "--speed", "10")
    try:
        open_page(browser, url, proc)
        wait = WebDriverWait(browser, 60, poll_frequency=0.2)
        wait.until(lambda d: attr(d, "#robot-robot_1", "cx"))
        first = (attr(browser, "#robot-robot_1", "cx"), attr(browser, "#robot-robot_1", "cy"))
        wait.until(lambda d: (attr(d, "#robot-robot_1", "cx"),
                              attr(d, "#robot-robot_1", "cy")) != first)  # fmt: skip
        # Task 7 is robot_1's last; click it on the map, pick robot_3, reassign.
        click(browser, "#task-7")
        wait.until(lambda d: "task 7" in d.find_element(By.ID, "selection").text)
        click(browser, "#pick-robot_3")
        click(browser, "#cmd-reassign")
        wait.until(lambda d: "reassign" in d.find_element(By.ID, "commands").text)
        # The mission ends; the page stays up with its final state and the result.
        status = lambda d: d.find_element(By.ID, "status").text  # noqa: E731
        WebDriverWait(browser, 240, poll_frequency=0.5).until(
            lambda d: "mission ended" in status(d)
        )
        assert proc.poll() is None
        open_page(browser, url, proc)  # a new page after the end: the server still answers
        wait.until(lambda d: "mission ended: successful · 7/7 tasks" in status(d))
        assert attr(browser, "#robot-robot_3", "cx")  # the final state on the map
        click(browser, "#quit")
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
    proc, url = _console(
        "--network", "wlan", "--spl", "50", "--seed", "3", "--speed", "20", "--exit-on-end"
    )  # fmt: skip
    try:
        open_page(browser, url, proc)
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
                click(browser, f"#{task}")
                click(browser, "#cmd-redo")
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
