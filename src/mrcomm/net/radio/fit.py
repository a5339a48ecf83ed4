"""Fitting a radio profile to RSSI readings (``mrcomm radio fit``).

A reading is one RSSI value (dBm) measured at a receiver of a transmitter's packets,
with both antennas' positions and the walls between them on the map. The model is the
``radio`` network model's (:mod:`mrcomm.net.radio.model`)::

    rssi = A − 10 n log10(max(d, 1 m)) − w · walls + ε,     A = tx_power − L0

**Mean** — ordinary least squares for (A, n, w). The wall loss must be ≥ 0: a negative
least-squares value is clipped to 0 and A, n refitted without the walls (noted). When
the readings do not vary in the number of walls crossed (none crosses a wall, or all
cross the same number), w cannot be told apart from A: it is kept at the base
profile's value (noted) and A, n fitted with it. L0 = tx_power − A, for the transmit
power the user states (default: the base profile's).

**Residuals** — ε is, in the model, the sum of

* the link's shadowing ``S = (F(a) + F(b)) / √2`` of a field F with standard deviation
  σ and correlation ``exp(−Δ/dc)``; two readings i, j (transmitter a, receiver b) have
  ``cov(S_i, S_j) = σ² · ½ [ρ(a_i a_j) + ρ(a_i b_j) + ρ(b_i a_j) + ρ(b_i b_j)]``
  (so a short link varies by up to 2σ²: its two ends share the field);
* the per-direction offset of the pair (σ_a, ``asymmetry_db``): ``+x`` one way, ``−x``
  the other, fixed for a run;
* a nugget τ² of independent noise per reading: quantisation to whole dBm (1/12 dB²),
  fast fading, measurement noise.

Readings of different groups (runs: each run draws its own field and offsets) are
independent. **Shadowing** — a weighted least-squares fit of the semivariogram, the
classic way of fitting Gudmundson's ``exp(−Δ/dc)`` to measurements, with each pair's
own geometry instead of one Δ per bin: for pairs of readings i, j of the same group,
``½ (r_i − r_j)²`` has expectation

    γ_ij = σ² [½(1 + ρ(d_i)) + ½(1 + ρ(d_j)) − k_ij(dc)] + σ_a² (1 − s_ij) + τ²

(k_ij the bracket above, ρ(d) the correlation of a link's own two ends d apart,
s_ij = ±1 for two readings of the same robot pair the same or the other way, 0
otherwise). Differences, not products, so each group's (each run's) own mean level
cancels. σ_a comes first, when the readings say when they were taken: half the
difference of a pair's two directions read at the same moment is its offset plus
independent noise, whatever the shadowing, walls or position errors (the two share
them) — :func:`reciprocal_asymmetry`; its part of γ is then taken out. For each dc on a
log grid (then refined), (σ², τ²[, σ_a² when it was not found so]) are the
non-negative least-squares solution — linear — and dc the one with the smallest
error; a pilot fit with equal weights, then weights 1/γ² (the variance of
½(r_i − r_j)² is 2γ² for Gaussian residuals, so short lags, where dc shows, count
more: Cressie's weighting). The pairs: every pair of a group when there are at most
``max_pairs``, else a seeded sample, half of it neighbours in the readings' order (they
come in time order: close in space) and half uniform; lags beyond half the largest are
left out (few, far apart places). Without link identities (a CSV of readings) σ_a is
not fitted (kept at the base profile's value; the nugget holds it). Residuals are
scaled by N/(N − p) first (p fitted mean parameters). :attr:`RadioFit.variogram` bins
the measured and fitted semivariogram by the mean distance between matched link ends.

What is identifiable: σ and dc only as well as the readings sample the field. A few
robots in a few runs see a few dozen decorrelation areas; a field that does not
decorrelate within the readings' extent leaves dc unidentified (kept at the base's,
σ refitted with it, noted), and over a small area σ and dc come out low together (the
semivariogram of one realisation levels off below its sill). The simulator's own field
(:mod:`mrcomm.net.radio.shadowing`, bilinear between grid points dc/8 apart) is
smoother than ``exp(−Δ/dc)`` at lags of a few grid points, so readings of robots that
stand still much of the time (many short lags) give a larger dc than the profile's.

**Intervals** — the readings are strongly correlated (a robot reads its peers twice a
second while the field changes over metres), so independent-error standard errors
would be far too small: the covariance of (A, n, w) is the sandwich
``(XᵀX)⁻¹ XᵀΣX (XᵀX)⁻¹`` with Σ the fitted residual covariance (exact per group up to
:data:`MEAT_EXACT` readings, beyond an unbiased estimate from a seeded subset); 95 %
intervals are ±1.96 standard errors. σ, dc and σ_a get no interval.

**Censoring** — a card reports nothing below its sensitivity, so readings near it are
a censored sample. When no reading lies below the sensitivity, readings within
``censor_margin_db`` of it are left out (noted, with their share: the rest is then a
truncated sample, biased towards a stronger signal where many readings lie near the
floor). When some do (a simulation records the modelled power whatever it is), the
readings are not censored and all are kept.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray
from scipy.optimize import minimize_scalar, nnls
from scipy.spatial.distance import cdist

from mrcomm.errors import InputError
from mrcomm.fileio import atomic_write_text
from mrcomm.net.radio.profile import RadioProfile

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: Fewest readings a profile is fitted from (after censored ones are left out).
MIN_READINGS = 30
#: Readings within this many dB of the sensitivity are left out as censored (when no
#: reading lies below it).
CENSOR_MARGIN_DB = 1.0
#: Reading pairs used by the covariance fit (all pairs of a group if fewer).
MAX_PAIRS = 200_000
#: Per group, the sandwich's middle term is exact up to this many readings.
MEAT_EXACT = 1200
#: 95 % two-sided normal quantile.
Z95 = 1.959963984540054
#: Fewest robot pairs read both ways at once that σ_a is estimated from directly.
MIN_RECIPROCAL = 3
#: Below this shadowing σ (dB) there is no field to find a decorrelation distance of.
MIN_SIGMA_FOR_DC = 0.5
#: Decorrelation distances searched (m): from this ...
DC_MIN = 0.1
#: ... up to the profile's limit.
DC_MAX = 1000.0
#: Bins (m) of the semivariogram shown, by the mean distance between matched link ends.
VARIOGRAM_EDGES = (0.0, 0.5, 1.0, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0, 24.0, 32.0, 48.0, 64.0)
#: A semivariogram bin is shown with at least this many pairs.
VARIOGRAM_MIN_PAIRS = 30


@dataclass(frozen=True, eq=False)
class Readings:
    """RSSI readings and their geometry (parallel arrays, one entry per reading).

    ``tx``/``rx``: (n, 2) positions of the transmitter and the receiver (m, map frame);
    ``walls``: walls crossed by the straight line between them; ``group``: readings of
    different groups have independent shadowing (runs); ``pair`` and ``direction``: the
    unordered robot pair within the group (−1: unknown) and which way the reading went
    (±1), for the per-direction offsets; ``time``: when (s; NaN: unknown), to find the
    two directions of a pair read at the same moment."""

    tx: FloatArray
    rx: FloatArray
    rssi: FloatArray
    walls: IntArray
    group: IntArray
    pair: IntArray
    direction: IntArray
    time: FloatArray
    source: str = ""
    #: What the readings are and how they were made (printed with the fit).
    notes: tuple[str, ...] = ()

    @classmethod
    def of(
        cls,
        tx: Any,
        rx: Any,
        rssi: Any,
        walls: Any,
        *,
        group: Any = None,
        pair: Any = None,
        direction: Any = None,
        time: Any = None,
        source: str = "",
        notes: Sequence[str] = (),
    ) -> Readings:
        r = np.asarray(rssi, dtype=np.float64).reshape(-1)
        n = r.size
        return cls(
            tx=np.asarray(tx, dtype=np.float64).reshape(n, 2),
            rx=np.asarray(rx, dtype=np.float64).reshape(n, 2),
            rssi=r,
            walls=np.asarray(walls, dtype=np.int64).reshape(n),
            group=np.zeros(n, np.int64) if group is None else np.asarray(group, np.int64),
            pair=np.full(n, -1, np.int64) if pair is None else np.asarray(pair, np.int64),
            direction=(
                np.ones(n, np.int64) if direction is None else np.asarray(direction, np.int64)
            ),
            time=np.full(n, np.nan) if time is None else np.asarray(time, np.float64),
            source=source,
            notes=tuple(notes),
        )

    def __len__(self) -> int:
        return int(self.rssi.size)

    @property
    def distance(self) -> FloatArray:
        return np.asarray(np.hypot(*(self.tx - self.rx).T))

    @property
    def has_links(self) -> bool:
        """Whether the readings say which robot pair each came from."""
        return bool(self.pair.size) and bool(np.all(self.pair >= 0))

    def subset(self, mask: NDArray[np.bool_]) -> Readings:
        return Readings(
            self.tx[mask],
            self.rx[mask],
            self.rssi[mask],
            self.walls[mask],
            self.group[mask],
            self.pair[mask],
            self.direction[mask],
            self.time[mask],
            self.source,
            self.notes,
        )


@dataclass(frozen=True)
class Estimate:
    """One fitted (or kept) parameter."""

    value: float
    base: float
    #: Standard error, when the parameter was fitted freely.
    se: float | None = None
    #: 'fitted', 'kept' (the base profile's value) or 'clipped' (at a bound).
    status: str = "fitted"

    @property
    def interval(self) -> tuple[float, float] | None:
        if self.se is None:
            return None
        return (self.value - Z95 * self.se, self.value + Z95 * self.se)

    def as_dict(self) -> dict[str, Any]:
        ci = self.interval
        return {
            "value": _round(self.value),
            "ci95": None if ci is None else [_round(ci[0]), _round(ci[1])],
            "se": None if self.se is None else _round(self.se),
            "base": _round(self.base),
            "status": self.status,
        }


#: The profile's key of each fitted parameter, in the order of the summary.
PROFILE_KEYS = {
    "reference_loss": "reference_loss_db",
    "exponent": "exponent",
    "wall_loss": "wall_loss_db",
    "sigma": "shadowing_sigma_db",
    "decorrelation": "decorrelation_m",
    "asymmetry": "asymmetry_db",
}


@dataclass(frozen=True)
class RadioFit:
    """What :func:`fit_profile` found."""

    base: RadioProfile
    tx_power_dbm: float
    #: A = tx − L0: the mean power at the 1 m reference, dBm.
    intercept: Estimate
    reference_loss: Estimate
    exponent: Estimate
    wall_loss: Estimate
    sigma: Estimate
    decorrelation: Estimate
    asymmetry: Estimate
    #: Independent noise per reading (quantisation, fading), dB.
    nugget_db: float
    readings: int
    groups: int
    excluded_censored: int
    r_squared: float
    #: Standard deviation of the residuals, corrected for the fitted mean parameters.
    residual_std_db: float
    #: The semivariogram of the residuals, measured and fitted, binned by distance.
    variogram: list[dict[str, float]]
    notes: list[str] = field(default_factory=list)
    source: str = ""

    def estimates(self) -> dict[str, Estimate]:
        return {name: getattr(self, name) for name in PROFILE_KEYS}

    def profile(self, name: str, source: str) -> RadioProfile:
        """The base profile with the fitted values (and the stated transmit power)."""
        values = self.base.model_dump()
        values.update({key: _round(getattr(self, k).value) for k, key in PROFILE_KEYS.items()})
        values.update(name=name, source=source, tx_power_dbm=self.tx_power_dbm)
        return RadioProfile.model_validate(values)

    def as_dict(self) -> dict[str, Any]:
        return {
            "source": self.source,
            "base": self.base.name,
            "tx_power_dbm": self.tx_power_dbm,
            "intercept_dbm": self.intercept.as_dict(),
            **{key: getattr(self, k).as_dict() for k, key in PROFILE_KEYS.items()},
            "nugget_db": _round(self.nugget_db),
            "readings": self.readings,
            "groups": self.groups,
            "excluded_censored": self.excluded_censored,
            "r_squared": _round(self.r_squared, 4),
            "residual_std_db": _round(self.residual_std_db),
            "variogram": self.variogram,
            "notes": list(self.notes),
        }


def _round(value: float, digits: int = 3) -> float:
    return float(round(float(value), digits))


# -- the fit ---------------------------------------------------------------------------


def fit_profile(
    readings: Readings,
    base: RadioProfile,
    *,
    tx_power_dbm: float | None = None,
    seed: int = 0,
    max_pairs: int = MAX_PAIRS,
    censor_margin_db: float = CENSOR_MARGIN_DB,
    min_readings: int = MIN_READINGS,
) -> RadioFit:
    """Fit L0, n, wall loss, σ, dc (and σ_a when the readings name their links) to
    ``readings``; see the module docstring. Too few or degenerate readings are an
    :class:`InputError` naming the readings' source."""
    notes = list(readings.notes)
    tx = base.tx_power_dbm if tx_power_dbm is None else float(tx_power_dbm)
    readings, excluded = censor(readings, base.sensitivity_dbm, censor_margin_db, notes=notes)
    n = len(readings)
    where = readings.source or None
    if n < min_readings:
        raise InputError(
            f"only {n} usable readings, need at least {min_readings}", file=where, field="rssi"
        )
    if np.all(readings.rssi == np.round(readings.rssi)):
        notes.append(
            "readings are whole dBm (quantised: 1/12 dB² of noise per reading, in the nugget)"
        )
    y = readings.rssi
    log_d = np.log10(np.maximum(readings.distance, 1.0))
    if np.ptp(log_d) < 1e-3:
        raise InputError(
            "every reading is at the same distance (or within 1 m): the exponent cannot be fitted",
            file=where,
            field="readings",
        )
    walls = readings.walls.astype(np.float64)
    beta, design, offset, wall_status = _fit_mean(y, log_d, walls, base.wall_loss_db, notes)
    p = design.shape[1]
    if np.linalg.matrix_rank(design) < p:
        raise InputError(
            "distance and walls vary together in these readings: L0, n and the wall loss "
            "cannot be told apart",
            file=where,
            field="readings",
        )
    a_value, n_value = float(beta[0]), float(beta[1])
    if n_value <= 0:
        raise InputError(
            f"the fitted exponent is {n_value:.2f}: the readings do not fall with distance",
            file=where,
            field="rssi",
        )
    residual = y - offset - design @ beta
    dof = n - p
    residual_std = float(np.sqrt(residual @ residual / dof))
    total = float(np.sum((y - y.mean()) ** 2))
    r_squared = 1.0 - float(residual @ residual) / total if total > 0 else 0.0

    cov, shadowing, nugget, variogram = _fit_covariance(
        readings, residual * math.sqrt(n / dof), base, seed=seed, max_pairs=max_pairs, notes=notes
    )
    bread = np.linalg.inv(design.T @ design)
    beta_cov = bread @ _meat(design, readings, cov, seed) @ bread
    se = np.sqrt(np.clip(np.diag(beta_cov), 0.0, None))

    base_a = base.tx_power_dbm - base.reference_loss_db
    intercept = Estimate(a_value, base_a, float(se[0]))
    reference = Estimate(tx - a_value, base.reference_loss_db, float(se[0]))
    exponent = Estimate(n_value, base.exponent, float(se[1]))
    if wall_status == "fitted":
        wall = Estimate(float(beta[2]), base.wall_loss_db, float(se[2]))
    else:
        value = 0.0 if wall_status == "clipped" else base.wall_loss_db
        wall = Estimate(value, base.wall_loss_db, None, wall_status)
    return RadioFit(
        base=base,
        tx_power_dbm=tx,
        intercept=intercept,
        reference_loss=reference,
        exponent=exponent,
        wall_loss=wall,
        sigma=shadowing["sigma"],
        decorrelation=shadowing["decorrelation"],
        asymmetry=shadowing["asymmetry"],
        nugget_db=nugget,
        readings=n,
        groups=int(np.unique(readings.group).size),
        excluded_censored=excluded,
        r_squared=r_squared,
        residual_std_db=residual_std,
        variogram=variogram,
        notes=notes,
        source=readings.source,
    )


