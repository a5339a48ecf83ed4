"""SSD vs ESD: the signal two thresholds saw in otherwise equal configurations,
compared two-sided — are the simulated (SSD's predicted) RSSI readings close to the
measured (ESD's) ones?

Configurations that differ only in their threshold (same scenario, network, behaviour
and SPL) and both recorded RSSI are compared pairwise. The unit of analysis is the run:
the readings of one run are strongly autocorrelated (2 Hz, robots moving slowly), so
pooling them would overstate the evidence. Each run is summarised by

* the mean RSSI of all its robot-pair readings, and its 10th percentile (the weak
  links, which decide warnings);
* its RSSI at equal distance: the behaviours place robots differently under each
  threshold, so only at equal distance do the two signals compare like for like. The
  readings taken while the two robots were within a distance band (their distance
  from the trajectories) are each moved along one log-distance slope to the band's
  middle, and averaged: "at 6 m (4-8 m)". The slope (dB per decade of distance, at
  least 1 m) is the pooled within-run slope of all readings of both configurations,
  so that neither threshold's own curve decides it, a difference in level between
  them does not tilt it, and distances spread differently inside a band do not pass
  for a difference in signal.

Each summary is compared with a two-sided Mann–Whitney U (via
:func:`mrcomm.analysis.stats.mann_whitney`), the effect size r = Z/√(m+n) with its
bootstrap interval, and the Hodges–Lehmann shift (the median of all differences
a − b between the runs of the two configurations) with its bootstrap interval; p is
corrected across the table.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import asdict

import numpy as np
import pandas as pd

from mrcomm.analysis.inference import Correction, adjust_p, bootstrap_ci
from mrcomm.analysis.stats import ALPHA, NOT_REJECTED, mann_whitney, usable_runs

#: Distance bands (m) of the at-equal-distance comparisons: [low, high).
DISTANCE_BANDS: tuple[tuple[float, float], ...] = ((0.0, 4.0), (4.0, 8.0), (8.0, 16.0))
#: A band's mean is taken only from runs with at least this many readings in it.
MIN_READINGS = 5
#: Configurations compared: the same in everything but the threshold.
SAME = ("scenario", "network", "behaviour", "spl")
#: The decision when the two-sided test rejects H0 (the signals' distributions are equal).
DIFFER = "signals differ"
#: The measured signal is named first (a − b reads "measured minus predicted").
_ORDER = {"esd": 0, "ssd": 1}

COLUMNS = [
    *SAME,
    "threshold_a",
    "threshold_b",
    "statistic",
    "m",
    "n",
    "median_a",
    "median_b",
    "shift",
    "shift_low",
    "shift_high",
    "u",
    "z",
    "p",
    "p_adj",
    "r",
    "r_low",
    "r_high",
    "effect",
    "direction",
    "min_p",
    "method",
    "correction",
    "decision",
]
#: The columns of a row before the table's correction is applied.
_ROW_COLUMNS = [c for c in COLUMNS if c not in ("p_adj", "correction", "decision")]


def readings_with_distance(rssi: pd.DataFrame, trajectories: pd.DataFrame) -> pd.DataFrame:
    """The RSSI readings (run_id, t, src, dst, rssi) with the two robots' distance at
    each (their trajectory samples nearest in time, within 0.5 s; NaN without)."""
    out = rssi.copy()
    out["distance"] = math.nan
    if out.empty or trajectories.empty:
        return out
    poses = trajectories[["run_id", "robot", "t", "x", "y"]].sort_values("t")
    out = out.sort_values("t").reset_index(drop=True)
    ends = []
    for end in ("src", "dst"):
        located = pd.merge_asof(
            out[["run_id", "t", end]].rename(columns={end: "robot"}),
            poses,
            on="t",
            by=["run_id", "robot"],
            direction="nearest",
            tolerance=0.5,
        )
        ends.append(located[["x", "y"]].to_numpy(dtype=float))
    a, b = ends
    out["distance"] = np.hypot(a[:, 0] - b[:, 0], a[:, 1] - b[:, 1])
    return out


def common_slope(readings: pd.DataFrame) -> float:
    """dB per decade of distance: the pooled within-run slope of all ``readings``
    (each run's log-distances and RSSI centred on its own means, one least-squares
    slope through all), so that a difference between the runs' levels — what is
    compared — does not tilt it. 0 when no run's distance varies."""
    x = np.log10(np.maximum(readings["distance"].to_numpy(dtype=float), 1.0))
    y = readings["rssi"].to_numpy(dtype=float)
    keep = np.isfinite(x) & np.isfinite(y)
    runs = readings["run_id"].to_numpy()[keep]
    frame = pd.DataFrame({"run_id": runs, "x": x[keep], "y": y[keep]})
    centred = frame[["x", "y"]] - frame.groupby("run_id")[["x", "y"]].transform("mean")
    sxx = float((centred["x"] ** 2).sum())
    return float((centred["x"] * centred["y"]).sum()) / sxx if sxx > 0.0 else 0.0


