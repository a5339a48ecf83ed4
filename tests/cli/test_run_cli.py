"""`mrcomm run` from the command line: JSON output, the plot and bad input."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import ROOT, S1_PATH

MRCOMM = [sys.executable, "-c", "from mrcomm.cli.main import app; app()"]


def mrcomm(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*MRCOMM, *args], capture_output=True, text=True, cwd=cwd or ROOT, timeout=300
    )


def test_json_output_has_the_documented_keys(tmp_path: Path) -> None:
    plot = tmp_path / "s1.png"
    proc = mrcomm(
        "run",
        str(S1_PATH),
        "--network",
        "ah",
        "--spl",
        "25",
        "--seed",
        "3",
        "--json",
        "--plot",
        str(plot),
    )
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert {"config", "mission", "robots", "messages", "sim_time_s", "wall_time_s"} <= set(out)
    for key in (
        "successful",
        "failed_tasks",
        "tasks_completed",
        "execution_phase_time",
        "total_movement_time",
        "total_distance",
        "near_collisions",
        "delay_time",
        "idle_time",
        "min_separation",
        "max_separation",
    ):
        assert key in out["mission"], key
    assert set(out["robots"]) == {"robot_1", "robot_2", "robot_3"}
    assert out["config"]["network"] == "ah" and out["config"]["spl"] == 25
    assert {"sent", "received", "dropped_loss", "dropped_range"} <= set(out["messages"]["pose"])
    assert plot.exists() and plot.stat().st_size > 10_000
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_human_output_is_a_table() -> None:
    proc = mrcomm("run", str(S1_PATH), "--seed", "2")
    assert proc.returncode == 0, proc.stderr
    assert "Mission" in proc.stdout and "robot_1" in proc.stdout and "failed_tasks" in proc.stdout


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--network", "mesh"], "--network"),
        (["--spl", "120"], "spl"),
        (["--spl", "-1"], "spl"),
        (["--behaviour", "nbb"], "did you mean 'nb'"),
        (["--threshold", "ssd", "--network", "wlan"], "ssd"),
        (["--threshold", "sdd"], "did you mean"),
        (["--spl", "abc"], "spl"),
    ],
)
def test_bad_options_exit_2_in_one_line(tmp_path: Path, args: list[str], needle: str) -> None:
    plot = tmp_path / "p.png"
    proc = mrcomm("run", str(S1_PATH), *args, "--plot", str(plot))
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert needle in proc.stderr
    assert not plot.exists()


def test_missing_scenario_and_bad_plot_directory(tmp_path: Path) -> None:
    proc = mrcomm("run", str(tmp_path / "nope.yaml"))
    assert proc.returncode == 2 and "nope.yaml" in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
    proc = mrcomm("run", str(S1_PATH), "--plot", str(tmp_path / "no" / "dir.png"))
    assert proc.returncode == 2 and "does not exist" in proc.stderr


def test_task_inside_a_wall_names_file_and_field(tmp_path: Path) -> None:
    scenario = tmp_path / "s.yaml"
    tasks = tmp_path / "tasks.yaml"
    src = (ROOT / "data" / "scenarios" / "s1.yaml").read_text()
    scenario.write_text(
        src.replace("../maps/office.yaml", str(ROOT / "data" / "maps" / "office.yaml")).replace(
            "s1_tasks.yaml", str(tasks)
        )
    )
    tasks.write_text(
        "- task_id: '1'\n  type: SENSOR_SWEEP\n  location: {x: 0.01, y: 0.01}\n"
        "  arrival_time: 0\n  num_robots: 1\n  duration: 0\n  depends: []\n"
    )
    proc = mrcomm("run", str(scenario))
    assert proc.returncode == 2, proc.stderr
    assert "tasks.yaml" in proc.stderr and "location" in proc.stderr
    assert "Traceback" not in proc.stderr