def censor(
    readings: Readings,
    sensitivity: float,
    margin: float = CENSOR_MARGIN_DB,
    *,
    notes: list[str],
) -> tuple[Readings, int]:
    """Leave out readings within ``margin`` dB of the sensitivity, unless the readings
    go below it (then they are not censored); say which in ``notes``. Returns the
    readings kept and how many were left out."""
    below = int(np.count_nonzero(readings.rssi < sensitivity - 0.5))
    if below:
        notes.append(
            f"{below} readings lie below the sensitivity ({sensitivity:g} dBm): the "
            "readings are not censored (a simulation records the modelled power), all kept"
        )
        return readings, 0
    near = readings.rssi <= sensitivity + margin
    count = int(np.count_nonzero(near))
    if count:
        share = 100.0 * count / max(len(readings), 1)
        notes.append(
            f"left out {count} readings ({share:.1f} %) within {margin:g} dB of the "
            f"sensitivity ({sensitivity:g} dBm): a card reports nothing below it, so they "
            "are a censored sample"
            + ("; so many that the fit is biased towards a stronger signal" if share > 5 else "")
        )
    return readings.subset(~near), count


def _fit_mean(
    y: FloatArray, log_d: FloatArray, walls: FloatArray, base_wall: float, notes: list[str]
) -> tuple[FloatArray, FloatArray, FloatArray, str]:
    """Least squares (A, n[, w]): (coefficients, design, fixed offset, wall status)."""
    ones = np.ones_like(y)
    slope = -10.0 * log_d
    if np.unique(walls).size < 2:
        crossed = (
            "no reading crosses a wall"
            if walls.max() == 0
            else (f"every reading crosses {int(walls[0])} wall(s)")
        )
        notes.append(
            f"{crossed}: the wall loss cannot be told apart from L0; kept the base "
            f"profile's {base_wall:g} dB"
        )
        design = np.column_stack([ones, slope])
        offset = -base_wall * walls
        beta = np.asarray(np.linalg.lstsq(design, y - offset, rcond=None)[0], np.float64)
        return beta, design, offset, "kept"
    design = np.column_stack([ones, slope, -walls])
    beta = np.asarray(np.linalg.lstsq(design, y, rcond=None)[0], np.float64)
    if beta[2] >= 0:
        return beta, design, np.zeros_like(y), "fitted"
    notes.append(
        f"the least-squares wall loss is negative ({beta[2]:.2f} dB): clipped to 0 and "
        "L0, n refitted without walls"
    )
    design = design[:, :2]
    beta = np.asarray(np.linalg.lstsq(design, y, rcond=None)[0], np.float64)
    return beta, design, np.zeros_like(y), "clipped"


