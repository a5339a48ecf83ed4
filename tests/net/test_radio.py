"""The radio model's parts: walls on the grid, the shadowing field, the profile's
curves, packet error and the sender's queue."""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mrcomm.errors import InputError
from mrcomm.messaging.messages import PoseMsg, encode
from mrcomm.net.link_sensors import MeasuredSensor
from mrcomm.net.links import LinkModel
from mrcomm.net.radio.channel import RadioChannel, fading_gain_db
from mrcomm.net.radio.model import (
    RadioNetwork,
    RadioParams,
    delivery_ratio,
    mean_power_dbm,
    packet_error_rate,
)
from mrcomm.net.radio.profile import RadioProfile, bundled_profiles, load_profile, profile_path
from mrcomm.net.radio.shadowing import ShadowingField
from mrcomm.world.geometry import Pose
from mrcomm.world.occupancy import OccupancyGrid

OFFICE = load_profile("office-2.4ghz")


def _walls_grid() -> OccupancyGrid:
    """20 m x 4 m at 0.05 m: a thin wall at x = 5 m and a thick one at x = 12-12.5 m."""
    occ = np.zeros((80, 400), dtype=np.bool_)
    occ[:, 100] = True
    occ[:, 240:250] = True
    return OccupancyGrid(occ, 0.05)


def test_walls_are_counted_once_each_however_thick() -> None:
    grid = _walls_grid()
    assert grid.walls_between(1.0, 2.0, 4.0, 2.0) == 0
    assert grid.walls_between(1.0, 2.0, 8.0, 2.0) == 1
    assert grid.walls_between(1.0, 2.0, 15.0, 2.0) == 2
    assert grid.walls_between(15.0, 2.5, 1.0, 1.5) == 2  # both directions, slanted
    assert grid.walls_between(7.0, 2.0, 15.0, 3.0) == 1  # the thick wall alone


def test_a_ray_grazing_along_a_wall_crosses_one_wall() -> None:
    """A diagonal wall drawn as a staircase of cells: a ray along it steps in and out of
    its cells, which is one wall, not one per step."""
    occ = np.zeros((200, 200), dtype=np.bool_)
    for i in range(20, 180):
        occ[i, i] = True  # the diagonal y = x, one cell thick
    grid = OccupancyGrid(occ, 0.05)
    assert grid.walls_between(1.0, 1.02, 8.9, 8.93) == 1
    assert grid.walls_between(2.0, 6.0, 6.0, 2.0) == 1  # straight across it


def test_bundled_profiles_load() -> None:
    assert {"office-2.4ghz", "corridor-los", "outdoor"} <= set(bundled_profiles())
    for name in bundled_profiles():
        assert load_profile(name).name == name


def test_delivery_falls_smoothly_with_distance_and_walls() -> None:
    distances = np.arange(1.0, 80.0, 0.5)
    curves = [delivery_ratio(OFFICE, distances, walls) for walls in range(4)]
    for curve in curves:
        assert np.all(np.diff(curve) <= 1e-12), "delivery must not rise with distance"
        # Smooth: no step larger than 5 points between samples half a metre apart.
        assert np.max(np.abs(np.diff(curve))) < 0.05
    for near, far in itertools.pairwise(curves):
        assert np.all(far <= near + 1e-12), "a wall more must not help"
    los = dict(zip(distances.tolist(), curves[0].tolist(), strict=True))
    two_walls = dict(zip(distances.tolist(), curves[2].tolist(), strict=True))
    assert los[2.0] > 0.999 and los[5.0] > 0.999
    assert two_walls[20.0] < 0.9 and two_walls[30.0] < 0.6


def test_packet_error_grows_with_message_size() -> None:
    ber = 1e-4
    assert packet_error_rate(ber, 800) < packet_error_rate(ber, 8000)
    assert packet_error_rate(ber, 8000) == pytest.approx(1 - (1 - ber) ** 8000)
    assert packet_error_rate(0.0, 8000) == 0.0


def test_mean_power_follows_the_log_distance_law_and_wall_loss() -> None:
    p = OFFICE
    at_1m = mean_power_dbm(p, 1.0, 0)
    assert at_1m == pytest.approx(p.tx_power_dbm - p.reference_loss_db)
    assert mean_power_dbm(p, 10.0, 0) == pytest.approx(at_1m - 10 * p.exponent)
    assert mean_power_dbm(p, 10.0, 2) == pytest.approx(
        mean_power_dbm(p, 10.0, 0) - 2 * p.wall_loss_db
    )