def run_summaries(readings: pd.DataFrame, slope: float) -> pd.DataFrame:
    """Per run: the statistics compared (columns named as the table's ``statistic``);
    ``slope``: dB per decade of distance that moves a reading to its band's middle."""
    rows = []
    for run_id, frame in readings.groupby("run_id", sort=True):
        values = frame["rssi"].to_numpy(dtype=float)
        row: dict[str, object] = {
            "run_id": run_id,
            "mean": float(values.mean()),
            "10th percentile": float(np.percentile(values, 10)),
        }
        distance = frame["distance"].to_numpy(dtype=float)
        for low, high in DISTANCE_BANDS:
            inside = (distance >= low) & (distance < high)
            middle = (low + high) / 2.0
            # Each reading moved along the slope from where it was taken to the middle.
            moved = values[inside] + slope * (
                np.log10(middle) - np.log10(np.maximum(distance[inside], 1.0))
            )
            name = band_name(low, high)
            row[name] = float(moved.mean()) if len(moved) >= MIN_READINGS else math.nan
        rows.append(row)
    return pd.DataFrame(rows)


def band_name(low: float, high: float) -> str:
    return f"at {(low + high) / 2:g} m ({low:g}-{high:g} m)"


def statistics() -> list[str]:
    """The compared statistics, in table order."""
    return [
        "mean",
        "10th percentile",
        *(band_name(low, high) for low, high in DISTANCE_BANDS),
    ]


def hodges_lehmann(a: np.ndarray, b: np.ndarray, axis: int = -1) -> np.ndarray:
    """Median of all differences a_i − b_j along ``axis`` (vectorised, for the
    bootstrap)."""
    a = np.moveaxis(np.asarray(a, dtype=float), axis, -1)
    b = np.moveaxis(np.asarray(b, dtype=float), axis, -1)
    diff = a[..., :, None] - b[..., None, :]
    return np.asarray(np.median(diff.reshape(*diff.shape[:-2], -1), axis=-1))


def rssi_comparisons(
    runs: pd.DataFrame,
    rssi: pd.DataFrame,
    trajectories: pd.DataFrame,
    alpha: float = ALPHA,
    correction: Correction = "holm",
) -> pd.DataFrame:
    """The two-sided comparisons (see the module docstring); empty when no two
    configurations differing only in their threshold both recorded RSSI."""
    runs = usable_runs(runs)
    with_rssi = set(rssi["run_id"]) if not rssi.empty else set()
    runs = runs[runs["run_id"].isin(with_rssi)]
    rows: list[dict[str, object]] = []
    if runs.empty:
        return _finish(pd.DataFrame(rows, columns=_ROW_COLUMNS), alpha, correction)
    readings = readings_with_distance(rssi[rssi["run_id"].isin(set(runs["run_id"]))], trajectories)
    readings = readings.merge(runs[["run_id", "threshold", *SAME]], on="run_id")
    for key, in_group in readings.groupby(list(SAME), sort=True):
        group = run_summaries(in_group, common_slope(in_group)).merge(
            runs[["run_id", "threshold"]], on="run_id"
        )
        thresholds = sorted(group["threshold"].unique(), key=lambda t: (_ORDER.get(t, 2), t))
        for first, second in itertools.combinations(thresholds, 2):
            for statistic in statistics():
                a = _sample(group, first, statistic)
                b = _sample(group, second, statistic)
                if len(a) == 0 and len(b) == 0:
                    continue
                same = dict(zip(SAME, key, strict=True))
                rows.append(_compare(same, first, second, statistic, a, b))
    return _finish(pd.DataFrame(rows, columns=_ROW_COLUMNS), alpha, correction)


def _sample(group: pd.DataFrame, threshold: str, statistic: str) -> np.ndarray:
    values = group.loc[group["threshold"] == threshold, statistic].to_numpy(dtype=float)
    return values[np.isfinite(values)]


def _compare(
    key: dict[str, object], first: str, second: str, statistic: str, a: np.ndarray, b: np.ndarray
) -> dict[str, object]:
    test = mann_whitney(a, b, "two-sided")
    shift = float(hodges_lehmann(a, b)) if len(a) and len(b) else math.nan
    low, high = bootstrap_ci((a, b), hodges_lehmann)
    found = asdict(test)
    direction = "none"
    if math.isfinite(test.z) and test.z != 0.0:
        direction = f"{first.upper()} {'higher' if test.z > 0 else 'lower'}"
    return {
        **key,
        "threshold_a": first,
        "threshold_b": second,
        "statistic": statistic,
        "m": test.m,
        "n": test.n,
        "median_a": float(np.median(a)) if len(a) else math.nan,
        "median_b": float(np.median(b)) if len(b) else math.nan,
        "shift": shift,
        "shift_low": low,
        "shift_high": high,
        **{k: found[k] for k in ("u", "z", "p", "r", "r_low", "r_high", "effect", "min_p")},
        "direction": direction,
        "method": test.method,
    }


def _finish(table: pd.DataFrame, alpha: float, correction: Correction) -> pd.DataFrame:
    table["correction"] = correction
    table["p_adj"] = adjust_p(table["p"].to_numpy(dtype=float), correction)
    table["decision"] = [
        "n/a" if not math.isfinite(p) else DIFFER if p < alpha else NOT_REJECTED
        for p in table["p_adj"]
    ]
    return table[COLUMNS]


def compared_pairs(table: pd.DataFrame) -> Sequence[str]:
    """'ESD vs SSD'-style names of the threshold pairs compared."""
    pairs = table[["threshold_a", "threshold_b"]].drop_duplicates()
    return [f"{a.upper()} vs {b.upper()}" for a, b in pairs.itertuples(index=False)]