# -- the residuals' covariance ---------------------------------------------------------


@dataclass(frozen=True)
class _Covariance:
    """The fitted residual covariance: σ², dc, σ_a² (per-direction offsets of the same
    robot pair; only with ``links``) and τ² (the nugget)."""

    sigma2: float
    dc: float
    asym2: float
    tau2: float
    links: bool

    def pair(self, r: Readings, i: IntArray, j: IntArray, ends: FloatArray) -> FloatArray:
        """Covariance of the residuals of readings i and j (i ≠ j)."""
        cov = self.sigma2 * _kernel(ends, self.dc)
        if self.links:
            cov = cov + self.asym2 * _same_pair_sign(r, i, j)
        return np.asarray(cov)

    def variance(self, r: Readings, at: IntArray | slice = slice(None)) -> FloatArray:
        """Variance of each reading's residual."""
        own = r.distance[at]
        return np.asarray(self.sigma2 * (1.0 + np.exp(-own / self.dc)) + self.asym2 + self.tau2)


def _same_pair_sign(r: Readings, i: IntArray, j: IntArray) -> FloatArray:
    """+1 for two readings of the same robot pair the same way, −1 the other way, else 0."""
    same = (r.pair[i] == r.pair[j]) & (r.group[i] == r.group[j])
    return np.asarray(same * r.direction[i] * r.direction[j], dtype=np.float64)


