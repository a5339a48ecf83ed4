"""A trajectory kept as one array of doubles (run/trajectory.py) reads as the list of
(t, x, y) tuples it replaces: the same values bit for bit, in order, and far smaller."""

from __future__ import annotations

import math
import pickle
import sys

import numpy as np
import pytest

from mrcomm.run.trajectory import Trajectory


def _samples(n: int) -> list[tuple[float, float, float]]:
    rng = np.random.default_rng(n)
    xy = rng.uniform(-300.0, 300.0, (n, 2)).round(3).tolist()
    return [(round(0.5 * k, 3), x, y) for k, (x, y) in enumerate(xy)]


@pytest.mark.parametrize("n", [0, 1, 7, 500])
def test_reads_as_the_list_it_replaces(n: int) -> None:
    samples = _samples(n)
    track = Trajectory()
    for sample in samples:
        track.append(sample)
    assert len(track) == n and list(track) == samples and track == samples
    assert [track[k] for k in range(n)] == samples
    assert [track[-k] for k in range(1, n + 1)] == [samples[-k] for k in range(1, n + 1)]
    assert track[1:5] == samples[1:5] and track[::-3] == samples[::-3]
    for bad in (n, -n - 1):
        with pytest.raises(IndexError):
            track[bad]
    assert Trajectory(samples) == track and pickle.loads(pickle.dumps(track)) == track
    assert all(type(v) is float for sample in track for v in sample)


def test_keeps_every_double_bit_for_bit() -> None:
    odd = [(0.1, math.pi, -1e-300), (1e300, -0.0, 5e-324), (math.inf, 2.0**52 + 1, 0.3)]
    assert [tuple(map(float.hex, s)) for s in Trajectory(odd)] == [
        tuple(map(float.hex, s)) for s in odd
    ]


def test_is_far_smaller_than_the_list_of_tuples() -> None:
    samples = _samples(10_000)
    listed = sys.getsizeof(samples) + sum(
        sys.getsizeof(s) + sum(sys.getsizeof(v) for v in s) for s in samples
    )
    track = Trajectory(samples)
    assert sys.getsizeof(track._values) < listed / 4
