"""Bad input to the live commands: a clear one-line error and exit status 2 — unknown
robot, unreachable endpoints, two agents claiming one id, bad TLS files and team
directories, no security chosen, a busy port, a record directory without a world
journal. ``--insecure`` prints one warning line once every input is checked."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from mrcomm.live.identity import INSECURE_WARNING
from mrcomm.live.launcher import free_port
from mrcomm.net.team_dir import init_team

from .helpers import S1, wait_for

CODE = "from mrcomm.cli.main import app; app()"


def mrcomm(*args: str, timeout: float = 60) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", CODE, *args], capture_output=True, text=True, timeout=timeout
    )


def one_line_error(done: subprocess.CompletedProcess[str], *needles: str) -> str:
    assert done.returncode == 2, (done.returncode, done.stdout[-500:], done.stderr[-2000:])
    lines = [line for line in done.stderr.splitlines() if line.strip() and line != INSECURE_WARNING]
    assert len(lines) == 1 and lines[0].startswith("mrcomm: error:"), done.stderr
    for needle in needles:
        assert needle in lines[0], lines[0]
    assert "Traceback" not in done.stderr
    return lines[0]


def test_unknown_robot_and_misplaced_assigner(tmp_path: Path) -> None:
    rec = ["--record-dir", str(tmp_path)]
    one_line_error(
        mrcomm("agent", str(S1), "--robot", "robot_9", *rec),
        "--robot",
        "robot 'robot_9' is not in scenario S1",
        "did you mean",
    )
    one_line_error(
        mrcomm("agent", str(S1), "--robot", "assigner", *rec), "runs on robot_2", "--robot robot_2"
    )
    one_line_error(mrcomm("agent", str(S1), "--robot", "a/b", *rec), "not a valid id")


def test_unreachable_endpoints_and_bad_endpoints(tmp_path: Path) -> None:
    nobody = free_port("127.0.0.1")
    done = mrcomm(
        "agent", str(S1), "--robot", "robot_1", "--connect", f"tcp/127.0.0.1:{nobody}",
        "--join-timeout", "1", "--record-dir", str(tmp_path), "--insecure",
    )  # fmt: skip
    one_line_error(done, "--connect", "no team reachable within 1 s", f"127.0.0.1:{nobody}")
    assert not list(tmp_path.glob("*.jsonl"))  # nothing half-written
    one_line_error(
        mrcomm("agent", str(S1), "--robot", "robot_1", "--connect", "nowhere", "--insecure"),
        "--connect",
    )
    one_line_error(mrcomm("world", str(S1), "--protocol", "sctp", "--insecure"), "--protocol")
    one_line_error(mrcomm("live", str(S1), "--network", "mesh"), "--network")


def test_busy_listen_port(tmp_path: Path) -> None:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        sock.listen()
        port = sock.getsockname()[1]
        done = mrcomm(
            "world", str(S1), "--listen", f"tcp/127.0.0.1:{port}", "--record-dir",
            str(tmp_path), "--insecure",
        )  # fmt: skip
    one_line_error(done, "--listen", "Address already in use")


def test_bad_tls_files(tmp_path: Path) -> None:
    init_team(tmp_path / "team", ("robot_1", "robot_2"), days=1)
    team = tmp_path / "team"
    tls = ["--tls-ca", str(team / "ca.pem"), "--tls-cert", str(team / "robot_1.pem")]
    base = ["world", str(S1), "--listen", "127.0.0.1:0", "--record-dir", str(tmp_path)]
    one_line_error(
        mrcomm(*base, *tls, "--tls-key", str(team / "missing.key")),
        "missing.key",
        "--tls-key",
        "file not found",
    )
    one_line_error(
        mrcomm(*base, *tls, "--tls-key", str(team / "robot_1.pem")), "not a PEM private key"
    )
    one_line_error(mrcomm(*base, *tls, "--tls-key", str(team / "robot_2.key")), "--tls-cert", "TLS")
    one_line_error(mrcomm(*base, *tls[:2]), "needs all of --tls-ca, --tls-cert and --tls-key")


def test_security_must_be_chosen_and_team_directories_are_checked(tmp_path: Path) -> None:
    """Secure by default: a process without certificates refuses to start unless told
    --insecure; a team directory must be one and hold this process's files."""
    records = tmp_path / "records"
    agent = ["agent", str(S1), "--robot", "robot_1", "--record-dir", str(records)]
    one_line_error(mrcomm(*agent), "--team-dir", "no team certificates", "--insecure")
    one_line_error(mrcomm("world", str(S1)), "--team-dir", "no team certificates")
    one_line_error(mrcomm(*agent, "--team-dir", str(tmp_path / "nope")), "not a directory")
    one_line_error(mrcomm(*agent, "--team-dir", str(tmp_path)), "no ca.pem")
    team = init_team(tmp_path / "team", ("world", "robot_2"), days=1).path
    one_line_error(
        mrcomm(*agent, "--team-dir", str(team)), "'robot_1' is not a member", "mrcomm team add"
    )
    one_line_error(
        mrcomm("agent", str(S1), "--robot", "robot_2", "--team-dir", str(team), "--insecure"),
        "--insecure contradicts --team-dir",
    )
    one_line_error(
        mrcomm("world", str(S1), "--team-dir", str(team), "--tls-ca", str(team / "ca.pem")),
        "drop --tls-ca",
    )
    # mrcomm live checks every process's certificate before launching any.
    one_line_error(
        mrcomm("live", str(S1), "--team-dir", str(team), "--record-dir", str(records)),
        "'robot_1' is not a member",
    )
    one_line_error(mrcomm("live", str(S1), "--protocol", "udp"), "--protocol", "--insecure")
    assert not records.exists()


