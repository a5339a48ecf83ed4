"""Progress on long commands: on a terminal (a pseudo-terminal made by ``script``),
``mrcomm run`` of S2 draws its line on stderr — mission clock, tasks, robots, rate —
and prints the same result; with ``--json`` or ``--quiet`` nothing but the result;
piped, nothing at all on stderr. The line only reads the mission: same result."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from mrcomm.cli.progress import MissionProgress, ProgressLine
from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission
from tests.conftest import ROOT

S2 = ROOT / "data" / "scenarios" / "s2" / "s2.yaml"
ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")
pytestmark = pytest.mark.skipif(shutil.which("script") is None, reason="needs script(1)")


def _on_terminal(tmp_path: Path, *args: str) -> tuple[str, str]:
    """What a terminal shows (stderr; stdout goes to a file) and the file."""
    out = tmp_path / "stdout.txt"
    command = " ".join([sys.executable, "-m", "mrcomm", *args]) + f" > {out}"
    log = tmp_path / "terminal.log"
    env = {**os.environ, "COLUMNS": "120", "TERM": "xterm"}
    subprocess.run(["script", "-qec", command, str(log)], cwd=ROOT, env=env, check=True,
                   capture_output=True, timeout=300)  # fmt: skip
    lines = log.read_text(errors="replace").replace("\r", "\n").splitlines()
    shown = [ANSI.sub("", line) for line in lines if not line.startswith("Script ")]
    return "\n".join(line for line in shown if line.strip()), out.read_text()


RUN = ("run", str(S2), "--network", "ah", "--spl", "25", "--max-time", "300")


def test_run_shows_progress_on_a_terminal(tmp_path: Path) -> None:
    shown, stdout = _on_terminal(tmp_path, *RUN)
    assert re.search(
        r"mission .*\d+/300 s · tasks heard \d+/20 · 10 robots · ×\d+ real time · ETA", shown
    ), shown
    assert "AH_NB_SPL25 on S2 (seed 1)" in stdout


def test_json_and_quiet_show_nothing_but_the_result(tmp_path: Path) -> None:
    shown, stdout = _on_terminal(tmp_path, *RUN, "--json")
    assert shown == ""
    assert json.loads(stdout)["mission"]["tasks_total"] == 20
    shown, stdout = _on_terminal(tmp_path, *RUN, "--quiet")
    assert shown == "" and "AH_NB_SPL25 on S2 (seed 1)" in stdout


def test_piped_stderr_gets_no_progress() -> None:
    proc = subprocess.run([sys.executable, "-m", "mrcomm", *RUN[:2], "--max-time", "20"],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)  # fmt: skip
    assert proc.returncode == 0 and proc.stderr == ""


def test_the_line_changes_no_result(s1_resources: object) -> None:
    config = make_config(None, scenario=ROOT / "data/scenarios/s1.yaml", network="ah", spl=25,
                         behaviour="lf", threshold="slt", seed=3)  # fmt: skip
    seen: list[float] = []
    with ProgressLine("mission", config.max_time, enabled=False) as line:
        watched = MissionProgress(line)
        result = run_mission(config, s1_resources, None, lambda m: (seen.append(m.now), watched(m)))
    plain = run_mission(config, s1_resources)
    assert len(seen) > 100
    assert result.summary()["mission"] == plain.summary()["mission"]


def test_check_report_and_scenario_make_show_progress(tmp_path: Path) -> None:
    shown, _ = _on_terminal(tmp_path, "check", "behaviour.nb", "--only", "api", "--only",
                            "determinism")  # fmt: skip
    assert re.search(r"check .*\d/2 done · behaviour\.nb: (api|determinism)", shown), shown
    shown, _ = _on_terminal(tmp_path, "scenario", "make", "--out", str(tmp_path / "g"), "--map",
                            "grid", "--size", "20x15", "--robots", "3", "--tasks", "3")  # fmt: skip
    # A small map is drawn faster than the line redraws (10 times a second): either stage.
    assert re.search(r"scenario make .*(drawing the grid map|checking that every start)", shown)
    db = tmp_path / "r.duckdb"
    for spl in ("0", "50"):
        subprocess.run([sys.executable, "-m", "mrcomm", "run", "s1", "--network", "ah", "--spl",
                        spl, "--db", str(db), "--max-time", "60"], cwd=ROOT, check=True,
                       capture_output=True, timeout=300)  # fmt: skip
    shown, stdout = _on_terminal(tmp_path, "report", "--db", str(db), "--out",
                                 str(tmp_path / "rep"), "--no-svg")  # fmt: skip
    assert re.search(r"report .*\d+ figures drawn, \d+ encoded", shown), shown
    assert "report.html" in stdout
