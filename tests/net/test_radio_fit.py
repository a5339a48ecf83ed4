"""Fitting a radio profile to RSSI readings (net/radio/fit.py, experiment/radio_readings.py).

The readings are drawn with MRComm's own radio model on S1's office map: robots
wander the floor, and every 0.5 s each measures each peer as the ``radio`` network
would give it (the run's shadowing field and per-direction offsets, walls counted on
the map, rounded to whole dBm). The fit must find the profile they were drawn from."""

from __future__ import annotations

import math
from collections.abc import Sequence
from functools import cache
from pathlib import Path

import numpy as np
import pytest

from mrcomm.errors import InputError
from mrcomm.experiment.radio_readings import positions_at, read_csv_readings
from mrcomm.net.radio.fit import RadioFit, fit_profile, write_profile
from mrcomm.net.radio.fit_data import Readings
from mrcomm.net.radio.fit_shadowing import reciprocal_asymmetry
from mrcomm.net.radio.model import RadioNetwork, RadioParams
from mrcomm.net.radio.profile import RadioProfile, load_profile
from mrcomm.world.mapio import load_map
from mrcomm.world.occupancy import OccupancyGrid

MAP = Path(__file__).parents[2] / "data" / "maps" / "office.yaml"
BASE = "office-2.4ghz"
#: What the readings are drawn from: every fitted value differs from the base's
#: (office-2.4ghz: L0 40, n 3.0, 6 dB per wall, σ 6 over 5 m, asymmetry 1).
TRUTH = {
    "reference_loss_db": 45.0,
    "exponent": 2.6,
    "wall_loss_db": 4.5,
    "shadowing_sigma_db": 5.0,
    "decorrelation_m": 4.0,
    "asymmetry_db": 1.5,
}


@cache
def office() -> OccupancyGrid:
    return load_map(MAP)


def true_profile(**changes: float) -> RadioProfile:
    return load_profile(BASE).model_copy(update={**TRUTH, **changes})


def wander(grid: OccupancyGrid, rng: np.random.Generator, robots: int, steps: int) -> np.ndarray:
    """(robots, steps, 2) positions: each robot walks 0.5 m per step on a slowly
    turning heading, turning at random where the next step would leave free space."""
    free = np.argwhere(grid.distance_field() > 0.4)
    paths = np.empty((robots, steps, 2))
    for k in range(robots):
        iy, ix = free[rng.integers(len(free))]
        x, y = grid.cell_to_world(int(iy), int(ix))
        heading = rng.uniform(0.0, 2.0 * math.pi)
        for s in range(steps):
            paths[k, s] = (x, y)
            for _ in range(20):
                turn = heading + rng.normal(0.0, 0.05)
                nx, ny = x + 0.5 * math.cos(turn), y + 0.5 * math.sin(turn)
                if grid.in_bounds(nx, ny) and grid.clearance(nx, ny) > 0.3:
                    x, y, heading = nx, ny, turn
                    break
                heading = rng.uniform(0.0, 2.0 * math.pi)
    return paths


def draw_readings(
    profile: RadioProfile, seeds: Sequence[int], robots: int = 4, steps: int = 300
) -> Readings:
    """Each seed is a run: its own shadowing field, offsets and walks (one group)."""
    grid = office()
    tx: list[list[float]] = []
    rx: list[list[float]] = []
    rssi: list[float] = []
    walls: list[int] = []
    group: list[int] = []
    pair: list[int] = []
    direction: list[int] = []
    time: list[float] = []
    pairs = [(a, b) for a in range(robots) for b in range(a + 1, robots)]
    for g, seed in enumerate(seeds):
        network = RadioNetwork(
            RadioParams.model_validate({}), profile=profile, extent=grid.extent, seed=seed
        )
        offsets = network.offsets(robots)
        paths = wander(grid, np.random.default_rng(1000 + seed), robots, steps)
        for t in range(steps):
            xy = paths[:, t].tolist()
            distance = [math.dist(xy[a], xy[b]) for a, b in pairs]
            crossed = [
                0 if grid.line_of_sight(*xy[a], *xy[b]) else grid.walls_between(*xy[a], *xy[b])
                for a, b in pairs
            ]
            ends = (np.array([a for a, _ in pairs]), np.array([b for _, b in pairs]))
            power = network.pair_power(xy, ends, np.array(distance), np.array(crossed))
            for k, (a, b) in enumerate(pairs):
                for sender, receiver in ((a, b), (b, a)):
                    tx.append(xy[sender])
                    rx.append(xy[receiver])
                    # As ESD on the radio records it: the card's whole dBm.
                    rssi.append(round(power[k] + offsets[sender, receiver]))
                    walls.append(crossed[k])
                    group.append(g)
                    pair.append(g * 100 + k)
                    direction.append(1 if sender < receiver else -1)
                    time.append(0.5 * t)
    return Readings.of(
        tx, rx, rssi, walls, group=group, pair=pair, direction=direction, time=time,
        source="synthetic",
    )  # fmt: skip


