"""Odometry and localisation noise: statistics and reproducibility."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mrcomm.robot.noise import LocalisationError, NormalStream, Odometry


def test_normal_stream_is_reproducible_and_standard() -> None:
    a = NormalStream(np.random.default_rng(7))
    b = NormalStream(np.random.default_rng(7))
    xs = [a.next() for _ in range(10_000)]
    assert xs == [b.next() for _ in range(10_000)]
    assert abs(np.mean(xs)) < 0.05
    assert np.std(xs) == pytest.approx(1.0, rel=0.05)
    # numpy's own sequence, whatever the block the stream draws at a time: a smaller
    # block changed no run.
    assert xs == np.random.default_rng(7).standard_normal(10_000).tolist()


def test_odometry_increment_noise_is_multiplicative_two_percent() -> None:
    odo = Odometry(NormalStream(np.random.default_rng(1)), (0.0, 0.0, 0.0), 0.02, 0.02)
    ratios_d = []
    ratios_h = []
    for _ in range(5_000):
        before_theta = odo.theta
        step = odo.add(0.05, 0.1)
        ratios_d.append(step / 0.05)
        ratios_h.append((odo.theta - before_theta) / 0.1)
    assert np.mean(ratios_d) == pytest.approx(1.0, abs=0.002)
    assert np.std(ratios_d) == pytest.approx(0.02, rel=0.1)
    assert np.mean(ratios_h) == pytest.approx(1.0, abs=0.002)
    assert np.std(ratios_h) == pytest.approx(0.02, rel=0.1)
    assert odo.distance == pytest.approx(5_000 * 0.05, rel=0.01)


def test_odometer_counts_reversing_as_distance() -> None:
    odo = Odometry(NormalStream(np.random.default_rng(2)), (0.0, 0.0, 0.0), 0.0, 0.0)
    odo.add(-0.5, 0.0)
    assert odo.distance == pytest.approx(0.5)
    assert odo.x == pytest.approx(-0.5)


def test_odometry_pose_drifts_but_stays_close() -> None:
    # 10 m straight in 1 cm steps: heading noise on a zero turn is zero, distance error
    # is 2 % / sqrt(1000 steps) of 10 m on average -- a few millimetres.
    odo = Odometry(NormalStream(np.random.default_rng(3)), (0.0, 0.0, 0.0), 0.02, 0.02)
    for _ in range(1000):
        odo.add(0.01, 0.0)
    assert odo.x != 10.0
    assert abs(odo.x - 10.0) < 0.03
    assert odo.y == pytest.approx(0.0, abs=1e-12)


def test_localisation_error_has_requested_spread_and_correlation() -> None:
    loc = LocalisationError(NormalStream(np.random.default_rng(4)), 0.02, 0.01, 2.0)
    xs, hs = [], []
    for _ in range(40_000):
        loc.step(0.1)
        xs.append(loc.ex)
        hs.append(loc.eth)
    assert np.std(xs) == pytest.approx(0.02, rel=0.15)
    assert np.std(hs) == pytest.approx(0.01, rel=0.15)
    lag1 = np.corrcoef(xs[:-1], xs[1:])[0, 1]
    assert lag1 == pytest.approx(math.exp(-0.1 / 2.0), abs=0.01)
