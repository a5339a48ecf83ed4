"""ESD pulse: stepping, publishing RssiMsg per known peer, robustness, peers file and
the ``iw`` poller."""

from __future__ import annotations

import logging
import stat
from pathlib import Path

import pytest

from mrcomm.errors import InputError
from mrcomm.messaging.messages import TOPIC_RSSI, Message, RssiMsg
from mrcomm.net.pulse import PollError, Pulse, ReplayPulse, iw_poller, load_peers
from mrcomm.ports import Handler

FIXTURES = Path(__file__).parent / "fixtures"
PEERS = {"02:00:00:00:00:02": "robot_2", "02:00:00:00:00:03": "robot_3"}


class RecordingBus:
    owner = "robot_1-pulse"

    def __init__(self) -> None:
        self.sent: list[tuple[str, Message]] = []

    def publish(self, topic: str, message: Message) -> None:
        self.sent.append((topic, message))

    def subscribe(self, topic: str, handler: Handler) -> None:
        raise AssertionError("the pulse only publishes")


def _dump(name: str) -> str:
    return (FIXTURES / name).read_text(encoding="utf-8")


def test_publishes_one_message_per_known_peer_at_2_hz(caplog: pytest.LogCaptureFixture) -> None:
    bus = RecordingBus()
    polls: list[int] = []

    def poll() -> str:
        polls.append(1)
        return _dump("iw_station_dump_adhoc.txt")

    pulse = Pulse(bus, "robot_1", PEERS, poll, incarnation=7)
    with caplog.at_level(logging.WARNING):
        for k in range(11):  # 0.0 .. 1.0 s in 0.1 s steps: polls at 0, 0.5, 1.0
            pulse.step(k / 10)
    assert len(polls) == 3 and pulse.stats.polls == 3
    assert len(bus.sent) == 6 and pulse.stats.published == 6
    topic, first = bus.sent[0]
    assert topic == TOPIC_RSSI and isinstance(first, RssiMsg)
    assert (first.robot, first.peer, first.rssi) == ("robot_1", "robot_2", -38.0)
    assert (first.sender, first.incarnation, first.stamp) == ("robot_1-pulse", 7, 0.0)
    assert [m.seq for _, m in bus.sent] == [1, 2, 3, 4, 5, 6]
    assert bus.sent[-1][1].stamp == pytest.approx(1.0)
    # The unknown station is skipped, counted every time, warned about once.
    assert pulse.stats.unknown == {"aa:bb:cc:dd:ee:01": 3}
    assert sum("aa:bb:cc:dd:ee:01" in r.message for r in caplog.records) == 1


def test_does_not_catch_up_after_a_stall() -> None:
    bus = RecordingBus()
    pulse = Pulse(bus, "robot_1", PEERS, lambda: "", period=0.5)
    pulse.step(0.0)
    pulse.step(10.0)  # stalled for 10 s: one poll, not twenty
    assert pulse.stats.polls == 2
    assert pulse.next_due == pytest.approx(10.5)


def test_keeps_running_through_bad_output_and_poll_failures() -> None:
    bus = RecordingBus()
    outputs = iter(
        [_dump("iw_station_dump_garbage.txt"), "FAIL", _dump("iw_station_dump_no_signal.txt"), ""]
    )

    def poll() -> str:
        text = next(outputs)
        if text == "FAIL":
            raise PollError("iw timed out")
        return text

    pulse = Pulse(bus, "robot_1", PEERS, poll, period=1.0)
    for t in range(4):
        pulse.step(float(t))
    assert pulse.stats.polls == 4
    assert pulse.stats.parse_errors == 1 and pulse.stats.poll_errors == 1
    # Station .02 has no signal at all (skipped); .03 only an average (used).
    assert pulse.stats.no_signal == 1
    sent = [m for _, m in bus.sent if isinstance(m, RssiMsg)]
    assert len(sent) == len(bus.sent) == 1
    assert (sent[0].peer, sent[0].rssi) == ("robot_3", -49.0)