def test_team_init_add_and_show(tmp_path: Path) -> None:
    team = tmp_path / "team"
    done = mrcomm("team", "init", str(team), "--members", "robot_1,robot_2")
    assert done.returncode == 0, done.stderr
    assert (team / "world.pem").is_file()  # every team has a world
    assert (team / "robot_1.key").stat().st_mode & 0o077 == 0  # private keys: owner only
    one_line_error(mrcomm("team", "init", str(team), "--members", "x"), "never overwritten")
    one_line_error(
        mrcomm("team", "add", str(team), "--members", "robot_2"), "already a member: robot_2"
    )
    one_line_error(mrcomm("team", "init", str(tmp_path / "t2"), "--members", "a/b"), "valid id")
    one_line_error(
        mrcomm("team", "init", str(tmp_path / "t3"), "--members", "r", "--address", "r"),
        "MEMBER=HOST",
    )
    assert not (tmp_path / "t2").exists() and not (tmp_path / "t3").exists()
    assert mrcomm("team", "add", str(team), "--members", "robot_3").returncode == 0
    shown = mrcomm("team", "show", str(team)).stdout
    assert "robot_3: robot_3.pem, robot_3.key" in shown
    assert [p.name for p in tmp_path.iterdir()] == ["team"]  # no staging left behind


@pytest.mark.parametrize("linked", [True, False], ids=["linked", "not_linked_to_the_first"])
def test_two_agents_cannot_claim_the_same_id(linked: bool, tmp_path: Path) -> None:
    """The second agent is refused whether or not its own link to the first is up when
    it checks. Without gossip it never links to the first (Zenoh peers do not forward
    each other's tokens): the state a loaded machine leaves it in during its check,
    where only the world's roster names the first. Before the world answered, that
    second agent joined as a duplicate and ran on (it once did so in CI)."""
    world_port, agent_port = free_port("127.0.0.1"), free_port("127.0.0.1")
    common = ["--record-dir", str(tmp_path)]
    unlinked: list[str] = []
    if not linked:
        config = tmp_path.parent / f"{tmp_path.name}-no-gossip.json5"
        config.write_text("{scouting: {gossip: {enabled: false}}}")
        unlinked = ["--zenoh-config", str(config)]
    world = subprocess.Popen(
        [sys.executable, "-c", CODE, "world", str(S1), "--listen",
         f"tcp/127.0.0.1:{world_port}", "--start-timeout", "120", "--insecure", *common],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )  # fmt: skip
    first = subprocess.Popen(
        [sys.executable, "-c", CODE, "agent", str(S1), "--robot", "robot_1", "--listen",
         f"tcp/127.0.0.1:{agent_port}", "--connect", f"tcp/127.0.0.1:{world_port}",
         "--insecure", *common],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )  # fmt: skip
    try:
        wait_for(lambda: list(tmp_path.glob("robot_1.*.jsonl")), 60, "robot_1 to join")
        second = mrcomm(
            "agent", str(S1), "--robot", "robot_1", "--connect",
            f"tcp/127.0.0.1:{world_port}", "--insecure", *unlinked, *common,
        )  # fmt: skip
        one_line_error(second, "--robot", "'robot_1' is already running", "same id")
        assert first.poll() is None  # the first one carries on
        assert len(list(tmp_path.glob("robot_1.*.jsonl"))) == 1
    finally:
        for process in (first, world):
            process.terminate()
            process.wait(timeout=20)


def test_collect_needs_a_world_journal(tmp_path: Path) -> None:
    one_line_error(mrcomm("collect", str(tmp_path)), "no world journal")
    one_line_error(mrcomm("collect", str(tmp_path / "nope")), "not a directory")


@pytest.mark.parametrize("value", ["0", "-1", "nan", "inf"])
def test_speed_must_be_finite_and_positive_and_nothing_is_left(value: str, tmp_path: Path) -> None:
    """Refused before any directory is made: the world's --record-dir, and the
    temporary directory of ``mrcomm live`` (TMPDIR points into tmp_path)."""
    records = tmp_path / "records"
    one_line_error(
        mrcomm("world", str(S1), "--speed", value, "--record-dir", str(records), "--insecure"),
        "--speed",
    )
    assert not records.exists()
    temp = tmp_path / "tmp"
    temp.mkdir()
    done = subprocess.run(
        [sys.executable, "-c", CODE, "live", str(S1), "--speed", value],
        capture_output=True, text=True, timeout=60, env={**os.environ, "TMPDIR": str(temp)},
    )  # fmt: skip
    one_line_error(done, "--speed")
    assert list(temp.iterdir()) == []


def test_agent_errors_leave_no_record_directory(tmp_path: Path) -> None:
    records = tmp_path / "records"
    for args in (["--robot", "robot_9"], ["--robot", "robot_1", "--lease", "nan", "--insecure"]):
        done = mrcomm("agent", str(S1), *args, "--record-dir", str(records))
        one_line_error(done)
        assert not records.exists(), args


def test_live_over_udp_runs_a_mission_slice(tmp_path: Path) -> None:
    done = mrcomm(
        "live", str(S1), "--protocol", "udp", "--speed", "20", "--max-time", "30", "--json",
        "--record-dir", str(tmp_path), "--insecure", timeout=180,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stderr.splitlines()[0] == INSECURE_WARNING  # said once, up front
    summary = json.loads(done.stdout)
    assert summary["mission"]["timed_out"] is True and summary["sim_time_s"] == 30.0
    pose = summary["messages"]["pose"]
    assert pose["sent"] > 100 and pose["received"] >= 0.99 * 3 * pose["sent"]
    assert summary["config"]["mode"] == "live"