@pytest.fixture(scope="module")
def drawn() -> Readings:
    """Eight runs of four robots wandering for 125 s: 24 000 readings."""
    return draw_readings(true_profile(), seeds=range(200, 208), steps=250)


@pytest.fixture(scope="module")
def fitted(drawn: Readings) -> RadioFit:
    return fit_profile(drawn, load_profile(BASE))


@pytest.fixture(scope="module")
def small() -> Readings:
    """Two runs of 75 s, for the tests of what the fit does with odd readings."""
    return draw_readings(true_profile(), seeds=(7, 8), steps=150)


def quick_fit(readings: Readings, tx_power_dbm: float | None = None) -> RadioFit:
    return fit_profile(readings, load_profile(BASE), tx_power_dbm=tx_power_dbm, max_pairs=40_000)


def test_the_fit_recovers_the_profile_the_readings_were_drawn_from(fitted: RadioFit) -> None:
    """Tolerances from the spread over six sets of eight runs (seeds 200-259): the
    field explored by a few robots in a few runs is only so much of it."""
    assert fitted.readings == 8 * 6 * 2 * 250 and fitted.groups == 8
    assert fitted.reference_loss.value == pytest.approx(45.0, abs=6.0)
    assert fitted.exponent.value == pytest.approx(2.6, abs=0.5)
    assert fitted.wall_loss.value == pytest.approx(4.5, abs=0.75)
    # The field's own σ (5 dB), not the residuals' spread (larger for links whose two
    # ends share the field, plus the offsets and the rounding).
    assert fitted.sigma.value == pytest.approx(5.0, rel=0.3)
    assert fitted.decorrelation.status == "fitted"
    assert 4.0 / 2 < fitted.decorrelation.value < 4.0 * 2
    assert fitted.asymmetry.value == pytest.approx(1.5, abs=0.5)
    assert fitted.nugget_db < 1.5
    assert fitted.r_squared > 0.85
    # Every interval holds the true value.
    for estimate, true in (
        (fitted.reference_loss, 45.0),
        (fitted.exponent, 2.6),
        (fitted.wall_loss, 4.5),
    ):
        assert estimate.status == "fitted"
        interval = estimate.interval
        assert interval is not None and interval[0] < true < interval[1]
    # L0 and A = tx − L0 share their uncertainty.
    assert fitted.intercept.value == pytest.approx(10.0 - fitted.reference_loss.value)
    assert fitted.intercept.se == fitted.reference_loss.se
    assert all(e.status == "fitted" for e in fitted.estimates().values())
    assert not any("not identifiable" in n for n in fitted.notes)


def test_intervals_account_for_correlated_readings(drawn: Readings, fitted: RadioFit) -> None:
    """Two readings a second apart share their shadowing: standard errors that
    assumed independent readings would be several times too small."""
    design = np.column_stack(
        [np.ones(len(drawn)), -10 * np.log10(np.maximum(drawn.distance, 1.0)), -drawn.walls]
    )
    naive = math.sqrt(fitted.residual_std_db**2 * np.linalg.inv(design.T @ design)[1, 1])
    assert fitted.exponent.se is not None and fitted.exponent.se > 4 * naive


