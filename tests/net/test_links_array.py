"""A large team's distances computed as one array (no rays cast) give the missions of
the pair-by-pair computation: every decision the same, the recorded distances equal
up to the last bit (the array's are ``sqrt(dx² + dy²)``, Python's ``math.hypot`` its
own)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import mrcomm.net.links as links_module
from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission
from tests.golden.golden import comparable

ROOT = Path(__file__).resolve().parents[2]


def _differences(a: Any, b: Any, path: str = "") -> list[tuple[str, Any, Any]]:
    """Where two results differ: (path, value, value)."""
    if isinstance(a, dict) and isinstance(b, dict):
        if set(a) != set(b):
            return [(path, sorted(a), sorted(b))]
        return [d for k in a for d in _differences(a[k], b[k], f"{path}/{k}")]
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        if len(a) != len(b):
            return [(path, len(a), len(b))]
        return [
            d
            for i, (u, v) in enumerate(zip(a, b, strict=True))
            for d in _differences(u, v, f"{path}[{i}]")
        ]
    return [] if a == b else [(path, a, b)]


@pytest.mark.parametrize("network", ["wlan", "ah"])
def test_array_distances_change_no_decision(network: str, monkeypatch: pytest.MonkeyPatch) -> None:
    config = make_config(
        None,
        scenario=ROOT / "data" / "scenarios" / "s3" / "s3.yaml",
        network=network,
        threshold="slt" if network == "ah" else "none",
        behaviour="nb",
        spl=25,
        seed=2,
        max_time=40,
    )
    as_array = comparable(run_mission(config))
    monkeypatch.setattr(links_module, "ARRAY_PAIRS", 10**9)
    pair_by_pair = comparable(run_mission(config))
    differences = _differences(as_array, pair_by_pair)
    for path, a, b in differences:
        assert path.endswith(("min_distance", "max_distance")), (path, a, b)
        assert math.isclose(a, b, rel_tol=1e-12), (path, a, b)
    # The two ways really ran: their distances differ somewhere in the last bit.
    assert differences or network == "ah"


def test_array_distances_match_the_pairs() -> None:
    """The matrix itself, NaN rows of a node without a position included."""
    from mrcomm.net.links import LinkModel
    from mrcomm.net.network import Wlan
    from mrcomm.net.thresholds import NoThreshold
    from mrcomm.world.occupancy import OccupancyGrid

    grid = OccupancyGrid(np.zeros((10, 10), dtype=np.bool_), 1.0, (0.0, 0.0))
    ids = tuple(f"r{i}" for i in range(14))
    rng = np.random.default_rng(1)
    positions = rng.uniform(0, 10, (14, 2)).tolist()
    positions[3] = [math.nan, math.nan]
    results = []
    for array_pairs in (1, 10**9):
        links_module.ARRAY_PAIRS = array_pairs
        try:
            model = LinkModel(ids, grid, Wlan(), NoThreshold())
            results.append(model.update(positions, 0.0).distance)
        finally:
            links_module.ARRAY_PAIRS = 64
    np.testing.assert_allclose(results[0], results[1], rtol=1e-14)
    assert np.isnan(results[0][3, 0]) and results[0][3, 3] == 0.0


@pytest.mark.parametrize("n", [1, 2, 3, 31, 32, 33, 63, 64, 65, 130, 201])
def test_distance_matrix_is_the_whole_matrix_bit_for_bit(n: int) -> None:
    # Blocks of DISTANCE_BLOCK rows make exactly the whole matrix (a node without a
    # position is NaN), symmetric bit for bit, and within one unit in the last place of
    # hypot.
    rng = np.random.default_rng(n)
    at = rng.normal(0.0, 100.0, (n, 2))
    if n > 2:
        at[n // 2] = np.nan
        at[1] = at[0]  # two robots at the same point
    dx = at[:, 0, None] - at[None, :, 0]
    dy = at[:, 1, None] - at[None, :, 1]
    whole = np.sqrt(dx * dx + dy * dy)
    np.fill_diagonal(whole, 0.0)
    got = links_module.distance_matrix(at)
    assert got.tobytes() == whole.tobytes()
    assert got.tobytes() == got.T.copy().tobytes()  # symmetric: PairExtent relies on it
    hypot = np.hypot(dx, dy)
    np.fill_diagonal(hypot, 0.0)
    ulp = np.spacing(np.where(np.isnan(hypot), 1.0, hypot))
    assert np.all((np.abs(got - hypot) <= ulp) | (np.isnan(got) & np.isnan(hypot)))
