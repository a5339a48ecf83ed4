"""Statistics between behaviours: do the behaviours of a study differ, and which from
which, under the same conditions.

Per metric and per condition — scenario, network, threshold, SPL level and setting (the
variant parameters other than the behaviour's, :mod:`mrcomm.analysis.settings`) — with
two or more behaviours (a behaviour with its own parameters, ``lf[utility=greedy]``, is
a behaviour of its own here):

* **Kruskal–Wallis** across the behaviours: H (tie-corrected), its degrees of freedom
  (behaviours − 1), p, and the effect size ε² = H / (N − 1) (N: runs in the condition;
  0 none, 1 every run of a behaviour ranked apart from every other); p corrected across
  every condition and metric of the table (Holm by default);
* **pairwise Mann–Whitney** between every two behaviours, two-sided (the same exact /
  permutation / normal-approximation choice as the SPL tables,
  :func:`mrcomm.analysis.stats.mann_whitney`), with the effect size r = Z/√(m+n) of the
  first behaviour against the second and its bootstrap 95 % interval (seeded);
  p corrected with Holm's method within the family of one metric and condition (its
  k(k−1)/2 pairs), the usual post-hoc family after an omnibus test.

A behaviour that ignores the threshold (NB) runs the same under every threshold; a
study records it under one threshold only (NB × SSD is excluded as a repeat of NB ×
SLT), so its runs join the conditions of every threshold.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import asdict

import numpy as np
import pandas as pd
from scipy import stats as sps

from mrcomm.analysis.inference import Correction, adjust_p
from mrcomm.analysis.stats import (
    ALPHA,
    NOT_REJECTED,
    SUPPORTED,
    mann_whitney,
    resolve_metrics,
    usable_runs,
)
from mrcomm.errors import InputError

#: The conditions under which behaviours are compared.
CONDITION = ("scenario", "network", "threshold", "spl", "setting")


def _ignores_threshold(behaviour: str) -> bool:
    """Whether a behaviour (``name`` or ``name[params]``) ignores the threshold, by its
    spec; unknown behaviours (a plugin not installed here) are taken to use it."""
    from mrcomm.specs import get_spec

    try:
        return not get_spec("behaviour", behaviour.split("[", 1)[0]).uses_threshold
    except InputError:
        return False


def _with_shared_baselines(runs: pd.DataFrame) -> pd.DataFrame:
    """The runs, with those of threshold-blind behaviours repeated under every other
    threshold of the study that they were not run under."""
    thresholds = sorted(runs["threshold"].dropna().unique())
    extra = []
    for behaviour, frame in runs.groupby("behaviour", sort=True):
        if not _ignores_threshold(str(behaviour)):
            continue
        own = sorted(frame["threshold"].dropna().unique())
        if not own:
            continue
        source = frame[frame["threshold"] == own[0]]
        for threshold in thresholds:
            if threshold not in own:
                extra.append(source.assign(threshold=threshold))
    return pd.concat([runs, *extra], ignore_index=True) if extra else runs


def _samples(frame: pd.DataFrame, column: str) -> dict[str, np.ndarray]:
    out = {}
    for behaviour, rows in frame.groupby("behaviour", sort=True):
        values = pd.to_numeric(rows[column], errors="coerce").to_numpy(dtype=float)
        values = values[np.isfinite(values)]
        if len(values):
            out[str(behaviour)] = values
    return out


def _conditions(runs: pd.DataFrame) -> list[tuple[tuple[object, ...], pd.DataFrame]]:
    return [
        (key if isinstance(key, tuple) else (key,), frame)
        for key, frame in runs.groupby(list(CONDITION), sort=True, dropna=False)
    ]


def kruskal_table(
    runs: pd.DataFrame,
    metrics: Sequence[str] | None = None,
    alpha: float = ALPHA,
    correction: Correction = "holm",
) -> pd.DataFrame:
    """Kruskal–Wallis across behaviours, one row per (metric, condition) with 2+
    behaviours; p corrected across the table."""
    runs = _with_shared_baselines(usable_runs(runs))
    rows = []
    for metric in resolve_metrics(metrics):
        if metric.name not in runs.columns:
            continue
        for key, frame in _conditions(runs):
            samples = _samples(frame, metric.name)
            if len(samples) < 2:
                continue
            values = list(samples.values())
            total = sum(len(v) for v in values)
            pooled = np.concatenate(values)
            if np.ptp(pooled) == 0.0:
                h, p = 0.0, 1.0  # every run equal: no difference to find
            else:
                res = sps.kruskal(*values)
                h, p = float(res.statistic), float(res.pvalue)
            rows.append(
                {
                    "metric": metric.name,
                    **dict(zip(CONDITION, key, strict=True)),
                    "behaviours": ", ".join(samples),
                    "n": total,
                    "medians": ", ".join(f"{np.median(v):.4g}" for v in values),
                    "h": h,
                    "df": len(values) - 1,
                    "p": p,
                    "epsilon2": h / (total - 1) if total > 1 else math.nan,
                }
            )
    table = pd.DataFrame(rows, columns=_KRUSKAL_COLUMNS[:-3])
    table["correction"] = correction
    table["p_adj"] = adjust_p(table["p"].to_numpy(dtype=float), correction)
    table["decision"] = [_decision(p, alpha) for p in table["p_adj"]]
    return table[_KRUSKAL_COLUMNS]


_KRUSKAL_COLUMNS = [
    "metric",
    *CONDITION,
    *("behaviours", "n", "medians", "h", "df", "p", "epsilon2"),
    *("correction", "p_adj", "decision"),
]


def pairwise_table(
    runs: pd.DataFrame,
    metrics: Sequence[str] | None = None,
    alpha: float = ALPHA,
) -> pd.DataFrame:
    """Two-sided Mann–Whitney between every two behaviours of a condition; p corrected
    with Holm within each (metric, condition) family of pairs."""
    runs = _with_shared_baselines(usable_runs(runs))
    rows = []
    for metric in resolve_metrics(metrics):
        if metric.name not in runs.columns:
            continue
        for key, frame in _conditions(runs):
            samples = _samples(frame, metric.name)
            pairs = list(itertools.combinations(sorted(samples), 2))
            family = []
            for a, b in pairs:
                res = mann_whitney(samples[a], samples[b], "two-sided")
                row = {
                    "metric": metric.name,
                    **dict(zip(CONDITION, key, strict=True)),
                    "behaviour_a": a,
                    "behaviour_b": b,
                    "median_a": float(np.median(samples[a])),
                    "median_b": float(np.median(samples[b])),
                    **asdict(res),
                }
                row["direction"] = (
                    f"{a} lower" if res.z < 0 else f"{a} higher" if res.z > 0 else "none"
                )
                family.append(row)
            adjusted = adjust_p([r["p"] for r in family], "holm")
            for row, p_adj in zip(family, adjusted, strict=True):
                row["p_adj"] = float(p_adj)
                row["decision"] = _decision(float(p_adj), alpha)
                rows.append(row)
    return pd.DataFrame(rows, columns=_PAIRWISE_COLUMNS)


_PAIRWISE_COLUMNS = [
    "metric",
    *CONDITION,
    *("behaviour_a", "behaviour_b", "median_a", "median_b", "m", "n", "u", "p", "z"),
    *("r", "r_low", "r_high", "effect", "direction", "min_p", "method", "p_adj", "decision"),
]


def _decision(p: float, alpha: float) -> str:
    if not math.isfinite(p):
        return "n/a"
    return SUPPORTED if p < alpha else NOT_REJECTED