@pytest.mark.parametrize("lag_m", [1.25, 2.5, 5.0, 10.0])
def test_shadowing_correlation_follows_the_decorrelation_distance(lag_m: float) -> None:
    decorrelation = 5.0
    fields = [
        ShadowingField(6.0, decorrelation, (0, 60, 0, 60), np.random.default_rng(seed)).values
        for seed in range(12)
    ]
    spacing = ShadowingField(6.0, decorrelation, (0, 60, 0, 60), np.random.default_rng(0)).spacing
    k = round(lag_m / spacing)
    v = np.stack(fields)
    a, b = v[:, :, :-k].ravel(), v[:, :, k:].ravel()
    measured = np.corrcoef(a, b)[0, 1]
    assert measured == pytest.approx(np.exp(-k * spacing / decorrelation), abs=0.06)
    assert np.std(v) == pytest.approx(6.0, rel=0.08)


@pytest.mark.parametrize(
    ("lag_m", "low", "high"), [(0.25, 0.55, 1.0), (1.5, 0.85, 1.05), (5.0, 0.92, 1.06)]
)
def test_shadowing_between_grid_points_keeps_its_semivariogram(
    lag_m: float, low: float, high: float
) -> None:
    """Where the robots are — between grid points — half the mean squared difference of
    readings lag_m apart follows σ²(1 − exp(−Δ/dc)): closely from 0.3·dc up; below one
    grid spacing the interpolation smooths it (documented bound)."""
    sigma, dc = 6.0, 5.0
    rng = np.random.default_rng(1)
    halves = []
    for seed in range(10):
        field = ShadowingField(sigma, dc, (0, 60, 0, 40), np.random.default_rng(seed))
        points = rng.uniform([5, 5], [55, 35], size=(1500, 2))
        angle = rng.uniform(0, 2 * np.pi, len(points))
        moved = points + lag_m * np.c_[np.cos(angle), np.sin(angle)]
        a = np.array([field.at(x, y) for x, y in points])
        b = np.array([field.at(x, y) for x, y in moved])
        halves.append(0.5 * np.mean((a - b) ** 2))
    nominal = sigma**2 * (1 - np.exp(-lag_m / dc))
    assert low * nominal < np.mean(halves) < high * nominal


def test_shadowing_is_seeded_and_reciprocal() -> None:
    one = ShadowingField(6.0, 5.0, (0, 30, 0, 20), np.random.default_rng(7))
    same = ShadowingField(6.0, 5.0, (0, 30, 0, 20), np.random.default_rng(7))
    other = ShadowingField(6.0, 5.0, (0, 30, 0, 20), np.random.default_rng(8))
    assert np.array_equal(one.values, same.values)
    assert not np.array_equal(one.values, other.values)
    assert one.link(1.0, 2.0, 20.0, 15.0) == one.link(20.0, 15.0, 1.0, 2.0)


def test_two_runs_of_one_seed_draw_one_field() -> None:
    a = RadioNetwork(RadioParams.model_validate({}), profile=OFFICE, extent=(0, 30, 0, 20), seed=3)
    b = RadioNetwork(RadioParams.model_validate({}), profile=OFFICE, extent=(0, 30, 0, 20), seed=3)
    assert np.array_equal(a.field.values, b.field.values)
    assert np.array_equal(a.offsets(4), b.offsets(4))
    offsets = a.offsets(4)
    assert np.allclose(offsets, -offsets.T)  # one direction gains what the other loses
    assert np.any(offsets != 0.0)


def test_a_sender_above_capacity_sees_delays_grow_then_drops() -> None:
    """10 kbit/s; 1000-bit messages every 50 ms offer twice the capacity: each waits
    longer than the one before until the wait passes max_queue_s, then messages drop."""
    profile = OFFICE.model_copy(update={"rate_bps": 1e4, "max_queue_s": 1.0})
    channel = RadioChannel(profile, ("a", "b"))
    delays: list[float | None] = [channel.transmit(0, 0.05 * i, 1000) for i in range(60)]
    sent = [d for d in delays if d is not None]
    assert sent[:5] == pytest.approx([0.1, 0.15, 0.2, 0.25, 0.3])
    first_drop = delays.index(None)
    assert all(b > a for a, b in itertools.pairwise(sent[:first_drop]))
    assert 15 < first_drop < 25  # the wait grows by 50 ms a message: ~1 s after ~20
    assert max(sent) <= profile.max_queue_s + 1000 / 1e4 + 1e-9
    # Below capacity nothing waits: 1000 bits every 0.2 s at 10 kbit/s.
    idle = RadioChannel(profile, ("a", "b"))
    assert [idle.transmit(0, 0.2 * i, 1000) for i in range(5)] == pytest.approx([0.1] * 5)


def test_message_size_counts_the_header() -> None:
    channel = RadioChannel(OFFICE, ("a", "b"))
    pose = PoseMsg(sender="a", incarnation=1, seq=1, stamp=0.0, x=1.0, y=2.0, theta=0.0)
    assert channel.bits(pose) == (len(encode(pose)) + OFFICE.header_bytes) * 8


