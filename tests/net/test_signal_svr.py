"""SVR signal models: numpy evaluation equals scikit-learn, JSON round trip and load
errors, and the bundled model reproduces the published behaviour."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from sklearn.svm import SVR

from mrcomm.errors import InputError
from mrcomm.net.signal.bundled import bundled_calibration_path, default_model, default_model_path
from mrcomm.net.signal.calibration import load_calibration
from mrcomm.net.signal.svr import SignalModel, fit, load_model, model_from_json, save_model
from mrcomm.net.signal.table import RssiTable


@pytest.fixture(scope="module")
def refit() -> SignalModel:
    return fit(bundled_calibration_path())


@pytest.fixture(scope="module")
def sklearn_models() -> dict[bool, SVR]:
    cal = load_calibration(bundled_calibration_path())
    out = {}
    for los in (True, False):
        d, r = cal.of_class(los)
        out[los] = SVR(kernel="rbf", gamma=0.1, C=100).fit(d.reshape(-1, 1), r)
    return out


def test_numpy_evaluation_equals_sklearn(
    refit: SignalModel, sklearn_models: dict[bool, SVR]
) -> None:
    d = np.random.default_rng(1).uniform(0.0, 30.0, 500)
    for los, svr in sklearn_models.items():
        expected = svr.predict(d.reshape(-1, 1))
        np.testing.assert_allclose(refit.curve(los).predict_raw(d), expected, rtol=0, atol=1e-9)


def test_json_round_trip_is_exact(refit: SignalModel, tmp_path: Path) -> None:
    path = tmp_path / "m.json"
    save_model(refit, path)
    back = load_model(path)
    d = np.linspace(0, 12, 301)
    for los in (True, False):
        assert np.array_equal(back.curve(los).predict_raw(d), refit.curve(los).predict_raw(d))
    assert back.threshold_dbm == -42.0
    assert back.provenance["synthetic"] is True
    assert json.loads(path.read_text())["kind"] == "svr"  # plain JSON, not a pickle


def test_refitting_bundled_csv_reproduces_bundled_model(refit: SignalModel) -> None:
    bundled = default_model()
    d = np.linspace(0.0, 30.0, 1001)
    for los in (True, False):
        np.testing.assert_allclose(
            refit.curve(los).predict(d), bundled.curve(los).predict(d), rtol=0, atol=0.01
        )


def test_bundled_model_reproduces_published_behaviour() -> None:
    table = RssiTable.from_model(default_model())
    found = table.crossings(-42.0)
    los = found["line_of_sight"]
    assert [how for _, how in los] == ["below", "above", "below"]
    assert abs(los[0][0] - 2.6) <= 0.3
    assert abs(los[1][0] - 3.6) <= 0.4
    assert abs(los[2][0] - 6.1) <= 0.4
    obstructed = found["obstructed"]
    assert [how for _, how in obstructed] == ["below"]
    assert abs(obstructed[0][0] - 1.6) <= 0.3
    assert -35.0 <= table.rssi_at(1.0, True) <= -30.0
    for flag in (True, False):  # saturation about −60 dBm beyond the trained range
        assert table.rssi_at(15.0, flag) == pytest.approx(-60.0, abs=2.0)
        assert table.rssi_at(25.0, flag) == table.rssi_at(15.0, flag)


def test_predict_saturates_outside_trained_range(refit: SignalModel) -> None:
    curve = refit.line_of_sight
    lo, hi = curve.trained_range
    assert (lo, hi) == (0.2, 9.0)
    assert curve.predict(20.0) == curve.predict_raw(hi)
    assert curve.predict(0.0) == curve.predict_raw(lo)
    mixed = refit.predict(np.array([1.0, 1.0]), np.array([True, False]))
    assert mixed[0] == curve.predict(1.0) and mixed[1] == refit.obstructed.predict(1.0)


def _model_json() -> dict[str, Any]:
    data: dict[str, Any] = json.loads(default_model_path().read_text())
    return data


@pytest.mark.parametrize(
    ("mutate", "expected"),
    [
        (lambda m: m.pop("models"), "models: missing key"),
        (lambda m: m.update(format="other"), "format: expected 'mrcomm-signal-model'"),
        (lambda m: m["models"].pop("obstructed"), "models.obstructed: missing key"),
        (
            lambda m: m["models"]["line_of_sight"].update(dual_coef=[1.0, 2.0]),
            "models.line_of_sight.dual_coef: has 2 values but there are",
        ),
        (
            lambda m: m["models"]["obstructed"].update(gamma="big"),
            "models.obstructed.gamma: expected a number",
        ),
        (
            lambda m: m["models"]["obstructed"]["support_vectors"].__setitem__(3, None),
            "models.obstructed.support_vectors[3]: expected a number",
        ),
        (
            lambda m: m["models"]["line_of_sight"].update(trained_range=[5.0]),
            "models.line_of_sight.trained_range: expected [min, max]",
        ),
        (
            lambda m: m["models"]["line_of_sight"].update(
                intercepts=m["models"]["line_of_sight"].pop("intercept")
            ),
            "models.line_of_sight.intercept: missing key (did you mean 'intercepts'?)",
        ),
    ],
)
def test_bad_model_files_are_one_line_errors(tmp_path: Path, mutate: Any, expected: str) -> None:
    data = _model_json()
    mutate(data)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    with pytest.raises(InputError) as err:
        load_model(path)
    assert err.value.one_line().startswith(f"{path}: ")
    assert expected in err.value.one_line()


def test_not_json_or_not_an_object(tmp_path: Path) -> None:
    path = tmp_path / "m.json"
    path.write_bytes(b"\x80\x04pickle?")
    with pytest.raises(InputError, match="not a JSON signal model"):
        load_model(path)
    path.write_text("[1, 2]")
    with pytest.raises(InputError, match="expected a JSON object"):
        load_model(path)
    with pytest.raises(InputError, match="file not found"):
        load_model(tmp_path / "missing.json")
    with pytest.raises(InputError):
        model_from_json({"format": "mrcomm-signal-model", "version": 99})
