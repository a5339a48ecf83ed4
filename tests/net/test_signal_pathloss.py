"""Path-loss theory: FSPL and the log-distance model."""

from __future__ import annotations

import numpy as np
import pytest

from mrcomm.net.signal.pathloss import (
    fit_log_distance,
    fspl_db,
    log_distance_range,
    log_distance_rssi,
)


def test_fspl_matches_textbook_values() -> None:
    # 2.4 GHz at 1 m: 40.05 dB; every doubling of distance or frequency adds 6.02 dB.
    assert fspl_db(1.0, 2.4e9) == pytest.approx(40.05, abs=0.01)
    assert fspl_db(2.0, 2.4e9) - fspl_db(1.0, 2.4e9) == pytest.approx(6.02, abs=0.01)
    assert fspl_db(1.0, 4.8e9) - fspl_db(1.0, 2.4e9) == pytest.approx(6.02, abs=0.01)


def test_log_distance_reference_and_exponent() -> None:
    assert log_distance_rssi(1.0, 32.0, 2.5) == pytest.approx(-32.0)
    assert log_distance_rssi(10.0, 32.0, 2.5) == pytest.approx(-57.0)
    d = np.array([0.5, 2.0, 7.0])
    assert log_distance_range(log_distance_rssi(d, 35.0, 3.0), 35.0, 3.0) == pytest.approx(d)


def test_fit_log_distance_recovers_parameters() -> None:
    rng = np.random.default_rng(3)
    d = np.repeat(np.arange(1.0, 10.0), 50)
    r = log_distance_rssi(d, 33.0, 2.7) + rng.normal(0, 1.0, d.size)
    a_db, n = fit_log_distance(d, r)
    assert a_db == pytest.approx(33.0, abs=0.3)
    assert n == pytest.approx(2.7, abs=0.05)
    with pytest.raises(ValueError):
        fit_log_distance([2.0, 2.0], [-40.0, -41.0])
