"""The operator as a live team member: ``mrcomm live --operator FILE`` starts it as its
own process (with a certificate of the throwaway team: TLS and the access-control
list), it joins over Zenoh, hears every robot, and its commands — sent with AON over
lossy links — reach every robot and the task assigner: the reassigned task is done by
its new owner and its status reaches the assigner."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from .helpers import ROOT, journal

pytestmark = pytest.mark.slow

S1 = ROOT / "data" / "scenarios" / "s1.yaml"
PLAN = """placement: base
commands:
  - {at: 10, command: reassign, task: "7", robot: robot_3}
  - {at: 20, command: pause, robot: robot_2}
  - {at: 30, command: resume, robot: robot_2}
"""


def test_a_live_operator_sees_the_robots_and_its_commands_are_carried_out(
    tmp_path: Path,
) -> None:
    plan = tmp_path / "operator.yaml"
    plan.write_text(PLAN)
    records = tmp_path / "records"
    args = [
        "live", str(S1), "--network", "ah", "--spl", "25", "--behaviour", "lf",
        "--threshold", "slt", "--seed", "1", "--speed", "10", "--json",
        "--record-dir", str(records), "--operator", str(plan),
    ]  # fmt: skip
    done = subprocess.run(
        [sys.executable, "-c", "from mrcomm.cli.main import app; app()", *args],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    result = json.loads(done.stdout)
    operator = result["operator"]
    assert operator["robots_seen"] == ["robot_1", "robot_2", "robot_3"]
    everyone = ["assigner", "operator", "robot_1", "robot_2", "robot_3"]
    for command in operator["commands"]:
        assert sorted(command["acknowledged"]) == everyone
        assert command["finished_at"] >= command["time"]
    # Task 7 went from robot_1 to robot_3, which did it; its status reached the assigner.
    assert result["robots"]["robot_3"]["tasks_assigned"] == 3
    assert result["robots"]["robot_1"]["tasks_assigned"] == 2
    assert result["mission"]["successful"], result["mission"]["failed_tasks"]
    completed = [line.get("data", {}).get("task_id") for line in journal(records, "robot_3")
                 if line.get("label") == "task_completed"]  # fmt: skip
    assert "7" in completed
    # The operator ran as its own process, on the team's clock.
    assert (records / "operator.log").exists()


def test_a_bad_operator_file_stops_the_live_run_before_any_process(tmp_path: Path) -> None:
    plan = tmp_path / "operator.yaml"
    plan.write_text("commands: [{at: 5, command: reassign, task: '7', robot: robot_1}]\n")
    records = tmp_path / "records"
    done = subprocess.run(
        [sys.executable, "-c", "from mrcomm.cli.main import app; app()", "live", str(S1),
         "--operator", str(plan), "--record-dir", str(records), "--insecure"],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert done.returncode == 2
    assert done.stderr.strip().endswith("commands[0]: task '7' is robot_1's already")
    assert not records.exists()
