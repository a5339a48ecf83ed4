"""Statistics of a study: every SPLX compared with the ideal case SPL0.

Per metric and per configuration group (scenario, network, threshold, behaviour with its
own parameters, and the other variant parameters: :mod:`mrcomm.analysis.settings`):

* Mann–Whitney U, one-sided (H_A "SPL0 < SPLX"; "SPL0 > SPLX" for near collisions),
  with U reported for the SPL0 sample, p, Z, the conventional effect size
  r = Z/√(m+n) (in [−1, 1]; it leads, with Cohen's label), the original study's
  r = Z/√n (n per group; it can exceed 1, so it is shown only as a labelled second
  column), the direction of the observed effect, a bootstrap confidence interval of r,
  the smallest p the design can reach, p corrected across the comparisons of the table
  (Holm by default, or Benjamini–Hochberg) and the decision at α on the corrected p:
  "H_A supported" or "H0 not rejected" (never "accepted");
* Shapiro–Wilk W and p per sample;
* successful-mission contingency tables with chi-squared (and Fisher's exact test for
  the 2×2 SPL0-vs-SPLX tables).

Choice of p-value method (:func:`mann_whitney`): the exact null distribution of U when a
sample has at most 8 observations and there are no ties; the exact *permutation*
distribution (every split of the pooled sample enumerated, so ties are handled
exactly) when there are ties and at most ``EXACT_PERMUTATIONS`` splits exist (n = 5
per group: 252); otherwise the normal approximation with tie and continuity correction.

Z (for the effect sizes) is ``(U − mn/2) / σ_U`` without continuity correction, with the
tie-corrected σ_U = √(mn/12 · ((N+1) − Σ(t³−t)/(N(N−1)))), N = m+n, t the size of each
group of tied values; without ties this is the textbook √(mn(m+n+1)/12).

The corrections of p, the minimum attainable p and the bootstrap intervals are in
:mod:`mrcomm.analysis.inference`.

Everything works on the ``runs`` DataFrame of the results database contract.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, fields
from typing import Literal

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike
from scipy import stats as sps

from mrcomm.analysis.inference import (
    Correction,
    adjust_p,
    bootstrap_ci,
    min_attainable_p,
    r_batch,
)
from mrcomm.errors import InputError, did_you_mean

ALPHA = 0.05
#: Group keys of a configuration without its packet-loss level (``setting``: the
#: variant parameters other than the behaviour's, :mod:`mrcomm.analysis.settings`).
GROUP = ("scenario", "network", "threshold", "behaviour", "setting")
#: Largest number of distinct splits enumerated for an exact test with ties.
EXACT_PERMUTATIONS = 200_000
Alternative = Literal["less", "greater", "two-sided"]
SUPPORTED = "H_A supported"
NOT_REJECTED = "H0 not rejected"


@dataclass(frozen=True)
class Metric:
    """A per-run metric (a column of the runs frame) and the direction of its test."""

    name: str
    label: str
    unit: str
    #: H_A of SPL0 against SPLX: "less" = SPL0 observations are less than SPLX ones.
    alternative: Alternative = "less"


_M = Metric
#: The metrics of every run, whatever its behaviour.
_RUN_METRICS = (
    _M("execution_phase_time", "Execution phase time", "s"),
    _M("total_movement_time", "Total movement time", "s"),
    _M("total_distance", "Total distance travelled", "m"),
    _M("near_collisions", "Near collisions", "count", "greater"),
    _M("near_collisions_filtered", "Near collisions (filtered)", "count", "greater"),
    _M("near_collisions_confirmed", "Near collisions (confirmed)", "count", "greater"),
    _M("near_collisions_false", "Near collisions (false alarms)", "count"),
    _M("near_collisions_missed", "Near collisions (missed)", "count"),
    _M("delay_time", "Delay time", "s"),
    _M("idle_time", "Idle time", "s"),
    _M("task_execution_time", "Task execution time", "s"),
    _M("n_failed_tasks", "Failed tasks", "count"),
    _M("min_separation", "Minimum separation", "m"),
    _M("max_separation", "Maximum separation", "m"),
    _M("tasks_per_minute", "Tasks per minute", "tasks/min", "greater"),
    _M("assigner_connected", "Time connected to the assigner", "fraction", "greater"),
    _M("largest_group_mean", "Largest connected group (mean)", "fraction", "greater"),
    _M("largest_group_min", "Largest connected group (min)", "fraction", "greater"),
)
#: The metrics of runs whose statuses go with AON.
_AON_METRICS = (
    _M("aon_publications", "AON publications", "count"),
    _M("aon_resends", "AON re-sends", "count"),
)


def all_metrics() -> dict[str, Metric]:
    """Every metric by name: those of every run, the team metrics each registered
    behaviour declares in its spec (plugins' too: ``VariantSpec.team_metrics``), and
    AON's."""
    from mrcomm.specs import REGISTRY

    found = {m.name: m for m in _RUN_METRICS}
    for spec in REGISTRY.all():
        for t in spec.team_metrics:
            found.setdefault(t.name, Metric(t.name, t.label, t.unit, t.alternative))
    found.update({m.name: m for m in _AON_METRICS})
    return found


def metric_info(name: str) -> Metric:
    """The metric called ``name`` (KeyError for none)."""
    return all_metrics()[name]


#: The core metrics of the original study: the default Q–Q plots.
CORE_METRICS = (
    "execution_phase_time",
    "total_movement_time",
    "total_distance",
    "near_collisions",
    "delay_time",
    "idle_time",
)


def resolve_metrics(names: Sequence[str] | None, field: str = "--metric") -> list[Metric]:
    """The metrics named (all when ``names`` is empty); unknown names are input errors."""
    known = all_metrics()
    if not names:
        return list(known.values())
    out = []
    for name in names:
        if name not in known:
            hint = did_you_mean(name, known)
            raise InputError(
                f"unknown metric {name!r}{hint}; known: {', '.join(known)}", field=field
            )
        out.append(known[name])
    return out


def effect_label(r: float) -> str:
    """Cohen's label of |r| (for the conventional r = Z/√(m+n)): < 0.1 negligible,
    [0.1, 0.3) weak, [0.3, 0.5] medium, > 0.5 strong."""
    if not math.isfinite(r):
        return "n/a"
    a = abs(r)
    if a < 0.1:
        return "negligible"
    if a < 0.3:
        return "weak"
    if a <= 0.5:
        return "medium"
    return "strong"


def sigma_u(x: ArrayLike, y: ArrayLike) -> float:
    """Tie-corrected standard deviation of U under H0 (see the module docstring)."""
    a, b = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    m, n = len(a), len(b)
    big_n = m + n
    if m == 0 or n == 0:
        return math.nan
    _, counts = np.unique(np.concatenate([a, b]), return_counts=True)
    ties = float(np.sum(counts.astype(float) ** 3 - counts))
    var = m * n / 12.0 * ((big_n + 1) - ties / (big_n * (big_n - 1)))
    return math.sqrt(max(var, 0.0))


@dataclass(frozen=True)
class MannWhitney:
    """One SPL0-vs-SPLX comparison."""

    m: int  # size of the SPL0 sample
    n: int  # size of the SPLX sample
    alternative: str
    u: float  # U of the SPL0 sample (number of pairs with SPL0 > SPLX, ties count 1/2)
    p: float  # uncorrected
    z: float  # (U − mn/2) / σ_U, tie-corrected, no continuity correction
    r: float  # the conventional effect size Z / √(m+n), in [−1, 1]
    r_low: float  # bootstrap confidence interval of r
    r_high: float
    r_original: float  # the original study's Z / √n (n: per-group sample size); may exceed 1
    effect: str  # Cohen's label of |r|
    direction: str  # observed effect: "SPL0 lower", "SPL0 higher" or "none"
    min_p: float  # the smallest p this design can give
    method: str  # how p was computed


def mann_whitney(
    spl0: ArrayLike,
    splx: ArrayLike,
    alternative: Alternative = "less",
) -> MannWhitney:
    """One-sided Mann–Whitney U of SPL0 against SPLX (NaNs dropped).

    The per-group sample size of the original's r = Z/√n is the size of the smaller
    sample (the groups are equal in a balanced design; they differ only when a metric is
    undefined in some runs).
    """
    x = np.asarray(spl0, dtype=float)
    y = np.asarray(splx, dtype=float)
    x, y = x[np.isfinite(x)], y[np.isfinite(y)]
    m, n = len(x), len(y)
    nan = math.nan
    if m < 2 or n < 2:
        return MannWhitney(
            m, n, alternative, nan, nan, nan, nan, nan, nan, nan, "n/a", "n/a", nan, "too few"
        )
    min_p = min_attainable_p(m, n)
    sigma = sigma_u(x, y)
    if sigma == 0.0:
        # Every observation equal: no evidence either way, U sits at its mean.
        u = m * n / 2.0
        return MannWhitney(
            m,
            n,
            alternative,
            u,
            1.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            "negligible",
            "none",
            min_p,
            "degenerate (all equal)",
        )
    has_ties = len(np.unique(np.concatenate([x, y]))) < m + n
    method: str | sps.PermutationMethod
    if not has_ties and min(m, n) <= 8:
        method, label = "exact", "exact"
    elif has_ties and math.comb(m + n, m) <= EXACT_PERMUTATIONS:
        # n_resamples >= the number of distinct splits makes permutation_test enumerate
        # them all: an exact test conditional on the ties. The generator is unused then.
        method = sps.PermutationMethod(n_resamples=EXACT_PERMUTATIONS, rng=np.random.default_rng(0))
        label = "exact permutation (ties)"
    else:
        method, label = "asymptotic", "normal approx. (tie + continuity corr.)"
    res = sps.mannwhitneyu(x, y, alternative=alternative, method=method)
    u = float(res.statistic)  # scipy's statistic is U of the first sample (SPL0)
    z = (u - m * n / 2.0) / sigma
    r = z / math.sqrt(m + n)
    r_low, r_high = bootstrap_ci((x, y), r_batch)
    return MannWhitney(
        m=m,
        n=n,
        alternative=alternative,
        u=u,
        p=float(res.pvalue),
        z=z,
        r=r,
        r_low=r_low,
        r_high=r_high,
        r_original=z / math.sqrt(min(m, n)),
        effect=effect_label(r),
        direction="SPL0 lower" if z < 0 else "SPL0 higher" if z > 0 else "none",
        min_p=min_p,
        method=label,
    )


def shapiro_wilk(sample: ArrayLike) -> tuple[float, float]:
    """Shapiro–Wilk (W, p); NaN when undefined (fewer than 3 values, or all equal)."""
    x = np.asarray(sample, dtype=float)
    x = x[np.isfinite(x)]
    if len(x) < 3 or np.ptp(x) == 0.0:
        return math.nan, math.nan
    res = sps.shapiro(x)
    return float(res.statistic), float(res.pvalue)


def usable_runs(runs: pd.DataFrame) -> pd.DataFrame:
    """Runs that finished (status 'ok'): the ones every statistic is computed over,
    with every :data:`GROUP` column (a missing ``setting``: "")."""
    if "setting" not in runs.columns:
        runs = runs.assign(setting="")
    if "status" not in runs.columns:
        return runs
    return runs[runs["status"] == "ok"]


def _groups(runs: pd.DataFrame) -> list[tuple[tuple[str, ...], pd.DataFrame]]:
    keys = list(GROUP)
    out = []
    for key, frame in runs.groupby(keys, sort=True, dropna=False):
        out.append((tuple(str(k) for k in key), frame))
    return out


def _sample(frame: pd.DataFrame, spl: float, column: str) -> np.ndarray:
    values = pd.to_numeric(frame.loc[frame["spl"] == spl, column], errors="coerce")
    arr = values.to_numpy(dtype=float, na_value=np.nan)
    return arr[np.isfinite(arr)]


def _spl_name(spl: float) -> str:
    return f"SPL{spl:g}"


def comparison_table(
    runs: pd.DataFrame,
    metrics: Sequence[str] | None = None,
    alpha: float = ALPHA,
    correction: Correction = "holm",
) -> pd.DataFrame:
    """Mann–Whitney SPL0 vs each SPLX, one row per (metric, group, SPLX); p corrected
    across every row of the table (``correction``), the decision taken on the corrected
    p, and whether the design can reach α at all (``reachable``: min_p < α)."""
    rows = []
    runs = usable_runs(runs)
    for metric in resolve_metrics(metrics):
        if metric.name not in runs.columns:
            continue
        for key, frame in _groups(runs):
            levels = sorted(frame["spl"].dropna().unique())
            if 0.0 not in levels:
                continue
            x = _sample(frame, 0.0, metric.name)
            for spl in levels:
                if spl == 0.0:
                    continue
                y = _sample(frame, spl, metric.name)
                if len(x) == 0 and len(y) == 0:
                    continue  # metric undefined for this group (LF metric of NB runs)
                res = mann_whitney(x, y, metric.alternative)
                op = "<" if metric.alternative == "less" else ">"
                rows.append(
                    {
                        "metric": metric.name,
                        **dict(zip(GROUP, key, strict=False)),
                        "spl_x": float(spl),
                        "hypothesis": f"SPL0 {op} {_spl_name(spl)}",
                        "median0": _median(x),
                        "iqr0": _iqr(x),
                        "median_x": _median(y),
                        "iqr_x": _iqr(y),
                        "mean0": _mean(x),
                        "sd0": _sd(x),
                        "mean_x": _mean(y),
                        "sd_x": _sd(y),
                        **asdict(res),
                    }
                )
    table = pd.DataFrame(rows, columns=_COMPARISON_COLUMNS[:-4])
    table["correction"] = correction
    table["p_adj"] = adjust_p(table["p"].to_numpy(dtype=float), correction)
    table["reachable"] = table["min_p"] < alpha
    table["decision"] = [
        "n/a" if not math.isfinite(p) else SUPPORTED if p < alpha else NOT_REJECTED
        for p in table["p_adj"]
    ]
    return table[_COMPARISON_COLUMNS]


_COMPARISON_COLUMNS = [
    "metric",
    *GROUP,
    *("spl_x", "hypothesis", "median0", "iqr0", "median_x", "iqr_x"),
    *("mean0", "sd0", "mean_x", "sd_x"),
    *(f.name for f in fields(MannWhitney)),
    *("correction", "p_adj", "reachable", "decision"),
]


def unreachable(comparisons: pd.DataFrame, alpha: float = ALPHA) -> list[str]:
    """One warning per distinct design (m, n) of the table that cannot reach α: its
    smallest attainable p is not below α, so no comparison of that size can be
    significant whatever the data."""
    if comparisons.empty:
        return []
    bad = comparisons[~comparisons["reachable"].astype(bool) & comparisons["min_p"].notna()]
    out = []
    for (m, n), frame in bad.groupby(["m", "n"], sort=True):
        out.append(
            f"{len(frame)} comparison(s) with {m} vs {n} runs cannot be significant: the "
            f"smallest attainable one-sided p is {frame['min_p'].iloc[0]:.4g} ≥ α = {alpha:g}; "
            "run more repetitions"
        )
    return out


def _median(a: np.ndarray) -> float:
    return float(np.median(a)) if len(a) else math.nan


def _iqr(a: np.ndarray) -> float:
    if len(a) == 0:
        return math.nan
    q1, q3 = np.percentile(a, [25, 75])
    return float(q3 - q1)


def _mean(a: np.ndarray) -> float:
    return float(np.mean(a)) if len(a) else math.nan


def _sd(a: np.ndarray) -> float:
    # Sample standard deviation (ddof=1), as the error bars of the figures.
    return float(np.std(a, ddof=1)) if len(a) > 1 else math.nan


def normality_table(
    runs: pd.DataFrame, metrics: Sequence[str] | None = None, alpha: float = ALPHA
) -> pd.DataFrame:
    """Shapiro–Wilk per sample: one row per (metric, group, SPL level)."""
    rows = []
    runs = usable_runs(runs)
    for metric in resolve_metrics(metrics):
        if metric.name not in runs.columns:
            continue
        for key, frame in _groups(runs):
            for spl in sorted(frame["spl"].dropna().unique()):
                x = _sample(frame, spl, metric.name)
                if len(x) == 0:
                    continue
                w, p = shapiro_wilk(x)
                normal = "n/a" if not math.isfinite(p) else ("yes" if p >= alpha else "no")
                rows.append(
                    {
                        "metric": metric.name,
                        **dict(zip(GROUP, key, strict=False)),
                        "spl": float(spl),
                        "n": len(x),
                        "w": w,
                        "p": p,
                        "normal": normal,
                    }
                )
    return pd.DataFrame(rows, columns=["metric", *GROUP, "spl", "n", "w", "p", "normal"])


def describe_table(runs: pd.DataFrame, metrics: Sequence[str] | None = None) -> pd.DataFrame:
    """Mean, standard deviation, min, max and n per (metric, group, SPL level)."""
    rows = []
    runs = usable_runs(runs)
    for metric in resolve_metrics(metrics):
        if metric.name not in runs.columns:
            continue
        for key, frame in _groups(runs):
            for spl in sorted(frame["spl"].dropna().unique()):
                x = _sample(frame, spl, metric.name)
                if len(x) == 0:
                    continue
                mean_ci = bootstrap_ci((x,), np.mean)
                median_ci = bootstrap_ci((x,), np.median)
                rows.append(
                    {
                        "metric": metric.name,
                        **dict(zip(GROUP, key, strict=False)),
                        "spl": float(spl),
                        "n": len(x),
                        "mean": _mean(x),
                        "mean_low": mean_ci[0],
                        "mean_high": mean_ci[1],
                        "sd": _sd(x),
                        "min": float(np.min(x)),
                        "q1": float(np.percentile(x, 25)),
                        "median": _median(x),
                        "median_low": median_ci[0],
                        "median_high": median_ci[1],
                        "q3": float(np.percentile(x, 75)),
                        "max": float(np.max(x)),
                    }
                )
    cols = [
        *("metric", *GROUP, "spl", "n", "mean", "mean_low", "mean_high", "sd"),
        *("min", "q1", "median", "median_low", "median_high", "q3", "max"),
    ]
    return pd.DataFrame(rows, columns=cols)


def success_counts(runs: pd.DataFrame) -> pd.DataFrame:
    """Successful and failed missions per group and SPL level (the contingency tables)."""
    runs = usable_runs(runs)
    rows = []
    for key, frame in _groups(runs):
        for spl in sorted(frame["spl"].dropna().unique()):
            ok = frame.loc[frame["spl"] == spl, "successful"].dropna().astype(bool)
            rows.append(
                {
                    **dict(zip(GROUP, key, strict=False)),
                    "spl": float(spl),
                    "runs": len(ok),
                    "successful": int(ok.sum()),
                    "failed": int((~ok).sum()),
                    "percent": 100.0 * float(ok.mean()) if len(ok) else math.nan,
                }
            )
    return pd.DataFrame(rows, columns=[*GROUP, "spl", "runs", "successful", "failed", "percent"])


def chi_squared(table: np.ndarray) -> dict[str, float | int | str]:
    """Chi-squared test of a k×2 (successful, failed) table; Fisher's exact p for 2×2.

    Yates' continuity correction applies to 2×2 tables (scipy's default). A table with
    an empty column (every mission successful, or every one failed) has no test: p is
    NaN and the note says why.
    """
    table = np.asarray(table, dtype=float)
    out: dict[str, float | int | str] = {
        "chi2": math.nan,
        "dof": 0,
        "p": math.nan,
        "fisher_p": math.nan,
        "min_expected": math.nan,
        "note": "",
    }
    if table.shape[0] < 2:
        out["note"] = "one SPL level"
        return out
    cols = table.sum(axis=0)
    if np.any(cols == 0):
        out["note"] = "all successful" if cols[1] == 0 else "all failed"
        return out
    res = sps.chi2_contingency(table)
    out.update(
        chi2=float(res.statistic),
        dof=int(res.dof),
        p=float(res.pvalue),
        min_expected=float(np.min(res.expected_freq)),
    )
    if table.shape == (2, 2):
        out["fisher_p"] = float(sps.fisher_exact(table).pvalue)
    if float(out["min_expected"]) < 5:
        out["note"] = (
            "expected count < 5: prefer Fisher's exact p"
            if table.shape
            == (
                2,
                2,
            )
            else "expected count < 5: chi-squared approximate"
        )
    return out


def success_tests(runs: pd.DataFrame) -> pd.DataFrame:
    """Per group: chi-squared across all SPL levels, then SPL0 vs each SPLX (2×2)."""
    counts = success_counts(runs)
    rows = []
    if counts.empty:
        return pd.DataFrame(
            columns=[*GROUP, "comparison", "chi2", "dof", "p", "fisher_p", "min_expected", "note"]
        )
    for key, frame in counts.groupby(list(GROUP), sort=True):
        frame = frame.sort_values("spl")
        table = frame[["successful", "failed"]].to_numpy()
        base = dict(zip(GROUP, key, strict=False))
        rows.append({**base, "comparison": "all SPL levels", **chi_squared(table)})
        if 0.0 in set(frame["spl"]):
            first = frame[frame["spl"] == 0.0][["successful", "failed"]].to_numpy()
            for _, row in frame[frame["spl"] != 0.0].iterrows():
                pair = np.vstack([first, [[row["successful"], row["failed"]]]])
                rows.append(
                    {**base, "comparison": f"SPL0 vs {_spl_name(row['spl'])}", **chi_squared(pair)}
                )
    return pd.DataFrame(rows)
