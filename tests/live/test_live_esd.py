"""ESD in live mode: the pulse publishes over Zenoh, the robot's agent feeds its
measured-signal sensor with its own pulse's readings, and ``mrcomm live --threshold esd
--rssi-trace CSV`` replays the trace through one pulse process per robot on the shared
clock, recording warnings and RSSI as ``mrcomm run`` does."""

from __future__ import annotations

import stat
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from mrcomm.live.agent import AgentProcess
from mrcomm.live.launcher import LiveTeam, free_port
from mrcomm.live.protocol import WORLD_ID
from mrcomm.live.settings import LiveSettings
from mrcomm.messaging.messages import TOPIC_RSSI, RssiMsg, decode
from mrcomm.net.zenoh_config import ZenohOptions, make_options
from mrcomm.net.zenoh_node import Incoming, ZenohNode
from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission
from mrcomm.world.geometry import Pose

from .helpers import ROOT, S1, drain

CODE = "from mrcomm.cli.main import app; app()"
TRACE = ROOT / "data" / "traces" / "s1_synthetic_esd.csv"
FIXTURES = ROOT / "tests" / "net" / "fixtures"
ESD = {"network": "ah", "threshold": "esd", "rssi_trace": TRACE}


def _fake_iw(directory: Path) -> Path:
    """An ``iw`` that answers ``dev wlan0 station dump`` with a recorded ad-hoc dump."""
    iw = directory / "iw"
    dump = FIXTURES / "iw_station_dump_adhoc.txt"
    iw.write_text(f'#!/bin/sh\n[ "$2" = "wlan0" ] || exit 237\ncat {dump}\n')
    iw.chmod(iw.stat().st_mode | stat.S_IXUSR)
    return directory


@pytest.fixture
def iw_pulse(tmp_path: Path) -> Iterator[tuple[subprocess.Popen[str], int]]:
    """``mrcomm pulse --iface wlan0`` (fake iw) publishing to a peer on a free port."""
    port = free_port("127.0.0.1")
    bin_dir = _fake_iw(tmp_path)
    args = [
        sys.executable, "-c", CODE, "pulse", "--iface", "wlan0",
        "--peers", str(FIXTURES / "peers.yaml"), "--robot", "robot_1", "--team", "t",
        "--connect", f"tcp/127.0.0.1:{port}", "--rate", "10", "--stdout", "--insecure",
    ]  # fmt: skip
    env = {"PATH": f"{bin_dir}:/usr/bin:/bin", "PYTHONUNBUFFERED": "1"}
    process = subprocess.Popen(
        args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
    )
    try:
        yield process, port
    finally:
        if process.poll() is None:
            process.terminate()
        process.communicate(timeout=20)


def _listen(port: int) -> ZenohNode:
    node = ZenohNode(make_options(team="t", listen=[f"tcp/127.0.0.1:{port}"]))
    node.listen(f"{node.prefix}/*/{TOPIC_RSSI}", "rssi", decode)
    return node


def _readings(node: ZenohNode, count: int) -> list[Incoming]:
    return drain(node, lambda items: len(items) >= count, timeout=30)


def test_pulse_publishes_over_zenoh_and_outlives_its_listener(
    iw_pulse: tuple[subprocess.Popen[str], int],
) -> None:
    process, port = iw_pulse
    node = _listen(port)
    try:
        first = _readings(node, 4)
    finally:
        node.close()  # the agent's session dies ...
    for item in first:
        assert item.key == "mrcomm/t/robot_1-pulse/rssi"
        message = item.value
        assert isinstance(message, RssiMsg)
        assert (message.sender, message.robot) == ("robot_1-pulse", "robot_1")
    assert {(m.value.peer, m.value.rssi) for m in first} == {
        ("robot_2", -38.0),
        ("robot_3", -57.0),
    }
    # ... the pulse keeps running and reaches the restarted listener by itself.
    assert process.poll() is None
    node = _listen(port)
    try:
        again = _readings(node, 2)
    finally:
        node.close()
    assert min(i.value.seq for i in again) > max(i.value.seq for i in first)
    process.terminate()
    out, err = process.communicate(timeout=20)
    assert process.returncode == 0, err
    # --stdout: the same readings as JSON lines, next to Zenoh.
    assert out.count('"sender": "robot_1-pulse"') >= 6
    assert "readings published" in err