def test_fading_has_unit_mean_power() -> None:
    rng = np.random.default_rng(0)
    for k_db in (None, 0.0, 9.0):
        gains = np.array([fading_gain_db(rng, k_db) for _ in range(20000)])
        assert np.mean(10 ** (gains / 10)) == pytest.approx(1.0, abs=0.03)
    rayleigh = np.array([fading_gain_db(rng, None) for _ in range(5000)])
    rician = np.array([fading_gain_db(rng, 9.0) for _ in range(5000)])
    assert np.std(rician) < np.std(rayleigh)  # a line of sight fades less


BAD_PROFILES = {
    "exponent: -2.0": "exponent: must be greater than 0",
    "shadowing_sigma_db: -1.0": "shadowing_sigma_db: must be greater than or equal to 0",
    "walls_loss_db: 3.0": "unknown key 'walls_loss_db'",
    "tx_power_dbm: .nan": "tx_power_dbm: must be a finite number",
}


@pytest.mark.parametrize("line", sorted(BAD_PROFILES))
def test_bad_profiles_are_one_line_errors(tmp_path: Path, line: str) -> None:
    good = profile_path("office-2.4ghz").read_text()
    key = line.split(":")[0]
    lines = [x for x in good.splitlines() if not x.startswith(key + ":")]
    path = tmp_path / "bad.yaml"
    path.write_text("\n".join([*lines, line]) + "\n")
    with pytest.raises(InputError) as err:
        load_profile(path)
    text = str(err.value)
    assert "\n" not in text and str(path) in text and BAD_PROFILES[line] in text


def test_a_profile_missing_a_value_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "short.yaml"
    path.write_text("name: short\ntx_power_dbm: 10\n")
    with pytest.raises(InputError, match="required key is missing"):
        load_profile(path)


def test_an_unknown_profile_name_suggests_the_bundled_ones() -> None:
    with pytest.raises(InputError, match=r"did you mean 'office-2\.4ghz'"):
        load_profile("ofice-2.4ghz")


def _pulse_on_walls_grid(profile: RadioProfile) -> tuple[Any, Any, dict[str, MeasuredSensor]]:
    """Robots a and b 6 m apart in line of sight, c 6 m from a behind the thin wall."""
    from mrcomm.net.thresholds import NoThreshold
    from mrcomm.run.wiring import RadioPulse

    grid = _walls_grid()
    network = RadioNetwork(
        RadioParams.model_validate({}), profile=profile, extent=grid.extent, seed=1
    )
    ids = ("a", "b", "c")
    links = LinkModel(ids, grid, network, NoThreshold())
    sensors = {r: MeasuredSensor(-41.0) for r in ids}
    pulse = RadioPulse(network, ids, ids, 1, sensors)
    state = links.update([(4.5, 1.0), (4.5, 3.9), (4.5 + 6.0, 1.0)], 0.0)
    return pulse, state, sensors


def test_esd_readings_follow_distance_and_walls() -> None:
    """No shadowing: what a's pulse reads of b (line of sight, 2.9 m) and of c (6 m,
    one wall) is the mean power rounded to 1 dBm; at equal distance a wall reads lower."""
    quiet = OFFICE.model_copy(update={"shadowing_sigma_db": 0.0, "asymmetry_db": 0.0})
    pulse, state, sensors = _pulse_on_walls_grid(quiet)
    pulse.step(0.0, state)
    own = Pose(4.5, 1.0, 0.0)
    seen_b = sensors["a"].rssi("b", own, 0, 0, 0.0)
    seen_c = sensors["a"].rssi("c", own, 0, 0, 0.0)
    assert seen_b == round(float(mean_power_dbm(quiet, 2.9, 0)))
    assert seen_c == round(float(mean_power_dbm(quiet, 6.0, 1)))
    assert seen_c < round(float(mean_power_dbm(quiet, 6.0, 0)))


def test_a_peer_out_of_range_gives_no_reading_and_goes_stale() -> None:
    deaf = OFFICE.model_copy(update={"shadowing_sigma_db": 0.0, "sensitivity_dbm": -45.0})
    pulse, state, sensors = _pulse_on_walls_grid(deaf)
    assert not state.connected[2, 0]  # c's packets do not reach a through the wall
    pulse.step(0.0, state)
    own = Pose(4.5, 1.0, 0.0)
    assert sensors["a"].rssi("c", own, 0, 0, 0.0) is None
    assert sensors["a"].rssi("b", own, 0, 0, 0.0) is not None
    assert sensors["a"].rssi("b", own, 0, 0, 10.0) is None  # no new reading: stale
