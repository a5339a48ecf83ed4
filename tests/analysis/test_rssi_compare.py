"""SSD vs ESD: the RSSI of configurations differing only in their threshold, compared
run by run, two-sided, at equal distance too."""

from __future__ import annotations

import itertools

import numpy as np
import pandas as pd
import pytest

from mrcomm.analysis.rssi_compare import (
    DIFFER,
    hodges_lehmann,
    readings_with_distance,
    rssi_comparisons,
)
from mrcomm.analysis.stats import NOT_REJECTED

from .conftest import mrcomm


def _study(offset_db: float, runs_per: int = 8, seed: int = 0) -> tuple[pd.DataFrame, ...]:
    """Runs of two configurations (SSD, ESD) whose robots stand d = 2..10 m apart; the
    RSSI is −40 − 20·log10(d) plus noise, ESD's ``offset_db`` lower. ESD's robots stand
    farther apart, so the pooled means differ even without an offset."""
    rng = np.random.default_rng(seed)
    runs, rssi, traj = [], [], []
    for threshold, spread in (("ssd", 3.0), ("esd", 6.0)):
        for k in range(runs_per):
            run_id = f"{threshold}-{k}"
            runs.append(
                {
                    "run_id": run_id,
                    "status": "ok",
                    "scenario": "S1",
                    "network": "radio",
                    "behaviour": "lf",
                    "threshold": threshold,
                    "spl": 0.0,
                }
            )
            for step in range(60):
                t = step * 0.5
                d = 2.0 + spread * (0.5 + 0.5 * np.sin(0.3 * t + k))
                traj += [(run_id, "a", t, 0.0, 0.0), (run_id, "b", t, d, 0.0)]
                value = -40.0 - 20.0 * np.log10(d) + rng.normal(0.0, 1.0)
                value -= offset_db if threshold == "esd" else 0.0
                rssi += [(run_id, t, "a", "b", value), (run_id, t, "b", "a", value)]
    return (
        pd.DataFrame(runs),
        pd.DataFrame(rssi, columns=["run_id", "t", "src", "dst", "rssi"]),
        pd.DataFrame(traj, columns=["run_id", "robot", "t", "x", "y"]),
    )


def test_distance_of_each_reading_comes_from_both_robots_trajectories() -> None:
    _, rssi, traj = _study(0.0, runs_per=1)
    joined = readings_with_distance(rssi, traj)
    expected = traj[traj["robot"] == "b"].set_index(["run_id", "t"])["x"]
    got = joined.set_index(["run_id", "t"])["distance"]
    assert np.allclose(got.to_numpy(), expected.reindex(got.index).to_numpy())


def test_a_measured_signal_lower_at_equal_distance_is_found_with_its_size() -> None:
    runs, rssi, traj = _study(offset_db=6.0)
    table = rssi_comparisons(runs, rssi, traj)
    by = table.set_index("statistic")
    assert set(table["threshold_a"]) == {"esd"} and set(table["threshold_b"]) == {"ssd"}
    assert (table["m"].isin([0, 8])).all()  # runs are the unit, never readings
    band = by.loc["at 6 m (4-8 m)"]
    assert band["decision"] == DIFFER and band["direction"] == "ESD lower"
    assert band["shift_low"] < -6.0 < band["shift_high"]
    assert band["shift"] == pytest.approx(-6.0, abs=0.7)


def test_equal_signals_at_equal_distance_are_not_called_different() -> None:
    """ESD's robots stand farther apart: the pooled mean differs, the signal at equal
    distance does not."""
    runs, rssi, traj = _study(offset_db=0.0)
    by = rssi_comparisons(runs, rssi, traj).set_index("statistic")
    assert by.loc["mean", "decision"] == DIFFER  # confounded by distance
    assert by.loc["at 6 m (4-8 m)", "decision"] == NOT_REJECTED
    assert abs(by.loc["at 6 m (4-8 m)", "shift"]) < 1.0


def test_hodges_lehmann_is_the_median_of_all_differences() -> None:
    a, b = np.array([1.0, 4.0, 9.0]), np.array([2.0, 3.0])
    assert hodges_lehmann(a, b) == np.median([x - y for x, y in itertools.product(a, b)])


def test_no_pair_of_thresholds_gives_an_empty_table(study_db) -> None:  # type: ignore[no-untyped-def]
    runs, rssi, traj = _study(0.0)
    only_ssd = runs[runs["threshold"] == "ssd"]
    assert rssi_comparisons(only_ssd, rssi, traj).empty
    # The small AH · SLT study has one threshold: analyze says so.
    done = mrcomm("analyze", "--db", str(study_db), "--table", "rssi")
    assert done.returncode == 0, done.stderr
    assert "no two configurations differing only in their threshold" in done.stdout
