"""The report opens in a real browser: headless Chromium (Debian's ``chromium``, driven
by its own command line) loads report.html, every figure decodes to an image with a
size, and the console stays silent. A control page with a broken image and a console
error shows that the check would notice both.

How: a copy of the page gets a small script that, on ``load``, writes each image's
state into a ``data-images`` attribute; ``--dump-dom`` prints the resulting DOM and
``--enable-logging=stderr`` prints every console message as a ``CONSOLE`` line (the
report itself has no script, so any console message is a problem).
"""

from __future__ import annotations

import re
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from tests import needs

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
pytestmark = pytest.mark.skipif(
    CHROMIUM is None,
    reason=needs.reason("chromium not installed (make system-deps installs it as root)"),
)

FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--no-first-run",
    "--enable-logging=stderr",
    "--v=0",
    "--virtual-time-budget=10000",
)
PROBE = """<script>
window.addEventListener("load", () => {
  const states = [...document.images].map(
    (img) => img.alt.replace(/[;=]/g, "_") + "="
      + (img.complete && img.naturalWidth > 0 ? "ok" : "broken")
  );
  document.body.setAttribute("data-images", states.join(";"));
});
</script>"""


@dataclass
class PageCheck:
    images: dict[str, str]
    console: list[str]


def open_in_chromium(page: Path, tmp_path: Path) -> PageCheck:
    probe = tmp_path / f"probe-{page.name}"
    html = page.read_text()
    probe.write_text(html.replace("</body>", PROBE + "</body>"))
    # The copy lives next to nothing: figures must come from the page itself.
    profile = tmp_path / "chromium-profile"
    proc = subprocess.run(
        [
            CHROMIUM or "chromium",
            *FLAGS,
            f"--user-data-dir={profile}",
            "--dump-dom",
            probe.as_uri(),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    match = re.search(r'data-images="([^"]*)"', proc.stdout)
    assert match, "the load event never fired: " + proc.stdout[:500]
    images = dict(item.split("=", 1) for item in match.group(1).split(";") if item)
    console = [line for line in proc.stderr.splitlines() if ":CONSOLE" in line]
    return PageCheck(images, console)


def test_report_opens_in_chromium_with_every_figure(built: Any, tmp_path: Path) -> None:
    check = open_in_chromium(built.html, tmp_path)
    assert len(check.images) == len(built.figures) > 10
    broken = [name for name, state in check.images.items() if state != "ok"]
    assert broken == [], f"figures that did not load: {broken}"
    assert check.console == [], f"console messages: {check.console}"


def test_the_check_notices_broken_images_and_console_errors(tmp_path: Path) -> None:
    page = tmp_path / "control.html"
    page.write_text(
        "<!DOCTYPE html><html><body>"
        '<img src="data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR4'
        '2mP8z8BQDwAEhQGAhKmMIQAAAABJRU5ErkJggg==" alt="good">'
        '<img src="data:image/png;base64,AAAA" alt="bad">'
        '<script>console.error("something broke")</script>'
        "</body></html>"
    )
    check = open_in_chromium(page, tmp_path)
    assert check.images == {"good": "ok", "bad": "broken"}
    assert any("something broke" in line for line in check.console)
