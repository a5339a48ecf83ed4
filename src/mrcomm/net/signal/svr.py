"""SSD signal models: two Support Vector Regressions of RSSI on distance.

One RBF-kernel SVR (gamma 0.1 m⁻², C 100, epsilon 0.1 dB — scikit-learn's default
epsilon) is fitted to the line-of-sight readings and one to the obstructed readings of a
calibration set. A fitted model is stored as plain JSON data — support vectors, dual
coefficients, intercept, hyper-parameters, trained distance range, default warning
threshold and provenance — never as a pickle, so it is safe to load, diffable and
readable from any language. Evaluation is numpy only:

    rssi(d) = Σ_i α_i exp(−γ (d − s_i)²) + b

which is exactly what scikit-learn's ``SVR.predict`` computes. Outside the trained range
an RBF model drifts towards its intercept, which means nothing physically, so
:meth:`SignalModel.predict` holds the value at the nearest end of the range (the model
*saturates*). scikit-learn is imported only by :func:`fit`.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mrcomm.errors import InputError, did_you_mean
from mrcomm.fileio import atomic_write_text
from mrcomm.net.signal.calibration import Calibration, load_calibration

FORMAT = "mrcomm-signal-model"
VERSION = 1
DEFAULT_GAMMA = 0.1
DEFAULT_C = 100.0
DEFAULT_EPSILON = 0.1
DEFAULT_THRESHOLD = -42.0
CLASSES = ("line_of_sight", "obstructed")

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class SvrCurve:
    """One fitted RBF SVR: RSSI (dBm) as a function of distance (m)."""

    support_vectors: FloatArray
    dual_coef: FloatArray
    intercept: float
    gamma: float
    C: float
    epsilon: float
    trained_range: tuple[float, float]
    n_samples: int

    def predict_raw(self, distances: ArrayLike) -> FloatArray:
        """The SVR's own prediction (no saturation), equal to scikit-learn's."""
        d = np.asarray(distances, dtype=np.float64)
        diff = d[..., None] - self.support_vectors
        exponent = -self.gamma * diff * diff
        # Not np.exp: numpy picks its exp by the CPU's vector instructions (AVX2,
        # AVX-512), and their results differ in the last bit, so a table built on one
        # machine differed from another's and SSD runs with it (seen: results recorded
        # on one machine, not reproduced on an AVX-512 one). The C library's exp is the
        # same on every x86-64 machine with FMA; ~0.2 s per table, built once per model.
        flat = exponent.ravel().tolist()
        kernel = np.fromiter(map(math.exp, flat), np.float64, len(flat)).reshape(exponent.shape)
        # A row-wise sum (not a matrix product, whose rounding depends on the batch
        # size) makes the result a pure function of each distance: saturated values
        # are then exactly constant.
        return np.asarray(np.sum(kernel * self.dual_coef, axis=-1) + self.intercept)

    def predict(self, distances: ArrayLike) -> FloatArray:
        """Prediction that saturates outside the trained distance range."""
        lo, hi = self.trained_range
        return self.predict_raw(np.clip(np.asarray(distances, dtype=np.float64), lo, hi))

    def to_json(self) -> dict[str, Any]:
        return {
            "kernel": "rbf",
            "gamma": self.gamma,
            "C": self.C,
            "epsilon": self.epsilon,
            "intercept": self.intercept,
            "support_vectors": self.support_vectors.tolist(),
            "dual_coef": self.dual_coef.tolist(),
            "trained_range": list(self.trained_range),
            "n_samples": self.n_samples,
        }


@dataclass(frozen=True, eq=False)
class SignalModel:
    """The SSD model pair plus the warning threshold it was calibrated for."""

    line_of_sight: SvrCurve
    obstructed: SvrCurve
    threshold_dbm: float = DEFAULT_THRESHOLD
    provenance: Mapping[str, Any] = field(default_factory=dict)

    def curve(self, line_of_sight: bool) -> SvrCurve:
        return self.line_of_sight if line_of_sight else self.obstructed

    def predict(self, distances: ArrayLike, line_of_sight: ArrayLike) -> FloatArray:
        """Saturating RSSI for each (distance, line of sight) pair (broadcast)."""
        d, los = np.broadcast_arrays(
            np.asarray(distances, dtype=np.float64), np.asarray(line_of_sight, dtype=bool)
        )
        out = np.empty(d.shape)
        out[los] = self.line_of_sight.predict(d[los])
        out[~los] = self.obstructed.predict(d[~los])
        return out

    def to_json(self) -> dict[str, Any]:
        return {
            "format": FORMAT,
            "version": VERSION,
            "kind": "svr",
            "threshold_dbm": self.threshold_dbm,
            "models": {
                "line_of_sight": self.line_of_sight.to_json(),
                "obstructed": self.obstructed.to_json(),
            },
            "provenance": dict(self.provenance),
        }


def fit(
    source: Calibration | str | Path,
    *,
    gamma: float = DEFAULT_GAMMA,
    C: float = DEFAULT_C,
    epsilon: float = DEFAULT_EPSILON,
    threshold_dbm: float = DEFAULT_THRESHOLD,
) -> SignalModel:
    """Fit the line-of-sight and obstructed SVRs to a calibration set (or CSV path)."""
    calibration = source if isinstance(source, Calibration) else load_calibration(source)
    curves = [
        _fit_curve(*calibration.of_class(flag), gamma=gamma, C=C, epsilon=epsilon)
        for flag in (True, False)
    ]
    provenance: dict[str, Any] = {
        "source": Path(calibration.source).name if calibration.source else "",
        "synthetic": calibration.synthetic,
        "readings": int(calibration.distance.size),
        "fitted_with": _library_versions(),
    }
    if calibration.source and Path(calibration.source).is_file():
        provenance["sha256"] = hashlib.sha256(Path(calibration.source).read_bytes()).hexdigest()
    return SignalModel(curves[0], curves[1], threshold_dbm, provenance)


def _fit_curve(
    distance: FloatArray, rssi: FloatArray, *, gamma: float, C: float, epsilon: float
) -> SvrCurve:
    from sklearn.svm import SVR  # heavy import, only needed when fitting

    svr = SVR(kernel="rbf", gamma=gamma, C=C, epsilon=epsilon)
    svr.fit(distance.reshape(-1, 1), rssi)
    return SvrCurve(
        support_vectors=np.asarray(svr.support_vectors_[:, 0], dtype=np.float64).copy(),
        dual_coef=np.asarray(svr.dual_coef_[0], dtype=np.float64).copy(),
        intercept=float(svr.intercept_[0]),
        gamma=float(gamma),
        C=float(C),
        epsilon=float(epsilon),
        trained_range=(float(distance.min()), float(distance.max())),
        n_samples=int(distance.size),
    )


def _library_versions() -> str:
    import sklearn

    import mrcomm

    return f"mrcomm {mrcomm.__version__}, scikit-learn {sklearn.__version__}"


def save_model(model: SignalModel, path: str | Path) -> None:
    """Write the model as JSON, atomically (nothing is half-written on error), creating
    its directory if needed."""
    text = json.dumps(model.to_json(), indent=1) + "\n"
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(path, text)


def load_model(path: str | Path) -> SignalModel:
    """Read a model JSON file; any problem is one :class:`InputError` naming the file
    and the offending field."""
    p = Path(path)
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError("file not found", file=p) from None
    except IsADirectoryError:
        raise InputError("is a directory, expected a model JSON file", file=p) from None
    except (json.JSONDecodeError, UnicodeDecodeError) as err:
        raise InputError(f"not a JSON signal model ({err})", file=p) from None
    except RecursionError:
        raise InputError("not a JSON signal model (nested too deeply)", file=p) from None
    except OSError as err:
        raise InputError(f"cannot read: {err}", file=p) from None
    return model_from_json(data, file=p)


def model_from_json(data: Any, *, file: str | Path | None = None) -> SignalModel:
    """Validate decoded JSON and build the model (see :func:`load_model`)."""
    reader = _Reader(file)
    top = reader.mapping(data, "")
    fmt = reader.get(top, "format", "")
    if fmt != FORMAT:
        raise reader.error("format", f"expected {FORMAT!r}, got {fmt!r}")
    version = reader.get(top, "version", "")
    if version != VERSION:
        raise reader.error("version", f"unsupported version {version!r} (expected {VERSION})")
    kind = reader.get(top, "kind", "")
    if kind != "svr":
        raise reader.error("kind", f"unsupported model kind {kind!r} (expected 'svr')")
    threshold = reader.number(reader.get(top, "threshold_dbm", ""), "threshold_dbm")
    models = reader.mapping(reader.get(top, "models", ""), "models")
    curves = [
        reader.curve(reader.get(models, name, "models"), f"models.{name}") for name in CLASSES
    ]
    provenance = reader.mapping(top.get("provenance", {}), "provenance")
    return SignalModel(curves[0], curves[1], threshold, dict(provenance))


class _Reader:
    """Field-by-field validation with errors that name the JSON path."""

    def __init__(self, file: str | Path | None) -> None:
        self.file = file

    def error(self, where: str, message: str) -> InputError:
        return InputError(message, file=self.file, field=where or None)

    def mapping(self, value: Any, where: str) -> Mapping[str, Any]:
        if not isinstance(value, Mapping):
            raise self.error(where, f"expected a JSON object, got {type(value).__name__}")
        return value

    def get(self, obj: Mapping[str, Any], key: str, where: str) -> Any:
        if key not in obj:
            hint = did_you_mean(key, [str(k) for k in obj])
            raise self.error(f"{where}.{key}" if where else key, f"missing key{hint}")
        return obj[key]

    def number(self, value: Any, where: str) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.error(where, f"expected a number, got {value!r}")
        try:
            number = float(value)  # a JSON integer can be larger than any float
        except OverflowError:
            number = math.inf
        if not math.isfinite(number):
            raise self.error(where, f"expected a finite number, got {str(value)[:40]}")
        return number

    def vector(self, value: Any, where: str) -> FloatArray:
        if not isinstance(value, list) or not value:
            raise self.error(where, "expected a non-empty list of numbers")
        return np.array([self.number(v, f"{where}[{i}]") for i, v in enumerate(value)])

    def curve(self, value: Any, where: str) -> SvrCurve:
        obj = self.mapping(value, where)
        kernel = self.get(obj, "kernel", where)
        if kernel != "rbf":
            raise self.error(f"{where}.kernel", f"unsupported kernel {kernel!r} (expected 'rbf')")
        sv = self.vector(self.get(obj, "support_vectors", where), f"{where}.support_vectors")
        coef = self.vector(self.get(obj, "dual_coef", where), f"{where}.dual_coef")
        if sv.shape != coef.shape:
            raise self.error(
                f"{where}.dual_coef",
                f"has {coef.size} values but there are {sv.size} support vectors",
            )
        rng = self.vector(self.get(obj, "trained_range", where), f"{where}.trained_range")
        if rng.size != 2 or not 0 <= rng[0] <= rng[1]:
            raise self.error(f"{where}.trained_range", "expected [min, max] with 0 <= min <= max")
        gamma = self.number(self.get(obj, "gamma", where), f"{where}.gamma")
        if gamma <= 0:
            raise self.error(f"{where}.gamma", "must be positive")
        n_samples = self.get(obj, "n_samples", where)
        if isinstance(n_samples, bool) or not isinstance(n_samples, int) or n_samples < 1:
            raise self.error(
                f"{where}.n_samples", f"expected a positive integer, got {n_samples!r}"
            )
        return SvrCurve(
            support_vectors=sv,
            dual_coef=coef,
            intercept=self.number(self.get(obj, "intercept", where), f"{where}.intercept"),
            gamma=gamma,
            C=self.number(self.get(obj, "C", where), f"{where}.C"),
            epsilon=self.number(self.get(obj, "epsilon", where), f"{where}.epsilon"),
            trained_range=(float(rng[0]), float(rng[1])),
            n_samples=n_samples,
        )