def test_the_decorrelation_distance_follows_the_field(fitted: RadioFit) -> None:
    short = fit_profile(
        draw_readings(true_profile(decorrelation_m=1.5), seeds=range(120, 128), steps=200),
        load_profile(BASE),
    )
    assert short.decorrelation.status == "fitted"
    assert 1.5 / 2 < short.decorrelation.value < 1.5 * 2
    assert short.decorrelation.value < fitted.decorrelation.value / 1.5
    assert short.sigma.value == pytest.approx(5.0, rel=0.3)


def test_without_walls_the_wall_loss_is_kept_and_said(small: Readings) -> None:
    clear = small.subset(small.walls == 0)
    result = quick_fit(clear)
    assert result.wall_loss.value == 6.0 and result.wall_loss.status == "kept"
    assert result.wall_loss.interval is None
    assert any("no reading crosses a wall" in n and "kept" in n for n in result.notes)
    assert result.exponent.value == pytest.approx(2.6, abs=1.0)


def test_a_negative_wall_loss_is_clipped_to_zero(small: Readings) -> None:
    # Walls that add 8 dB to a 4.5 dB loss: the least-squares loss is about −3.5 dB.
    odd = Readings.of(
        small.tx, small.rx, small.rssi + 8.0 * small.walls, small.walls,
        group=small.group, pair=small.pair, direction=small.direction,
    )  # fmt: skip
    result = quick_fit(odd)
    assert result.wall_loss.value == 0.0 and result.wall_loss.status == "clipped"
    assert any("negative" in n and "clipped to 0" in n for n in result.notes)
    assert result.profile("odd", "test").wall_loss_db == 0.0


def test_the_stated_transmit_power_sets_l0(small: Readings) -> None:
    own = quick_fit(small)
    other = quick_fit(small, tx_power_dbm=20.0)
    assert other.intercept.value == pytest.approx(own.intercept.value)
    assert other.reference_loss.value == pytest.approx(own.reference_loss.value + 10.0)
    assert other.profile("p", "s").tx_power_dbm == 20.0


def test_readings_near_the_sensitivity_are_censored_unless_some_lie_below(
    fitted: RadioFit, drawn: Readings, small: Readings
) -> None:
    # Sensitivity −95 dBm: a simulation records the power, however weak.
    assert np.any(drawn.rssi < -95.5)
    assert fitted.excluded_censored == 0 and fitted.readings == len(drawn)
    assert any("not censored" in n for n in fitted.notes)
    # As a card reports them: nothing below the sensitivity.
    card = small.subset(small.rssi >= -95.0)
    near = int(np.count_nonzero(card.rssi <= -94.0))
    assert near > 0
    cut = quick_fit(card)
    assert cut.excluded_censored == near and cut.readings == len(card) - near
    assert any(f"left out {near} readings" in n and "censored" in n for n in cut.notes)


def test_too_few_or_degenerate_readings_are_one_line_errors(small: Readings) -> None:
    base = load_profile(BASE)
    with pytest.raises(InputError, match="only 10 usable readings, need at least 30"):
        fit_profile(small.subset(np.arange(len(small)) < 10), base)
    same = Readings.of(
        [[10.0, 10.0]] * 40, [[10.5, 10.0]] * 40, np.linspace(-40, -30, 40), [0] * 40
    )
    with pytest.raises(InputError, match="same distance"):
        fit_profile(same, base)
    rising = Readings.of(
        small.tx, small.rx, -small.rssi, small.walls, group=small.group, source="up.csv"
    )
    with pytest.raises(InputError, match=r"up\.csv: rssi: the fitted exponent is -"):
        fit_profile(rising, base, max_pairs=40_000)


def test_the_written_profile_reads_back(fitted: RadioFit, tmp_path: Path) -> None:
    profile = fitted.profile("my-office", "fitted to synthetic readings")
    out = tmp_path / "my-office.yaml"
    write_profile(out, profile, ["a comment", ""])
    assert out.read_text().startswith("# a comment\n#\n")
    back = load_profile(out)
    assert back == profile
    assert back.exponent == pytest.approx(fitted.exponent.value, abs=1e-3)
    # Values not fitted come from the base.
    assert back.rate_bps == load_profile(BASE).rate_bps and back.name == "my-office"
    assert [p.name for p in tmp_path.iterdir()] == ["my-office.yaml"]  # no temp file