def test_load_peers_both_directions(tmp_path: Path) -> None:
    peers = load_peers(FIXTURES / "peers.yaml")
    assert peers == {
        "02:00:00:00:00:01": "robot_1",
        "02:00:00:00:00:02": "robot_2",
        "02:00:00:00:00:03": "robot_3",
    }
    # An all-digit MAC stays a string (YAML 1.1 would read it as a base-60 number).
    path = tmp_path / "p.yaml"
    path.write_text("robot_9: 10:20:30:40:50:59\n")
    assert load_peers(path) == {"10:20:30:40:50:59": "robot_9"}


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("robot_1: not-a-mac\n", "robot_1: neither 'robot_1' nor 'not-a-mac' is a MAC address"),
        ("robot_1: 02:00:00:00:00:0G\n", "is a MAC address"),
        ("02:00:00:00:00:01: 02:00:00:00:00:02\n", "both sides are MAC addresses"),
        ("- robot_1\n", "expected a mapping of robot ids to MAC addresses"),
        ("robot_1: [a, b]\n", "robot_1: expected a MAC address or robot id"),
        ("a: 02:00:00:00:00:01\nb: 02:00:00:00:00:01\n", "MAC 02:00:00:00:00:01 given for both"),
        ("robot_1: {\n", "not valid YAML"),
        ("", "expected a mapping"),
    ],
)
def test_load_peers_errors(tmp_path: Path, text: str, expected: str) -> None:
    path = tmp_path / "peers.yaml"
    path.write_text(text)
    with pytest.raises(InputError) as err:
        load_peers(path)
    assert err.value.one_line().startswith(str(path))
    assert expected in err.value.one_line()


def _fake_iw(tmp_path: Path, script: str) -> str:
    path = tmp_path / "iw"
    path.write_text("#!/bin/sh\n" + script)
    path.chmod(path.stat().st_mode | stat.S_IXUSR)
    return str(path)


def test_iw_poller_runs_station_dump(tmp_path: Path) -> None:
    dump = FIXTURES / "iw_station_dump_adhoc.txt"
    iw = _fake_iw(tmp_path, f'[ "$1 $2 $3 $4" = "dev wlan0 station dump" ] && cat {dump}\n')
    poll = iw_poller("wlan0", iw=iw)
    assert poll() == dump.read_text()


def test_iw_poller_start_up_errors(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(InputError, match="'iw' command was not found on PATH"):
        iw_poller("wlan0")
    with pytest.raises(InputError, match="not a network interface name"):
        iw_poller("wlan0; rm -rf /")
    iw = _fake_iw(tmp_path, 'echo "command failed: No such device (-19)" >&2; exit 237\n')
    with pytest.raises(InputError) as err:
        iw_poller("wlan9", iw=iw)
    assert "No such device" in err.value.one_line() and "\n" not in err.value.one_line()


def test_iw_poller_runtime_failure_is_poll_error(tmp_path: Path) -> None:
    flag = tmp_path / "broken"
    iw = _fake_iw(tmp_path, f'[ -e {flag} ] && {{ echo "device gone" >&2; exit 1; }}\nexit 0\n')
    poll = iw_poller("wlan0", iw=iw)
    assert poll() == ""
    flag.write_text("")
    with pytest.raises(PollError, match="device gone"):
        poll()


def test_replay_pulse_publishes_what_the_simulated_pulse_hands_the_sensor() -> None:
    """Live ESD on one host replays the trace exactly as the simulation does."""
    from mrcomm.net.link_sensors import MeasuredSensor
    from mrcomm.net.signal.trace import RssiTrace
    from mrcomm.run.wiring import TracePulse

    trace = RssiTrace.from_readings(
        [0.0, 0.0, 0.7, 1.0, 1.2, 2.0],
        ["robot_1", "robot_1", "robot_1", "robot_2", "robot_1", "robot_1"],
        ["robot_2", "robot_3", "robot_2", "robot_1", "robot_3", "robot_2"],
        [-30.0, -35.0, -44.0, -31.0, -50.0, -60.0],
    )
    robots = ("robot_1", "robot_2", "robot_3")
    sensor = MeasuredSensor(-41.0)
    sim = TracePulse(trace, {"robot_1": sensor}, robots)
    bus = RecordingBus()
    replay = ReplayPulse(bus, "robot_1", trace)
    simulated: list[tuple[float, str, float]] = []
    for k in range(40):  # 0 .. 3.9 s on a 0.1 s clock: past the end of the recording
        now = round(k * 0.1, 9)
        before = dict(sensor.latest)
        sim.step(now)
        simulated += [
            (t, peer, rssi)
            for peer, (rssi, t) in sensor.latest.items()
            if before.get(peer) != (rssi, t)
        ]
        replay.step(now)
    published = [(m.stamp, m.peer, m.rssi) for _, m in bus.sent if isinstance(m, RssiMsg)]
    assert sorted(published) == sorted(simulated)
    assert (2.0, "robot_2", -60.0) in published and max(t for t, _, _ in published) == 2.0
    assert all(m.robot == "robot_1" and m.sender == "robot_1-pulse" for _, m in bus.sent)


def test_replay_pulse_needs_readings_of_its_robot() -> None:
    from mrcomm.net.signal.trace import RssiTrace

    trace = RssiTrace.from_readings([0.0], ["robot_1"], ["robot_2"], [-30.0])
    with pytest.raises(InputError, match="no readings measured by 'robot_2'"):
        ReplayPulse(RecordingBus(), "robot_2", trace)
