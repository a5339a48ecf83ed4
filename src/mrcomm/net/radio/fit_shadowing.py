"""The shadowing part of a radio fit (:mod:`mrcomm.net.radio.fit`): σ, the
decorrelation distance, the nugget and the per-direction offset from the residuals'
pair-wise semivariogram under the link model, and the residual covariance the
intervals of the mean's parameters are computed with."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar, nnls
from scipy.spatial.distance import cdist

from mrcomm.errors import InputError
from mrcomm.net.radio.fit_data import Estimate, FloatArray, IntArray, Readings, rounded
from mrcomm.net.radio.profile import RadioProfile

#: Per group, the sandwich's middle term is exact up to this many readings.
MEAT_EXACT = 1200
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


def fit_covariance(
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
                "delta_m": rounded(float(np.mean(delta[mask])), 2),
                "pairs": count,
                "measured_db2": rounded(float(np.mean(measured[mask])), 2),
                "fitted_db2": rounded(float(np.mean(fitted[mask])), 2),
            }
        )
    return out


def meat(design: FloatArray, r: Readings, c: _Covariance, seed: int) -> FloatArray:
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
