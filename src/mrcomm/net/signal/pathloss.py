"""Radio propagation theory the signal models are judged against.

* Free-space path loss (Friis): ``FSPL = 20 log10(4 π d f / c)`` dB, d in metres, f in Hz.
* Log-distance model: ``RSSI(d) = −(10 n log10 d + A)`` dBm, where ``A`` is the
  magnitude of the RSSI at the 1 m reference distance (A = 32 means −32 dBm at 1 m) and
  ``n`` the path-loss exponent (2 in free space, about 1.6–1.8 in corridors that guide
  the wave, 2.7–5 indoors through walls).

The SVR models are fitted to measurements, not derived from these formulas; the fitted
log-distance parameters are printed by ``mrcomm signal fit`` as a sanity check.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

SPEED_OF_LIGHT = 299_792_458.0  # m/s

FloatArray = NDArray[np.float64]


def fspl_db(distance_m: ArrayLike, frequency_hz: float) -> FloatArray:
    """Free-space path loss ``20 log10(4 π d f / c)`` in dB (distances > 0)."""
    d = np.asarray(distance_m, dtype=np.float64)
    return np.asarray(20.0 * np.log10(4.0 * np.pi * d * frequency_hz / SPEED_OF_LIGHT))


def log_distance_rssi(distance_m: ArrayLike, a_db: float, n: float) -> FloatArray:
    """Log-distance RSSI ``−(10 n log10 d + A)`` in dBm (``A`` = |RSSI at 1 m|)."""
    d = np.asarray(distance_m, dtype=np.float64)
    return np.asarray(-(10.0 * n * np.log10(d) + a_db))


def log_distance_range(rssi_dbm: ArrayLike, a_db: float, n: float) -> FloatArray:
    """Inverse of :func:`log_distance_rssi`: the distance at which RSSI falls to a value."""
    r = np.asarray(rssi_dbm, dtype=np.float64)
    return np.asarray(10.0 ** ((-r - a_db) / (10.0 * n)))


def fit_log_distance(distance_m: ArrayLike, rssi_dbm: ArrayLike) -> tuple[float, float]:
    """Least-squares ``(A, n)`` of the log-distance model for measurements (d > 0)."""
    d = np.asarray(distance_m, dtype=np.float64)
    r = np.asarray(rssi_dbm, dtype=np.float64)
    if d.size < 2 or np.unique(d).size < 2:
        raise ValueError("need readings at two or more distances")
    # RSSI = −A − 10 n log10 d is linear in (A, n).
    design = np.column_stack([-np.ones_like(d), -10.0 * np.log10(d)])
    (a_db, n), *_ = np.linalg.lstsq(design, r, rcond=None)
    return float(a_db), float(n)
