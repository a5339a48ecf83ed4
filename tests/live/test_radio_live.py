"""The radio in live mode: a receiver judges each message over the one link it came by
exactly as the simulation judges it over the step's links (range from power, packet
error with fading, the sender's queue and its delay), and the live world measures the
radio for ESD. Real Zenoh on loopback."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import pytest
import yaml

from mrcomm.live.launcher import LiveTeam
from mrcomm.live.settings import LiveSettings
from mrcomm.net.delivery import DROPPED_QUEUE, DROPPED_RADIO, RECEIVED
from mrcomm.net.radio.profile import profile_path
from mrcomm.net.zenoh_config import make_options
from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission
from mrcomm.testing.buses import compare_decisions, record_in_process

from .helpers import S1


def harsh_profile(tmp_path: Path, **changes: object) -> Path:
    """The office profile with a weak transmitter and a slow channel: packet errors
    at S1's distances, queues that delay poses past a step and overflow."""
    data = yaml.safe_load(profile_path("office-2.4ghz").read_text())
    data.update(
        name="harsh",
        tx_power_dbm=-30.0,
        rate_bps=8_000.0,
        max_queue_s=0.4,
        **changes,
    )
    path = tmp_path / "harsh.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.mark.parametrize("fading", ["none", "rician"])
def test_live_radio_decides_as_the_simulation(tmp_path: Path, fading: str) -> None:
    config = make_config(
        None,
        scenario=S1,
        network="radio",
        threshold="slt",
        behaviour="lf",
        spl=10.0,
        seed=5,
        params={"network": {"profile": str(harsh_profile(tmp_path, fading=fading))}},
    )
    decisions = compare_decisions(config, steps=1500)
    outcomes = Counter(d[-1] for d in decisions)
    # Every kind of radio decision was compared, not only the easy ones.
    assert outcomes[RECEIVED] > 100 and outcomes[DROPPED_RADIO] > 20, outcomes
    assert outcomes[DROPPED_QUEUE] > 20, outcomes
    # ... and messages the radio held past the step after their publication.
    mission, _, _ = record_in_process(config, steps=1500)
    counts = mission.network.counts_by_agent().values()
    delays = [c["delay_max_s"] for topics in counts for c in topics.values()]
    assert max(delays) > 2 * config.dt


LIMIT = 80.0  # simulated s


@pytest.mark.slow
def test_live_mission_on_the_radio_with_esd_measured_by_the_world(tmp_path: Path) -> None:
    """``mrcomm live`` on the radio with ESD and no trace: every agent judges its
    messages on the radio (packet errors and delays counted as in simulation), and the
    world reads each robot's pulse on the modelled radio and publishes it, so the
    robots' measured-signal sensors are fed without hardware."""
    run = make_config(
        None,
        scenario=S1,
        network="radio",
        threshold="esd",
        behaviour="lf",
        spl=0.0,
        seed=2,
        max_time=LIMIT,
        params={"threshold": {"esd": {"warning_dbm": -70.0}}},
    )
    run.check_mode("live")
    sim = run_mission(run)
    with LiveTeam(LiveSettings(run, make_options(team="radio"), tmp_path, speed=10.0)) as team:
        assert team.pulses == {}  # no pulse processes: the world measures
        team.start()
        team.wait()
        live, report = team.collect()
    assert live.config["label"] == sim.config["label"]
    # Each robot's sensor got its pulse's readings: 2 peers at 2 Hz while in range.
    for robot in ("robot_1", "robot_2", "robot_3"):
        readings = report["processes"][robot]["pulse_readings"]
        assert 0.5 * 2 * 2 * LIMIT <= readings <= 2 * 2 * LIMIT + 4, (robot, readings)
    # Messages were judged by the radio, with its delays, in both modes.
    for result in (sim, live):
        pose = result.messages["pose"]
        assert {"dropped_radio", "dropped_queue", "delay_mean_s"} <= pose.keys()
        assert pose["received"] > 0 and 0.0 < pose["delay_mean_s"] < 0.01, pose
    # The world recorded the modelled RSSI as ground truth, in the simulation's range.
    values = [v for _, _, _, v in live.rssi_series]
    sim_values = [v for _, _, _, v in sim.rssi_series]
    assert values and min(sim_values) - 10 < sum(values) / len(values) < max(sim_values) + 10
    assert live.mission["tasks_completed"] >= 1