def reciprocal_asymmetry(r: Readings) -> tuple[float, int] | None:
    """σ_a from the readings of both directions of a robot pair at the same moment:
    half their difference is the pair's offset plus independent noise, whatever the
    shadowing, the walls or any error in the positions (the two share them). The
    offset of each (group, pair) is the mean half-difference; σ_a² is the mean of
    their squares less their sampling variance. (σ_a, pairs), or None without
    :data:`MIN_RECIPROCAL` pairs read both ways at least 10 times."""
    if not r.has_links or np.isnan(r.time).all():
        return None
    key = np.stack([r.group, r.pair, np.round(r.time * 1000).astype(np.int64)])
    order = np.lexsort(key[::-1])
    k, rssi, direction = key[:, order], r.rssi[order], r.direction[order]
    same = np.all(k[:, 1:] == k[:, :-1], axis=0) & (direction[1:] == -direction[:-1])
    first = np.flatnonzero(same)
    if first.size == 0:
        return None
    half = (rssi[first] - rssi[first + 1]) / 2.0 * direction[first]
    ids = k[0, first] * (int(k[1].max()) + 1) + k[1, first]
    _, which, counts = np.unique(ids, return_inverse=True, return_counts=True)
    sums = np.bincount(which, weights=half)
    means = sums / counts
    spread = np.bincount(which, weights=half**2) / counts - means**2
    usable = counts >= 10
    if np.count_nonzero(usable) < MIN_RECIPROCAL:
        return None
    m, c, v = means[usable], counts[usable], spread[usable]
    asym2 = float(np.mean(m**2 - v / np.maximum(c - 1, 1)))
    return math.sqrt(max(asym2, 0.0)), int(np.count_nonzero(usable))


