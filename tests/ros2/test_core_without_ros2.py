"""The core install stays free of ROS 2: nothing imports rclpy until a ROS 2 option is
used, and without the extra those options fail in one line (exit 2) before any work."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from .helpers import MISSING, S1

_CLI = "from mrcomm.cli.main import app; app()"


def mrcomm(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", _CLI, *args], capture_output=True, text=True, timeout=60, cwd=cwd
    )


def test_nothing_imports_rclpy_by_itself() -> None:
    code = (
        "import sys, mrcomm.cli.main, mrcomm.live.agent, mrcomm.live.world, "
        "mrcomm.live.launcher, mrcomm.live.robot_base, mrcomm.ros2.runtime\n"
        "leaked = sorted(m for m in sys.modules if m.split('.')[0] in "
        "('rclpy', 'nav2_msgs', 'geometry_msgs', 'nav_msgs', 'action_msgs'))\n"
        "print(','.join(leaked))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == ""


def test_unknown_base_is_one_line(tmp_path: Path) -> None:
    done = mrcomm("live", str(S1), "--base", "nav3", "--record-dir", "out", cwd=tmp_path)
    assert done.returncode == 2
    assert done.stderr.strip().splitlines()[-1] == (
        "mrcomm: error: --base: unknown base 'nav3' (did you mean 'nav2'?); choose native or nav2"
    )
    assert not (tmp_path / "out").exists()


@pytest.mark.skipif(MISSING is None, reason="the ros2 extra is installed here")
@pytest.mark.parametrize(
    "args",
    [
        ("live", "--base", "nav2", "--record-dir", "out"),
        ("agent", "--robot", "robot_1", "--base", "nav2", "--record-dir", "out"),
        ("world", "--ros2", "--record-dir", "out"),
    ],
)
def test_ros2_options_without_the_extra(args: tuple[str, ...], tmp_path: Path) -> None:
    done = mrcomm(args[0], str(S1), *args[1:], "--insecure", cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr
    assert "is not importable" in lines[0] and "mrcomm[ros2]" in lines[0]
    assert lines[0].startswith(("mrcomm: error: --base: ", "mrcomm: error: --ros2: "))
    assert not (tmp_path / "out").exists()  # nothing made before the check
