"""Whole S1 missions under the radio model: reproducible, the drops the model
predicts, delays in the message statistics, and the behaviours still succeed."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mrcomm.messaging.messages import Message
from mrcomm.net.delivery import DROPPED_RADIO, RECEIVED
from mrcomm.net.radio.profile import profile_path
from mrcomm.run.config import make_config
from mrcomm.run.resources import ScenarioResources
from mrcomm.sim.mission import Mission, run_mission
from mrcomm.testing.checks import S1_TRACE
from tests.golden.golden import SCENARIO, comparable

pytestmark = pytest.mark.slow


def _config(**options: Any) -> Any:
    values = {"network": "radio", "threshold": "slt", "behaviour": "nb", "spl": 0, "seed": 1}
    return make_config(None, scenario=SCENARIO, **{**values, **options})


def test_same_seed_same_result_other_seed_other(s1_resources: ScenarioResources) -> None:
    first = comparable(run_mission(_config(seed=4), s1_resources))
    again = comparable(run_mission(_config(seed=4), s1_resources))
    other = comparable(run_mission(_config(seed=5), s1_resources))
    assert first == again
    assert first != other


def test_radio_drops_match_the_packet_error_the_model_gives(
    s1_resources: ScenarioResources, tmp_path: Path
) -> None:
    """Every pose decision on a link in range: the model's PER for that message (from
    the channel at that moment) against what happened. The number of radio drops must
    be the sum of the PERs within four binomial standard deviations."""
    # A weaker radio than the office's, so that S1's links lose a measurable share.
    text = profile_path("office-2.4ghz").read_text()
    weak = tmp_path / "weak.yaml"
    weak.write_text(text.replace("tx_power_dbm: 10.0", "tx_power_dbm: -12.0"))
    mission = Mission(_config(params={"network": {"profile": str(weak)}}, seed=2), s1_resources)
    channel = mission.network.channel
    assert channel is not None and channel.profile.tx_power_dbm == -12.0
    per_sum, per_var, drops, decisions = 0.0, 0.0, 0, 0
    index = {a: i for i, a in enumerate(mission.node_ids)}

    def observe(now: float, topic: str, s: str, r: str, message: Message, outcome: str) -> None:
        nonlocal per_sum, per_var, drops, decisions
        if outcome not in (RECEIVED, DROPPED_RADIO) or topic != "pose":
            return
        p = channel.packet_error(index[s], index[r], channel.bits(message))
        per_sum, per_var = per_sum + p, per_var + p * (1 - p)
        drops += outcome == DROPPED_RADIO
        decisions += 1

    mission.network.observer = observe
    mission.run()
    assert decisions > 1000
    assert per_sum > 50, "the test needs links that lose packets"
    assert abs(drops - per_sum) < 4 * np.sqrt(per_var) + 1


def test_message_statistics_show_radio_causes_and_delays(
    s1_resources: ScenarioResources,
) -> None:
    result = run_mission(_config(behaviour="lf", seed=1), s1_resources)
    pose = result.messages["pose"]
    assert {"dropped_radio", "dropped_queue", "delay_mean_s", "delay_max_s"} <= set(pose)
    # A pose (~150 bytes + header) takes ~1.7 ms of airtime at 1 Mbit/s.
    assert 1e-3 < pose["delay_mean_s"] < 5e-3
    assert result.messages["aon"]["delay_mean_s"] > 0
    # Models without a radio keep their results as they were: no radio keys.
    plain = run_mission(_config(network="ah", seed=1), s1_resources)
    assert "dropped_radio" not in plain.messages["pose"]


@pytest.mark.parametrize("threshold", ["slt", "ssd", "esd"])
def test_lf_succeeds_on_s1_under_the_radio(s1_resources: ScenarioResources, threshold: str) -> None:
    # ESD measures the radio: its warning level on the radio's scale (the default -41 dBm
    # is the original robots' and is warned about, see test_esd_default_is_warned_about).
    params = {"threshold": {"warning_dbm": -70.0}} if threshold == "esd" else {}
    for seed in (1, 2):
        result = run_mission(
            _config(behaviour="lf", threshold=threshold, spl=25, seed=seed, params=params),
            s1_resources,
        )
        assert result.mission["successful"], (threshold, seed, result.mission["failed_tasks"])


def test_esd_on_the_radio_records_the_measured_signal(s1_resources: ScenarioResources) -> None:
    """ESD without a trace: the robots' pulses measure the radio, and the run's 2 Hz
    RSSI series is the radio's power as the cards report it (whole dBm)."""
    config = _config(
        behaviour="lf", threshold="esd", seed=3, params={"threshold": {"warning_dbm": -70.0}}
    )
    result = run_mission(config, s1_resources)
    values = [v for _, _, _, v in result.rssi_series]
    assert len(values) > 100
    assert all(v == round(v) for v in values)
    assert min(values) < max(values) - 10  # the signal changes as the robots move