def _sample_pairs(group: IntArray, max_pairs: int, seed: int) -> tuple[IntArray, IntArray]:
    """Index pairs (i ≠ j) of readings of the same group: every pair when there are at
    most ``max_pairs``; otherwise half of them neighbours in the readings' order (lags
    1, 2, 3, 4, 6, 8, ... 256: readings come in time order, so these are close in
    space, where the decorrelation distance and the nugget show) and half a uniform
    sample, both seeded."""
    order = np.argsort(group, kind="stable")
    _, starts, counts = np.unique(group[order], return_index=True, return_counts=True)
    total = int(np.sum(counts * (counts - 1) // 2))
    rng = np.random.default_rng(seed)
    firsts: list[IntArray] = []
    seconds: list[IntArray] = []
    if total <= max_pairs:
        for start, count in zip(starts.tolist(), counts.tolist(), strict=True):
            members = order[start : start + count]
            i, j = np.triu_indices(count, k=1)
            firsts.append(members[i])
            seconds.append(members[j])
    else:
        lags = sorted({int(v) for v in np.geomspace(1, 256, 24).round()})
        near_i: list[IntArray] = []
        near_j: list[IntArray] = []
        for start, count in zip(starts.tolist(), counts.tolist(), strict=True):
            members = order[start : start + count]
            for lag in lags:
                if lag < count:
                    near_i.append(members[:-lag])
                    near_j.append(members[lag:])
        if near_i:
            i, j = np.concatenate(near_i), np.concatenate(near_j)
            if i.size > max_pairs // 2:
                keep = np.sort(rng.choice(i.size, max_pairs // 2, replace=False))
                i, j = i[keep], j[keep]
            firsts.append(i)
            seconds.append(j)
        for start, count in zip(starts.tolist(), counts.tolist(), strict=True):
            members = order[start : start + count]
            pairs = count * (count - 1) // 2
            if pairs == 0:
                continue
            m = max(1, round(max_pairs / 2 * pairs / total))
            i = rng.integers(0, count, m)
            j = rng.integers(0, count - 1, m)
            j = j + (j >= i)  # uniform over the others
            firsts.append(members[i])
            seconds.append(members[j])
    if not firsts:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    return np.concatenate(firsts), np.concatenate(seconds)


def _end_distances(r: Readings, i: IntArray, j: IntArray) -> FloatArray:
    """(4, m) distances between the ends of links i and j: aa, ab, ba, bb."""
    ta, tb, ra, rb = r.tx[i], r.tx[j], r.rx[i], r.rx[j]
    return np.stack(
        [
            np.hypot(*(ta - tb).T),
            np.hypot(*(ta - rb).T),
            np.hypot(*(ra - tb).T),
            np.hypot(*(ra - rb).T),
        ]
    )


def _kernel(distances: FloatArray, dc: float) -> FloatArray:
    """½ Σ exp(−D/dc) over the four end distances: the shadowing covariance in σ²."""
    return np.asarray(0.5 * np.exp(-distances / dc).sum(axis=0))


def _nnls(columns: FloatArray, target: FloatArray, weight: FloatArray) -> tuple[FloatArray, float]:
    """Non-negative weighted least squares through the (small) normal equations:
    (coefficients, weighted squared error)."""
    weighted = columns * weight[:, None]
    gram = weighted.T @ columns
    rhs = weighted.T @ target
    scale = np.sqrt(np.clip(np.diag(gram), 1e-300, None))
    gram_s = gram / np.outer(scale, scale) + 1e-12 * np.eye(len(scale))
    lower = np.linalg.cholesky(gram_s)
    theta_s, _ = nnls(lower.T, np.linalg.solve(lower, rhs / scale))
    theta = theta_s / scale
    error = float(theta @ gram @ theta - 2.0 * theta @ rhs + np.sum(weight * target**2))
    return theta, error


def _fit_covariance(
    readings: Readings,
    residual: FloatArray,
    base: RadioProfile,
    *,
    seed: int,
    max_pairs: int,
    notes: list[str],
) -> tuple[_Covariance, dict[str, Estimate], float, list[dict[str, float]]]:
    """The semivariogram fit of σ², dc, σ_a², τ² (see the module docstring): the fitted
    covariance, the estimates of σ, dc and σ_a, the nugget (dB) and the binned
    semivariogram."""
    i, j = _sample_pairs(readings.group, max_pairs, seed)
    if i.size < 3:
        raise InputError("too few readings to fit the shadowing", file=readings.source or None)
    ends = _end_distances(readings, i, j)
    own = readings.distance
    target = 0.5 * (residual[i] - residual[j]) ** 2
    links = readings.has_links
    reciprocal = reciprocal_asymmetry(readings)
    asym_col: FloatArray | None = None
    if reciprocal is not None:
        # σ_a known from the pairs read both ways at once: its part of γ taken out.
        target = target - reciprocal[0] ** 2 * (1.0 - _same_pair_sign(readings, i, j))
    elif links:
        asym_col = 1.0 - _same_pair_sign(readings, i, j)
    nugget_col = np.ones(i.size)

    def columns(dc: float) -> FloatArray:
        sill = 1.0 + 0.5 * (np.exp(-own[i] / dc) + np.exp(-own[j] / dc))
        cols = [sill - _kernel(ends, dc), nugget_col]
        if asym_col is not None:
            cols.append(asym_col)
        return np.column_stack(cols)

    positions = np.concatenate([readings.tx, readings.rx])
    extent = float(np.hypot(*np.ptp(positions, axis=0)))
    hi = min(DC_MAX, max(4.0 * extent, 2 * DC_MIN))
    grid = np.geomspace(DC_MIN, hi, 24)

    def search(weight: FloatArray, grid: FloatArray) -> tuple[float, FloatArray]:
        errors = [_nnls(columns(float(dc)), target, weight)[1] for dc in grid]
        best = int(np.argmin(errors))
        lo_b, hi_b = grid[max(best - 1, 0)], grid[min(best + 1, grid.size - 1)]
        refined = minimize_scalar(
            lambda v: _nnls(columns(float(np.exp(v))), target, weight)[1],
            bounds=(math.log(lo_b), math.log(hi_b)),
            method="bounded",
            options={"xatol": 1e-2},
        )
        dc = float(np.exp(refined.x)) if refined.fun <= errors[best] else float(grid[best])
        return dc, _nnls(columns(dc), target, weight)[0]

    # Lags beyond half the largest are left out (few, far apart places: the usual rule
    # of thumb for variograms), by a zero weight. A pilot fit with equal weights, then
    # weights 1/γ² (the variance of ½(r_i − r_j)² is 2γ² for Gaussian residuals): short
    # lags, where dc shows, count more (Cressie's weighting).
    delta = np.minimum(ends[0] + ends[3], ends[1] + ends[2]) / 2.0
    weight = (delta <= 0.5 * float(delta.max())).astype(np.float64)
    dc, theta = search(weight, grid)
    gamma = columns(dc) @ theta
    floor = max(float(np.mean(gamma)) * 1e-2, 1e-6)
    weight = weight / np.maximum(gamma, floor) ** 2
    dc, theta = search(weight, grid)
    sigma = math.sqrt(float(theta[0]))
    decorrelation = Estimate(dc, base.decorrelation_m)
    if sigma < MIN_SIGMA_FOR_DC:
        notes.append(
            f"no spatially correlated shadowing found (σ = {sigma:.2f} dB): the "
            f"decorrelation distance is not identifiable, kept the base profile's "
            f"{base.decorrelation_m:g} m"
        )
        decorrelation = Estimate(base.decorrelation_m, base.decorrelation_m, None, "kept")
    elif dc >= extent:
        # σ and dc trade off when the field does not decorrelate over the readings: σ
        # refitted with dc fixed at the base's, so that the profile is consistent.
        dc = base.decorrelation_m
        theta = _nnls(columns(dc), target, weight)[0]
        notes.append(
            f"the shadowing does not decorrelate within the readings' extent "
            f"({extent:.1f} m; best fit {decorrelation.value:.0f} m): the decorrelation "
            f"distance is not identifiable, kept the base profile's {dc:g} m and fitted "
            "σ with it"
        )
        decorrelation = Estimate(dc, dc, None, "kept")
    elif dc <= grid[1]:
        notes.append(
            "the shadowing decorrelates within the closest reading pairs: decorrelation "
            f"≤ {grid[1]:.2f} m"
        )
        decorrelation = Estimate(dc, base.decorrelation_m, None, "clipped")
    sigma2, tau2 = float(theta[0]), float(theta[1])
    estimates = {
        "sigma": Estimate(math.sqrt(sigma2), base.shadowing_sigma_db),
        "decorrelation": decorrelation,
    }
    if reciprocal is not None:
        asym2 = reciprocal[0] ** 2
        estimates["asymmetry"] = Estimate(reciprocal[0], base.asymmetry_db)
        notes.append(
            f"asymmetry from {reciprocal[1]} robot pairs read both ways at the same moments"
        )
    elif links:
        asym2 = float(theta[2])
        estimates["asymmetry"] = Estimate(math.sqrt(asym2), base.asymmetry_db)
    else:
        asym2 = 0.0
        notes.append(
            "the readings do not say which robot pair each came from: the asymmetry is "
            f"kept at the base profile's {base.asymmetry_db:g} dB (the nugget includes it)"
        )
        estimates["asymmetry"] = Estimate(base.asymmetry_db, base.asymmetry_db, None, "kept")
    counts = np.unique(readings.group, return_counts=True)[1]
    within = int(np.sum(counts * (counts - 1) // 2))
    if i.size < within:
        notes.append(
            f"shadowing fitted on a seeded sample of {i.size} of the {within} pairs of "
            "readings of the same run"
        )
    model = _Covariance(sigma2, dc, asym2, tau2, links)
    gram = _variogram(readings, residual, i, j, ends, model)
    return model, estimates, math.sqrt(tau2), gram


def _variogram(
    r: Readings,
    residual: FloatArray,
    i: IntArray,
    j: IntArray,
    ends: FloatArray,
    c: _Covariance,
) -> list[dict[str, float]]:
    """The semivariogram ½(r_i − r_j)² of reading pairs binned by the mean distance
    between their matched ends (the closer of the two ways of matching them): measured,
    and as the fitted covariance gives it (dB²)."""
    delta = np.minimum(ends[0] + ends[3], ends[1] + ends[2]) / 2.0
    var = c.variance(r)
    fitted = 0.5 * (var[i] + var[j]) - c.pair(r, i, j, ends)
    measured = 0.5 * (residual[i] - residual[j]) ** 2
    out: list[dict[str, float]] = []
    edges = VARIOGRAM_EDGES
    for lo, hi in itertools.pairwise(edges):
        mask = (delta >= lo) & (delta < hi)
        count = int(np.count_nonzero(mask))
        if count < VARIOGRAM_MIN_PAIRS:
            continue
        out.append(
            {
                "delta_m": _round(float(np.mean(delta[mask])), 2),
                "pairs": count,
                "measured_db2": _round(float(np.mean(measured[mask])), 2),
                "fitted_db2": _round(float(np.mean(fitted[mask])), 2),
            }
        )
    return out


def _meat(design: FloatArray, r: Readings, c: _Covariance, seed: int) -> FloatArray:
    """XᵀΣX with Σ the fitted covariance: readings of different groups are independent;
    within a group exact up to :data:`MEAT_EXACT` readings, beyond an unbiased estimate
    from a seeded subset of that many."""
    p = design.shape[1]
    out = np.zeros((p, p))
    var = c.variance(r)
    rng = np.random.default_rng(seed + 1)
    for g in np.unique(r.group).tolist():
        members = np.flatnonzero(r.group == g)
        size = members.size
        out += (design[members] * var[members, None]).T @ design[members]
        subset = members
        if size > MEAT_EXACT:
            subset = np.sort(rng.choice(members, MEAT_EXACT, replace=False))
        m = subset.size
        tx, rx, x = r.tx[subset], r.rx[subset], design[subset]
        pair, direction = r.pair[subset], r.direction[subset].astype(np.float64)
        off = np.zeros((p, p))
        for start in range(0, m, 512):
            rows = slice(start, min(start + 512, m))
            kernel = np.exp(-cdist(tx[rows], tx) / c.dc)
            kernel += np.exp(-cdist(tx[rows], rx) / c.dc)
            kernel += np.exp(-cdist(rx[rows], tx) / c.dc)
            kernel += np.exp(-cdist(rx[rows], rx) / c.dc)
            block = 0.5 * c.sigma2 * kernel
            if c.links:
                same = pair[rows, None] == pair[None, :]
                block += c.asym2 * same * np.outer(direction[rows], direction)
            count = rows.stop - start
            block[np.arange(count), start + np.arange(count)] = 0.0  # i == j: added above
            off += x[rows].T @ block @ x
        if m < size:
            off *= size * (size - 1) / (m * (m - 1))
        out += off
    return out


# -- writing ---------------------------------------------------------------------------


def profile_yaml(profile: RadioProfile, header: Sequence[str] = ()) -> str:
    """A profile as YAML that :func:`~mrcomm.net.radio.profile.load_profile` reads."""
    comments = "".join(f"# {line}\n" if line else "#\n" for line in header)
    body = yaml.safe_dump(profile.model_dump(), sort_keys=False, width=1 << 16)
    return comments + body


def write_profile(path: str | Path, profile: RadioProfile, header: Sequence[str] = ()) -> None:
    """Write a profile atomically (temporary file + rename)."""
    atomic_write_text(path, profile_yaml(profile, header))