def test_agent_feeds_only_its_own_pulse_readings_to_its_sensor(tmp_path: Path) -> None:
    run = make_config(None, scenario=S1, behaviour="lf", **ESD)
    settings = LiveSettings(run, make_options(team="unit"), tmp_path)
    agent = AgentProcess(settings, "robot_1", incarnation=1)
    try:
        sensor = agent.measured
        assert sensor is not None and agent.executor is not None
        assert agent.executor.link_sensor is sensor  # what LF judges its links with

        def feed(robot: str, peer: str, rssi: float, seq: int) -> None:
            message = RssiMsg(
                sender=f"{robot}-pulse", incarnation=1, seq=seq, stamp=0.0,
                robot=robot, peer=peer, rssi=rssi,
            )  # fmt: skip
            agent._on_item(Incoming("pulse", "k", message, None, 0.0))

        agent.now = 10.0
        feed("robot_1", "robot_2", -50.0, 1)
        feed("robot_2", "robot_3", -60.0, 2)  # measured by another robot: not ours
        feed("robot_1", "robot_1", -20.0, 3)  # of itself: meaningless
        assert sensor.latest == {"robot_2": (-50.0, 10.0)}  # dated on the shared clock
        assert agent.pulse_readings == 1
        here = Pose(0.0, 0.0)
        assert sensor.warning("robot_2", here, 1.0, 0.0, 12.0)  # -50 < -41 dBm
        assert not sensor.warning("robot_3", here, 1.0, 0.0, 12.0)  # no reading: no warning
        assert not sensor.warning("robot_2", here, 1.0, 0.0, 15.5)  # stale after 5 s
        feed("robot_1", "robot_2", -30.0, 4)
        assert not sensor.warning("robot_2", here, 1.0, 0.0, 10.0)
    finally:
        agent._finish()


def test_launcher_starts_one_replaying_pulse_per_robot(tmp_path: Path) -> None:
    run = make_config(None, scenario=S1, **ESD)
    zenoh = ZenohOptions(team="esd")
    team = LiveTeam(LiveSettings(run, zenoh, tmp_path), team_dir=tmp_path)  # TLS on every link
    team.ports = {name: 7000 + i for i, name in enumerate(team.names)}
    assert sorted(team.pulses) == ["robot_1-pulse", "robot_2-pulse", "robot_3-pulse"]
    args = team.command("robot_2-pulse")
    assert args[:5] == ["pulse", "--trace", str(TRACE), "--robot", "robot_2"]
    text = " ".join(args)
    assert f"--connect tls/127.0.0.1:{team.ports['robot_2']}" in text  # its own agent
    assert f"--world-connect tls/127.0.0.1:{team.ports[WORLD_ID]}" in text  # the clock
    assert f"--team-dir {tmp_path}" in text  # it presents its robot's certificate
    # Every process gets the trace: the team's run configurations must agree.
    assert f'--set threshold.trace="{TRACE}"' in " ".join(team.command("robot_1"))
    assert f'--set threshold.trace="{TRACE}"' in " ".join(team.command(WORLD_ID))


def test_live_esd_needs_a_trace(tmp_path: Path) -> None:
    done = subprocess.run(
        [sys.executable, "-c", CODE, "live", str(S1), "--network", "ah", "--threshold", "esd",
         "--record-dir", str(tmp_path)],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        "mrcomm: error: threshold 'esd' needs --rssi-trace CSV (or --network "
        "radio, whose signal the pulses then measure)"
    ]
    assert not list(tmp_path.iterdir())  # nothing started


LIMIT = 60.0  # simulated s: the first ESD warnings come at ~4 s, the first task at ~51 s


@pytest.mark.slow
def test_live_esd_mission_records_warnings_and_rssi_like_simulation(tmp_path: Path) -> None:
    run = make_config(None, scenario=S1, behaviour="lf", max_time=LIMIT, **ESD)
    sim = run_mission(run)
    with LiveTeam(LiveSettings(run, make_options(team="esd"), tmp_path, speed=10.0)) as team:
        team.start()
        team.wait()
        live, report = team.collect()
    assert live.config["label"] == sim.config["label"] == "AH_LF_SPL0_ESD"
    assert live.mission["timed_out"] and sim.mission["timed_out"]
    assert live.mission["successful"] == sim.mission["successful"]
    assert abs(live.mission["tasks_completed"] - sim.mission["tasks_completed"]) <= 1
    # Every robot's agent was fed by its own pulse: 2 peers at 2 Hz on the shared clock.
    for robot in ("robot_1", "robot_2", "robot_3"):
        readings = report["processes"][robot]["pulse_readings"]
        assert 0.9 * 2 * 2 * LIMIT <= readings <= 2 * 2 * LIMIT + 4, (robot, readings)
    # The measured RSSI made LF switch, early, in both modes.
    for result in (sim, live):
        first = [
            e.time
            for tl in result.timelines.values()
            for e in tl.events
            if e.label == "disconnect_detected"
        ]
        assert first and min(first) < 10.0
        assert result.mission["role_assignment_time"] > 0
    # Ground truth: the trace on the shared clock, so the links' warnings and RSSI match.
    assert live.links.keys() == sim.links.keys()
    for pair, s in sim.links.items():
        lv = live.links[pair]
        assert s["min_rssi"] is not None and lv["min_rssi"] == s["min_rssi"], pair
        assert abs(lv["warnings"] - s["warnings"]) <= 1, pair
        assert lv["time_in_warning"] == pytest.approx(s["time_in_warning"], abs=1.0), pair
    pairs = {(a, b) for _, a, b, _ in sim.rssi_series}
    assert len(pairs) == 6 and {(a, b) for _, a, b, _ in live.rssi_series} == pairs
    assert abs(len(live.rssi_series) - len(sim.rssi_series)) <= 12
    sim_at = {(t, a, b): v for t, a, b, v in sim.rssi_series}
    same = [sim_at[(t, a, b)] == v for t, a, b, v in live.rssi_series if (t, a, b) in sim_at]
    assert len(same) > 0.9 * len(live.rssi_series) and all(same)
