"""Driving the console's pages in headless Chromium (Debian's chromium and
chromium-driver, installed by ``make system-deps``), shared by the console's browser
tests. Import it after ``pytest.importorskip("selenium.webdriver")``."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from typing import Any

from selenium import webdriver
from selenium.common.exceptions import StaleElementReferenceException
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import WebDriverWait

from mrcomm.live.launcher import free_port
from tests.conftest import ROOT
from tests.needs import missing_commands

CHROMIUM = shutil.which("chromium")
DRIVER = shutil.which("chromedriver")
#: Why the browser tests cannot run here (None: they can).
MISSING = missing_commands("chromium", "chromedriver")

__all__ = ["free_port"]


def start_browser() -> Any:
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1600,1000"):
        options.add_argument(arg)
    return webdriver.Chrome(service=webdriver.ChromeService(DRIVER), options=options)


def mrcomm_process(*args: str) -> subprocess.Popen[str]:
    """``mrcomm ARGS`` in a process of its own, its output piped."""
    # Without pytest's marker: NiceGUI would take the run for its own screen tests.
    env = {k: v for k, v in os.environ.items() if k != "PYTEST_CURRENT_TEST"}
    return subprocess.Popen(
        [sys.executable, "-c", "from mrcomm.cli.main import app; app()", *args],
        cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip


def console_url(proc: subprocess.Popen[str]) -> str:
    """The console's address with its secret, as the command prints it on stderr."""
    assert proc.stderr is not None
    for line in proc.stderr:
        if line.startswith("console: "):
            return line.split()[1]
    raise AssertionError(f"no console address printed (exit {proc.wait()})")


def open_page(driver: Any, url: str, proc: subprocess.Popen[str]) -> None:
    """Load the page once the server answers (it starts within seconds)."""

    def loaded(d: Any) -> bool:
        assert proc.poll() is None, proc.stderr.read() if proc.stderr else ""
        try:
            d.get(url)
        except Exception:
            return False
        return bool(d.find_elements(By.ID, "clock"))

    WebDriverWait(driver, 60, poll_frequency=0.5).until(loaded)


def attr(driver: Any, css: str, name: str) -> str | None:
    """An attribute of the first element ``css`` finds (None: none, or redrawn)."""
    try:
        found = driver.find_elements(By.CSS_SELECTOR, css)
        return found[0].get_attribute(name) if found else None
    except StaleElementReferenceException:  # redrawn meanwhile
        return None


def click(driver: Any, css: str) -> None:
    """Click an element of the map, which the page redraws four times a second: found
    and clicked again if it was replaced in between."""

    def clicked(d: Any) -> bool:
        try:
            d.find_element(By.CSS_SELECTOR, css).click()
        except StaleElementReferenceException:
            return False
        return True

    WebDriverWait(driver, 10, poll_frequency=0.05).until(clicked)
