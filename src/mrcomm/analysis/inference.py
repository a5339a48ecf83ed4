"""Inference helpers of the study statistics: the smallest p a design can reach,
corrections of p for multiple comparisons (Holm, Benjamini–Hochberg), and percentile
bootstrap confidence intervals (also of the effect size r = Z/√(m+n), vectorised).

Bootstrap intervals use ``BOOTSTRAP_RESAMPLES`` resamples drawn with a fixed seed
(``BOOTSTRAP_SEED``), so the same data always give the same interval.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, Literal, cast

import numpy as np
from scipy import stats as sps

from mrcomm.errors import InputError

#: Resamples and seed of every bootstrap confidence interval (percentile method).
BOOTSTRAP_RESAMPLES = 2000
BOOTSTRAP_SEED = 0
CONFIDENCE = 0.95
#: How p-values are corrected across the comparisons of one table.
CORRECTIONS = ("holm", "bh", "none")
Correction = Literal["holm", "bh", "none"]


def min_attainable_p(m: int, n: int) -> float:
    """The smallest one-sided p any data can give with samples of m and n runs: the
    most extreme split has probability 1/C(m+n, m) under H0 (ties only make it
    larger). With 3 runs per group this is 1/20 = 0.05, so nothing can reach α = 0.05."""
    if m < 1 or n < 1:
        return math.nan
    return 1.0 / math.comb(m + n, m)


def check_correction(name: str) -> Correction:
    """``name`` as a correction method, or an input error naming the choices."""
    if name not in CORRECTIONS:
        raise InputError(
            f"unknown correction {name!r}; choose {', '.join(CORRECTIONS)}", field="--correction"
        )
    return cast(Correction, name)


def adjust_p(p: Sequence[float], method: Correction = "holm") -> np.ndarray:
    """p-values corrected for multiple comparisons (NaNs stay NaN and are not counted).

    Holm: sort ascending, p_(i)·(k − i + 1) for i = 1..k, made non-decreasing, capped
    at 1 (controls the family-wise error rate). Benjamini–Hochberg ("bh"): p_(i)·k/i,
    made non-increasing from the largest down, capped at 1 (controls the false
    discovery rate)."""
    check_correction(method)
    values = np.asarray(p, dtype=float)
    out = np.full(values.shape, np.nan)
    finite = np.flatnonzero(np.isfinite(values))
    k = len(finite)
    if k == 0 or method == "none":
        out[finite] = values[finite]
        return out
    order = finite[np.argsort(values[finite], kind="stable")]
    ranked = values[order]
    i = np.arange(1, k + 1)
    if method == "holm":
        adjusted = np.maximum.accumulate(ranked * (k - i + 1))
    else:
        adjusted = np.minimum.accumulate((ranked * k / i)[::-1])[::-1]
    out[order] = np.minimum(adjusted, 1.0)
    return out


def r_batch(x: np.ndarray, y: np.ndarray, axis: int = -1) -> np.ndarray:
    """The conventional r = Z/√(m+n) of samples along ``axis`` (vectorised, for the
    bootstrap): U counted pair by pair, σ_U tie-corrected; r = 0 where every value ties."""
    x = np.moveaxis(np.asarray(x, dtype=float), axis, -1)
    y = np.moveaxis(np.asarray(y, dtype=float), axis, -1)
    m, n = x.shape[-1], y.shape[-1]
    big_n = m + n
    diff = x[..., :, None] - y[..., None, :]
    u = np.sum(diff > 0, axis=(-2, -1)) + 0.5 * np.sum(diff == 0, axis=(-2, -1))
    pooled = np.concatenate([x, y], axis=-1)
    # Σ(t³ − t) over tie groups = Σ_i c_i² − N, c_i the number of values equal to value i.
    equal = np.sum(pooled[..., :, None] == pooled[..., None, :], axis=-1)
    ties = np.sum(equal.astype(float) ** 2, axis=-1) - big_n
    var = m * n / 12.0 * ((big_n + 1) - ties / (big_n * (big_n - 1)))
    sigma = np.sqrt(np.maximum(var, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(sigma > 0, (u - m * n / 2.0) / sigma, 0.0)
    return np.asarray(z / math.sqrt(big_n))


def bootstrap_ci(
    samples: Sequence[np.ndarray], statistic: Any, confidence: float = CONFIDENCE
) -> tuple[float, float]:
    """Percentile bootstrap interval of ``statistic(*samples, axis=-1)``, each sample
    resampled independently, seeded (the same data give the same interval); NaN when a
    sample has fewer than two values."""
    if any(len(s) < 2 for s in samples):
        return math.nan, math.nan
    res = sps.bootstrap(
        tuple(samples),
        statistic,
        n_resamples=BOOTSTRAP_RESAMPLES,
        confidence_level=confidence,
        method="percentile",
        vectorized=True,
        rng=np.random.default_rng(BOOTSTRAP_SEED),
    )
    low, high = res.confidence_interval
    return float(low), float(high)
