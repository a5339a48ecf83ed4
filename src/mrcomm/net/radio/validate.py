"""A radio profile held against measurements: fitted on a dataset's training readings,
judged on its held-out ones (``mrcomm radio validate``, docs/RADIO.md).

Three predictions of the mean received power of every held-out reading are judged:

* **calibrated** — the profile :func:`~mrcomm.net.radio.fit.fit_profile` fits to the
  training readings (L0, exponent, wall loss, shadowing);
* **bundled default** — the profile the radio network uses unless told otherwise
  (``office-2.4ghz``), as shipped: no calibration at all;
* **log-distance** — the plain log-distance law fitted to the training readings (its
  intercept and exponent by least squares), walls ignored: what a model without walls
  reaches on the same data.

For each: the number of readings, the RMSE and the bias (mean of predicted − measured,
dB) in line of sight (no wall), obstructed (one or more) and over all. The mean power
is what a profile predicts; a measurement also holds shadowing (σ of a few dB), which no
mean can predict: the RMSE of a perfect mean is σ.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from mrcomm.net.radio.fit import RadioFit, fit_profile
from mrcomm.net.radio.fit_data import FloatArray, Readings
from mrcomm.net.radio.model import mean_power_dbm
from mrcomm.net.radio.profile import RadioProfile

#: The classes the errors are given for: name -> which readings.
CLASSES = ("line of sight", "obstructed", "all")
MODELS = ("calibrated", "bundled default", "log-distance")


@dataclass(frozen=True)
class ErrorRow:
    """The error of one model's prediction on one class of held-out readings."""

    model: str
    where: str
    readings: int
    rmse_db: float
    bias_db: float

    def as_dict(self) -> dict[str, Any]:
        return {
            "model": self.model,
            "where": self.where,
            "readings": self.readings,
            "rmse_db": round(self.rmse_db, 2) if math.isfinite(self.rmse_db) else None,
            "bias_db": round(self.bias_db, 2) if math.isfinite(self.bias_db) else None,
        }


@dataclass(frozen=True)
class Validation:
    """A profile fitted on training readings and every model judged on the test ones."""

    fit: RadioFit
    calibrated: RadioProfile
    default: RadioProfile
    #: The log-distance law's intercept (dBm at 1 m) and exponent, fitted.
    log_distance: tuple[float, float]
    rows: tuple[ErrorRow, ...]
    #: Test readings: measured, and each model's prediction (for the figure).
    measured: FloatArray
    walls: FloatArray
    predicted: dict[str, FloatArray]

    def row(self, model: str, where: str) -> ErrorRow:
        return next(r for r in self.rows if r.model == model and r.where == where)


def log_distance_fit(readings: Readings) -> tuple[float, float]:
    """Intercept (dBm at 1 m) and exponent of RSSI = A − 10 n log10(d), least squares."""
    log_d = np.log10(np.maximum(readings.distance, 1.0))
    design = np.column_stack([np.ones_like(log_d), -10.0 * log_d])
    (a, n), *_ = np.linalg.lstsq(design, readings.rssi, rcond=None)
    return float(a), float(n)


def errors(
    model: str, predicted: FloatArray, measured: FloatArray, walls: FloatArray
) -> list[ErrorRow]:
    """RMSE and bias of ``predicted`` against ``measured`` per class of :data:`CLASSES`."""
    masks = {"line of sight": walls == 0, "obstructed": walls > 0, "all": np.ones_like(walls, bool)}
    out = []
    for where in CLASSES:
        mask = masks[where]
        diff = predicted[mask] - measured[mask]
        count = int(mask.sum())
        rmse = float(np.sqrt(np.mean(diff**2))) if count else math.nan
        bias = float(np.mean(diff)) if count else math.nan
        out.append(ErrorRow(model, where, count, rmse, bias))
    return out


def validate(
    train: Readings,
    test: Readings,
    base: RadioProfile,
    default: RadioProfile,
    name: str,
    source: str,
) -> Validation:
    """Fit on ``train`` (other values from ``base``), judge on ``test``; the calibrated
    profile is called ``name`` and says it was fitted to ``source``."""
    fitted = fit_profile(train, base)
    calibrated = fitted.profile(name, f"fitted by mrcomm radio validate to {source}")
    a, n = log_distance_fit(train)
    distance, walls = test.distance, test.walls.astype(np.float64)
    predicted = {
        "calibrated": np.asarray(mean_power_dbm(calibrated, distance, walls)),
        "bundled default": np.asarray(mean_power_dbm(default, distance, walls)),
        "log-distance": a - 10.0 * n * np.log10(np.maximum(distance, 1.0)),
    }
    rows = [row for model in MODELS for row in errors(model, predicted[model], test.rssi, walls)]
    return Validation(fitted, calibrated, default, (a, n), tuple(rows), test.rssi, walls, predicted)
