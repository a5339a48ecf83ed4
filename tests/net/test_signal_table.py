"""RSSI lookup table: agrees with scikit-learn, saturates, broadcasts, finds crossings."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.typing import ArrayLike, NDArray
from sklearn.svm import SVR

from mrcomm.net.signal.bundled import bundled_calibration_path, default_model
from mrcomm.net.signal.calibration import load_calibration
from mrcomm.net.signal.table import RssiTable


@pytest.fixture(scope="module")
def table() -> RssiTable:
    return RssiTable.from_model(default_model())


def test_agrees_with_sklearn_at_random_distances(table: RssiTable) -> None:
    cal = load_calibration(bundled_calibration_path())
    rng = np.random.default_rng(7)
    for los in (True, False):
        d, r = cal.of_class(los)
        svr = SVR(kernel="rbf", gamma=0.1, C=100).fit(d.reshape(-1, 1), r)
        query = rng.uniform(d.min(), d.max(), 2000)
        expected = svr.predict(query.reshape(-1, 1))
        got = table.rssi(query, np.full(query.shape, los))
        assert np.max(np.abs(got - expected)) < 0.1


def test_saturates_and_clamps(table: RssiTable) -> None:
    model = default_model()
    for los in (True, False):
        lo, hi = model.curve(los).trained_range
        edge_hi = float(model.curve(los).predict_raw(hi))
        edge_lo = float(model.curve(los).predict_raw(lo))
        far = table.rssi(np.array([hi + 0.5, 20.0, 30.0, 1e6]), np.full(4, los))
        np.testing.assert_allclose(far, edge_hi, atol=1e-9)
        near = table.rssi(np.array([0.0, lo / 2, -1.0]), np.full(3, los))
        np.testing.assert_allclose(near, edge_lo, atol=1e-9)


def test_vectorised_over_matrices(table: RssiTable) -> None:
    d = np.array([[0.0, 2.0, 5.0], [2.0, 0.0, 7.5], [5.0, 7.5, 0.0]])
    los = np.array([[True, True, False], [True, True, True], [False, True, True]])
    out = table.rssi(d, los)
    assert out.shape == (3, 3)
    assert out[0, 2] == table.rssi_at(5.0, False)
    assert out[1, 2] == table.rssi_at(7.5, True)
    assert np.array_equal(out, out.T)
    # The scalar path gives the same bits as the vectorised one.
    rng = np.random.default_rng(2)
    for dist, flag in zip(rng.uniform(-1, 40, 200), rng.random(200) < 0.5, strict=True):
        assert table.rssi_at(float(dist), bool(flag)) == table.rssi(dist, flag)
    # A scalar line-of-sight flag broadcasts over the distances.
    assert np.array_equal(table.rssi(d, True), table.rssi(d, np.ones_like(los)))


class _Linear:
    """RSSI falling 5 dB per metre from −30 dBm, then rising again after 6 m."""

    threshold_dbm = -42.0

    def predict(self, distances: ArrayLike, line_of_sight: ArrayLike) -> NDArray[np.float64]:
        d = np.asarray(distances, dtype=np.float64)
        v = -30.0 - 5.0 * np.minimum(d, 6.0) + 5.0 * np.maximum(d - 6.0, 0.0)
        return np.asarray(np.where(np.asarray(line_of_sight, dtype=bool), v, v - 10.0))


def test_crossings_on_a_known_model() -> None:
    table = RssiTable.from_model(_Linear(), max_range=12.0)
    found = table.crossings()
    # −30 − 5 d = −42 at 2.4 m; back at −42 at 6 + 3.6 m.
    assert found["line_of_sight"] == [(2.4, "below"), (pytest.approx(9.6), "above")]
    # Obstructed starts at −40: below from 0.4 m; rises to −42 at 6 + 5.6 m.
    assert found["obstructed"] == [(0.4, "below"), (pytest.approx(11.6), "above")]
    assert table.crossings(-20.0) == {"line_of_sight": [], "obstructed": []}
    assert table.max_range == pytest.approx(12.0)


def test_rejects_bad_grid() -> None:
    with pytest.raises(ValueError):
        RssiTable.from_model(_Linear(), resolution=0.0)