def test_the_original_robots_esd_level_on_the_radio_is_warned_about() -> None:
    """The default follows the radio (next test); the original robots' -41 dBm given
    by hand, which this radio passes 2.3 m from a peer, gets the advice."""
    assert _config(behaviour="lf", threshold="esd").ignored_settings() == []
    original = _config(behaviour="lf", threshold="esd", params={"threshold": {"warning_dbm": -41}})
    advice = original.ignored_settings()
    assert len(advice) == 1 and "ESD warns below -41 dBm" in advice[0]
    tuned = _config(behaviour="lf", threshold="esd", params={"threshold": {"warning_dbm": -70}})
    assert tuned.ignored_settings() == []
    assert _config(behaviour="lf", threshold="ssd").ignored_settings() == []


def test_esd_by_default_warns_where_the_original_robots_did() -> None:
    """-41 dBm was the original robots' reading of a peer about 4 m away in line of
    sight (their Table 6.2: 3.5-4.2 m): the default is the radio's power there, and
    -41 dBm with a replayed trace of such cards."""
    from mrcomm.net.radio.model import mean_power_dbm
    from mrcomm.net.radio.profile import load_profile
    from mrcomm.run.wiring import threshold_params

    expected = round(float(mean_power_dbm(load_profile("office-2.4ghz"), [4.0], [0])[0]))
    assert threshold_params(_config(behaviour="lf", threshold="esd")).warning_dbm == expected
    assert expected == -48
    outdoor = _config(behaviour="lf", threshold="esd", params={"network": {"profile": "outdoor"}})
    outdoor_expected = round(float(mean_power_dbm(load_profile("outdoor"), [4.0], [0])[0]))
    assert threshold_params(outdoor).warning_dbm == outdoor_expected
    given = _config(behaviour="lf", threshold="esd", params={"threshold": {"warning_dbm": -60}})
    assert threshold_params(given).warning_dbm == -60
    traced = make_config(
        None, scenario=SCENARIO, network="ah", threshold="esd", behaviour="lf",
        params={"threshold": {"trace": str(S1_TRACE)}},
    )  # fmt: skip
    assert threshold_params(traced).warning_dbm == -41


def test_lf_on_the_radio_with_esd_succeeds_where_nb_loses_statuses(
    s1_resources: ScenarioResources,
) -> None:
    """With the defaults: the LF team completes and reports every task on seeds 1-5 (it
    held for ever before: its level was the original cards' -41 dBm, and a follower
    waiting beside its leader could still warn in one direction of the link); NB loses
    a status on each."""
    for seed in range(1, 6):
        lf = run_mission(_config(behaviour="lf", threshold="esd", seed=seed), s1_resources)
        assert lf.mission["successful"] and not lf.mission["timed_out"], seed
        nb = run_mission(_config(behaviour="nb", threshold="esd", seed=seed), s1_resources)
        assert not nb.mission["successful"] and nb.mission["failed_tasks"], seed


#: Digests of three radio runs. Recorded before the review's restructuring (shared
#: count-key helpers, the log-distance law from net/signal/pathloss), which left them
#: unchanged; recorded again when wall counts became exact at every step (an obstructed
#: ray is cast again as soon as an end moves, no longer after 0.25 m), the one change
#: in them then — verified by running the old digests with the old recast distance; and
#: again when the shadowing grid became finer (dc/32, was dc/8; the SSD-LF run, whose
#: robots stay close in sight, lost nothing to the radio either way and kept its digest);
#: and again (SLT-NB, ESD-LF) when a mission stopped waiting for a step without a pose
#: in flight: they end 0.1 s sooner, and the old end rule gives the old digests.
RADIO_DIGESTS = {
    "slt-nb": "03f92f95730a3f33b52ecec6a32058f646063df28dc23c892e190db056a36b71",
    "ssd-lf": "c082968f789a365048f2478600a4af47421a80ecebb9eb1ca7f0607201ba6229",
    "esd-lf": "9eae2cfae9ada8946c02e6bcde4edee5129a0d258bccbd9053612ff58911f126",
}


@pytest.mark.parametrize("case", sorted(RADIO_DIGESTS))
def test_radio_runs_are_the_recorded_ones(s1_resources: ScenarioResources, case: str) -> None:
    threshold, behaviour = case.split("-")
    params = {"threshold": {"warning_dbm": -70.0}} if threshold == "esd" else {}
    config = _config(threshold=threshold, behaviour=behaviour, spl=25, seed=2, params=params)
    blob = json.dumps(comparable(run_mission(config, s1_resources)), sort_keys=True)
    assert hashlib.sha256(blob.encode()).hexdigest() == RADIO_DIGESTS[case]