def test_the_variogram_shows_the_field_rising_to_its_sill(fitted: RadioFit) -> None:
    bins = fitted.variogram
    assert len(bins) >= 6
    first, last = bins[0], max(bins, key=lambda b: b["pairs"])
    assert first["delta_m"] < 1.0 and first["measured_db2"] < last["measured_db2"] / 2
    for b in bins:
        if b["pairs"] > 2000:
            assert b["fitted_db2"] == pytest.approx(b["measured_db2"], rel=0.35)


def write_readings_csv(path: Path, readings: Readings, rows: int) -> None:
    lines = ["# synthetic readings", "x_tx,y_tx,x_rx,y_rx,rssi,note"]
    for k in range(rows):
        (xa, ya), (xb, yb) = readings.tx[k], readings.rx[k]
        lines.append(f"{xa:.3f},{ya:.3f},{xb:.3f},{yb:.3f},{readings.rssi[k]:g},x")
    path.write_text("\n".join(lines) + "\n")


def test_csv_readings_count_walls_on_the_map(small: Readings, tmp_path: Path) -> None:
    path = tmp_path / "r.csv"
    write_readings_csv(path, small, 400)
    loaded = read_csv_readings(path, office(), MAP)
    assert len(loaded) == 400 and not loaded.has_links
    assert np.array_equal(loaded.rssi, small.rssi[:400])
    # Positions rounded to 1 mm: the same walls but for rays grazing a corner.
    assert np.mean(loaded.walls == small.walls[:400]) > 0.98
    bad = tmp_path / "bad.csv"
    bad.write_text("x_tx,y_tx,x_rx,rssi\n1,2,3,-40\n")
    with pytest.raises(InputError, match=r"bad.csv: line 1: missing column 'y_rx'"):
        read_csv_readings(bad, office())
    off = tmp_path / "off.csv"
    off.write_text("x_tx,y_tx,x_rx,y_rx,rssi\n10,10,500,10,-40\n")
    with pytest.raises(InputError, match=r"line 2, column x_rx: \(500, 10\) is off the map"):
        read_csv_readings(off, office())


def test_the_asymmetry_comes_from_both_directions_read_at_once(
    drawn: Readings, fitted: RadioFit
) -> None:
    found = reciprocal_asymmetry(drawn)
    assert found is not None
    sigma_a, pairs = found
    assert pairs == 8 * 6 and sigma_a == pytest.approx(1.5, abs=0.4)
    assert fitted.asymmetry.value == pytest.approx(sigma_a)
    assert any(f"asymmetry from {pairs} robot pairs" in n for n in fitted.notes)
    # Without the times, the semivariogram fit finds it among the other terms.
    untimed = Readings.of(
        drawn.tx, drawn.rx, drawn.rssi, drawn.walls,
        group=drawn.group, pair=drawn.pair, direction=drawn.direction,
    )  # fmt: skip
    assert reciprocal_asymmetry(untimed) is None
    assert quick_fit(untimed).asymmetry.value == pytest.approx(1.5, abs=0.6)


def test_positions_are_interpolated_between_trajectory_samples() -> None:
    paths = {"a": ([0.0, 1.0, 2.0, 6.0], [0.0, 1.0, 2.0, 6.0], [5.0, 5.0, 5.0, 5.0])}
    robots = np.array(["a"] * 6 + ["b"])
    t = np.array([0.5, 1.0, 1.9, 3.0, 2.2, -0.2, 1.0])
    xy, ok = positions_at(paths, robots, t)
    assert ok.tolist() == [True, True, True, False, False, True, False]
    assert xy[0].tolist() == [0.5, 5.0] and xy[2].tolist() == pytest.approx([1.9, 5.0])
    assert xy[5].tolist() == [0.0, 5.0]  # just before the first sample: the first one
