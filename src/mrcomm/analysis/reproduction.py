"""The original study's results beside ours, each with a verdict.

The original's figures (``data/reproduction/zhivkov2020.yaml``: its Mann–Whitney tables,
its success counts and the statements of its text that carry numbers) are compared with
a study of the same design (``data/experiments/reproduction.yaml``: same configurations,
same number of runs). Every comparison gets one of three verdicts, by rules fixed here
before any number is looked at:

* **reproduced** — the same finding within the original's own sampling spread;
* **direction** — the effect points the same way, but its size or significance differs;
* **not reproduced** — otherwise.

Mann–Whitney rows are compared on the original's own statistic, computed from U for
both sides in the same way: one-sided normal approximation with continuity correction
and no tie correction (what the original's printed p values match), and its effect
size r = Z/√n with n one group's size (so |r| can exceed 1). The original's p and r
are derived from its printed U (they match the printed ones except where the thesis
copied cells: those rows are flagged). A row is *reproduced* when the same hypothesis is
supported at α = 0.05 and the two r differ by less than two samples of one effect
differ 95 % of the time (1.96·√(2/n): 0.51 for n = 30); *direction* when not, but
both r have the same sign.

The other rules are in :data:`CLAIM_RULES` (what each claim check computes and when
it passes).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from scipy import stats as sps

from mrcomm.errors import InputError

ALPHA = 0.05
REPRODUCED = "reproduced"
DIRECTION = "direction"
NOT_REPRODUCED = "not reproduced"
VERDICTS = (REPRODUCED, DIRECTION, NOT_REPRODUCED)
#: A figure the text calls "about" X is reproduced within this fraction of X.
ABOUT = 0.25

#: What each claim check computes, as the report states it.
CLAIM_RULES = {
    "means_within_sd": "reproduced when the largest and smallest mean over SPL differ by "
    "less than the pooled standard deviation; direction when by less than two",
    "all_successful": "reproduced when every run of every configuration succeeds with no "
    "failed task; direction when every configuration succeeds in at least 90 % of runs",
    "none_successful_except": "reproduced when at most 10 % of the runs of each configuration "
    "(but the exceptions) succeed; direction when at most half do",
    "some_failed_tasks": "reproduced when at least half the runs lose a status; direction "
    "when at least one does",
    "ratio_about": f"reproduced when the ratio of the means is within ±{ABOUT * 100:.0f} % of the "
    "stated one; direction when it is on the same side of 1",
    "ratio_above": "reproduced when the ratio of the means is above the stated one; "
    "direction when it is above 1",
    "mean_between": "reproduced when the mean (over the configurations named) is in the "
    f"stated range; direction when within ±{ABOUT * 100:.0f} % of it",
}


def original_path() -> Path:
    from mrcomm.bundled import data_file

    return data_file("reproduction/zhivkov2020.yaml")


def load_original(path: Path | None = None) -> dict[str, Any]:
    """The original's figures (the bundled file unless ``path``)."""
    from mrcomm.world.yamlfile import read_yaml

    data = read_yaml(path or original_path())
    for key in ("success", "claims", "mann_whitney"):
        if key not in data:
            raise InputError(f"missing '{key}'", file=path or original_path(), field=key)
    return data


# --- the original's statistic, from U ---------------------------------------------------


def thesis_p(u: float, m: int, n: int, alternative: str) -> float:
    """One-sided p of U (of the first sample) by the normal approximation with
    continuity correction, without tie correction — how the original's p were made."""
    mean = m * n / 2.0
    sigma = math.sqrt(m * n * (m + n + 1) / 12.0)
    if alternative == "less":
        z = (u - mean + 0.5) / sigma
        return float(sps.norm.cdf(z))
    z = (u - mean - 0.5) / sigma
    return float(sps.norm.sf(z))


def thesis_r(u: float, m: int, n: int) -> float:
    """The original's effect size: Z/√n, Z without continuity correction, n = one
    group's size (the smaller, when they differ)."""
    sigma = math.sqrt(m * n * (m + n + 1) / 12.0)
    return (u - m * n / 2.0) / sigma / math.sqrt(min(m, n))


def u_statistic(x: np.ndarray, y: np.ndarray) -> float:
    """U of the first sample (ties count one half)."""
    return float(sps.mannwhitneyu(x, y, alternative="two-sided", method="asymptotic").statistic)


def r_tolerance(n: int) -> float:
    """How far two estimates of the same effect fall apart 95 % of the time, on the
    original's r scale (Z/√n, Z ~ N(0, 1) per estimate): 1.96·√(2/n)."""
    return 1.96 * math.sqrt(2.0 / n)


def mann_whitney_verdict(ours: Mapping[str, float], theirs: Mapping[str, float], n: int) -> str:
    same_decision = (ours["p"] < ALPHA) == (theirs["p"] < ALPHA)
    if same_decision and abs(ours["r"] - theirs["r"]) < r_tolerance(n):
        return REPRODUCED
    if np.sign(ours["r"]) == np.sign(theirs["r"]) and ours["r"] != 0:
        return DIRECTION
    return NOT_REPRODUCED


# --- selecting our runs -------------------------------------------------------------------


def select(runs: pd.DataFrame, where: Mapping[str, Any]) -> pd.DataFrame:
    """The runs matching every key of ``where`` (network, threshold, behaviour, spl)."""
    mask = pd.Series(True, index=runs.index)
    for key, value in where.items():
        column = runs[key]
        mask &= (column.astype(float) == float(value)) if key == "spl" else (column == value)
    return runs[mask]


def _values(frame: pd.DataFrame, metric: str) -> np.ndarray:
    arr = pd.to_numeric(frame[metric], errors="coerce").to_numpy(dtype=float, na_value=np.nan)
    return arr[np.isfinite(arr)]


# --- the comparisons -----------------------------------------------------------------------


@dataclass(frozen=True)
class Row:
    """One comparison: what was compared, the original's figure, ours, the verdict."""

    table: str
    lines: str
    what: str
    theirs: str
    ours: str
    verdict: str
    note: str = ""
    #: The metric compared ("" for the statements of the text and the χ² rows).
    metric: str = ""
    #: Both effect sizes on the original's scale (Mann–Whitney rows only).
    r_theirs: float = math.nan
    r_ours: float = math.nan


def mann_whitney_rows(runs: pd.DataFrame, original: dict[str, Any]) -> list[Row]:
    rows = []
    for table in original["mann_whitney"]:
        for item in table["rows"]:
            where = {k: item[k] for k in ("network", "threshold", "behaviour")}
            metric, alternative = item["metric"], table["alternative"]
            x = _values(select(runs, {**where, "spl": 0}), metric)
            y = _values(select(runs, {**where, "spl": item["spl"]}), metric)
            n0 = int(original["runs_per_configuration"])
            theirs = {
                "U": item["U"],
                "p": thesis_p(item["U"], n0, n0, alternative),
                "r": thesis_r(item["U"], n0, n0),
            }
            note = ""
            if abs(theirs["r"] - item["r"]) > 0.015 or abs(theirs["p"] - item["p"]) > 0.015:
                note = f"printed p {item['p']:.2f}, r {item['r']:.2f} do not follow from U"
            if (item["p"] < ALPHA) != (item["decision"] == "H_A"):
                note = (
                    note + "; " if note else ""
                ) + f"printed {item['decision']} with p {item['p']:.2f}"
            label = (
                f"{item['network'].upper()} {item['behaviour'].upper()} "
                f"{item['threshold'].upper()}: SPL0 vs SPL{item['spl']}"
            )
            ours = None
            if len(x) >= 2 and len(y) >= 2:
                u = u_statistic(x, y)
                ours = {
                    "U": u,
                    "p": thesis_p(u, len(x), len(y), alternative),
                    "r": thesis_r(u, len(x), len(y)),
                }
            rows.append(
                Row(
                    table["table"],
                    table["lines"],
                    f"{metric} · {label}",
                    _mw_text(theirs),
                    "too few runs" if ours is None else _mw_text(ours),
                    NOT_REPRODUCED
                    if ours is None
                    else mann_whitney_verdict(ours, theirs, min(len(x), len(y), n0)),
                    note,
                    metric,
                    theirs["r"],
                    math.nan if ours is None else ours["r"],
                )
            )
    return rows


def _mw_text(stat: Mapping[str, float]) -> str:
    decision = "H_A" if stat["p"] < ALPHA else "H_0"
    return f"U {stat['U']:.0f}, p {stat['p']:.2f}, r {stat['r']:+.2f} ({decision})"


def success_rows(runs: pd.DataFrame, original: dict[str, Any]) -> list[Row]:
    """Successful missions per SPL level (Fisher's exact test of ours against theirs),
    and the original's χ² computed both ways on both tables."""
    rows = []
    n0 = int(original["runs_per_configuration"])
    for item in original["success"]:
        where = {k: item[k] for k in ("network", "threshold", "behaviour")}
        theirs_counts: list[int] = []
        ours_counts: list[tuple[int, int]] = []
        levels = sorted(item["successful"].items())
        # The SPL 0 shares: a count "points the same way" when it moved the same way from them.
        base_theirs = levels[0][1] / n0
        base = select(runs, {**where, "spl": levels[0][0]})["successful"].dropna().astype(bool)
        base_ours = float(base.mean()) if len(base) else 0.0
        for spl, k_theirs in levels:
            frame = select(runs, {**where, "spl": spl})
            ok = frame["successful"].dropna().astype(bool)
            k_ours, n_ours = int(ok.sum()), len(ok)
            theirs_counts.append(k_theirs)
            ours_counts.append((k_ours, n_ours))
            p = float(
                sps.fisher_exact([[k_theirs, n0 - k_theirs], [k_ours, n_ours - k_ours]]).pvalue
            )
            if p >= ALPHA:
                verdict = REPRODUCED
            elif np.sign(k_theirs / n0 - base_theirs) == np.sign(
                k_ours / max(n_ours, 1) - base_ours
            ):
                verdict = DIRECTION
            else:
                verdict = NOT_REPRODUCED
            rows.append(
                Row(
                    item["table"],
                    item["lines"],
                    f"successful missions · {item['network'].upper()} "
                    f"{item['behaviour'].upper()}: SPL{spl}",
                    f"{k_theirs}/{n0}",
                    f"{k_ours}/{n_ours}",
                    verdict,
                    f"Fisher's exact p {p:.2f} (ours against theirs)",
                    "successful",
                )
            )
        rows.append(_chi_squared_row(item, theirs_counts, ours_counts, n0))
    return rows


def _chi_squared_row(
    item: dict[str, Any], theirs: list[int], ours: list[tuple[int, int]], n0: int
) -> Row:
    """The original's χ² = 68.0 is a goodness of fit of the successful counts to a uniform
    spread (df 3); the test for a table of counts is the k×2 contingency test."""

    def both(success: list[int], totals: list[int]) -> tuple[float, float, float, float]:
        fit = sps.chisquare(success) if sum(success) else None
        table = np.array([[s, t - s] for s, t in zip(success, totals, strict=True)])
        cont = sps.chi2_contingency(table) if (table.sum(axis=0) > 0).all() else None
        return (
            float(fit.statistic) if fit else math.nan,
            float(fit.pvalue) if fit else math.nan,
            float(cont.statistic) if cont else math.nan,
            float(cont.pvalue) if cont else math.nan,
        )

    t = both(theirs, [n0] * len(theirs))
    o = both([k for k, _ in ours], [n for _, n in ours])
    agree = (t[1] < ALPHA) == (o[1] < ALPHA) and (t[3] < ALPHA) == (o[3] < ALPHA)
    return Row(
        item["table"],
        "1417",
        f"χ² of successful missions · {item['network'].upper()} "
        f"{item['behaviour'].upper()} over SPL",
        f"goodness of fit {t[0]:.1f} (p {t[1]:.1g}); contingency {t[2]:.1f} (p {t[3]:.1g})",
        f"goodness of fit {o[0]:.1f} (p {o[1]:.1g}); contingency {o[2]:.1f} (p {o[3]:.1g})",
        REPRODUCED if agree else NOT_REPRODUCED,
        "the original printed 68.0, p 0.0: its goodness-of-fit figure",
    )


def claim_rows(runs: pd.DataFrame, original: dict[str, Any]) -> list[Row]:
    return [_claim(runs, claim) for claim in original["claims"]]


def _claim(runs: pd.DataFrame, claim: dict[str, Any]) -> Row:
    check = claim["check"]
    where = claim.get("where", {})
    frame = select(runs, where)
    verdict, ours = NOT_REPRODUCED, ""
    if check == "means_within_sd":
        groups = [_values(g, claim["metric"]) for _, g in frame.groupby("spl")]
        means = [float(g.mean()) for g in groups]
        sd = float(np.sqrt(np.mean([g.var(ddof=1) for g in groups])))
        spread = max(means) - min(means)
        ours = f"means {', '.join(f'{m:.1f}' for m in means)} s; spread {spread:.1f}, SD {sd:.1f}"
        verdict = REPRODUCED if spread < sd else DIRECTION if spread < 2 * sd else NOT_REPRODUCED
    elif check in ("all_successful", "none_successful_except"):
        keys = ["network", "threshold", "spl"]
        rates = {key: (int(g["successful"].sum()), len(g)) for key, g in frame.groupby(keys)}
        if check == "none_successful_except":
            excepted = [tuple(e.values()) for e in claim.get("except", [])]
            rates = {k: v for k, v in rates.items() if (k[0], k[2]) not in excepted}
        fractions = [k / n for k, n in rates.values()]
        failed = float(frame["n_failed_tasks"].fillna(0).sum())
        ours = ", ".join(
            f"{k[0].upper()} {k[1].upper()} SPL{k[2]:g} {s}/{n}"
            for k, (s, n) in sorted(rates.items())
        )
        if check == "all_successful":
            ours += f"; failed tasks in all: {failed:.0f}"
            verdict = (
                REPRODUCED
                if min(fractions) == 1.0 and failed == 0
                else DIRECTION
                if min(fractions) >= 0.9
                else NOT_REPRODUCED
            )
        else:
            verdict = (
                REPRODUCED
                if max(fractions) <= 0.1
                else DIRECTION
                if max(fractions) <= 0.5
                else NOT_REPRODUCED
            )
    elif check == "some_failed_tasks":
        lost = frame["n_failed_tasks"].fillna(0) > 0
        mean = frame["n_failed_tasks"].mean()
        ours = f"{int(lost.sum())}/{len(lost)} runs lose a status (mean {mean:.2f} tasks)"
        verdict = REPRODUCED if lost.mean() >= 0.5 else DIRECTION if lost.any() else NOT_REPRODUCED
    elif check in ("ratio_about", "ratio_above"):
        num = _values(select(runs, claim["numerator"]), claim["metric"]).mean()
        den = _values(select(runs, claim["denominator"]), claim["metric"]).mean()
        ratio = num / den if den else math.inf
        stated = float(claim["ratio"])
        ours = f"{num:.1f} / {den:.1f} = {ratio:.2f}×"
        if check == "ratio_about":
            close = abs(ratio - stated) <= ABOUT * stated
            verdict = (
                REPRODUCED
                if close
                else DIRECTION
                if (ratio > 1) == (stated > 1)
                else NOT_REPRODUCED
            )
        else:
            verdict = REPRODUCED if ratio > stated else DIRECTION if ratio > 1 else NOT_REPRODUCED
    elif check == "mean_between":
        mean = _values(frame, claim["metric"]).mean()
        low, high = float(claim["low"]), float(claim["high"])
        ours = f"mean {mean:.1f}"
        verdict = (
            REPRODUCED
            if low <= mean <= high
            else DIRECTION
            if low * (1 - ABOUT) <= mean <= high * (1 + ABOUT)
            else NOT_REPRODUCED
        )
    else:
        raise InputError(
            f"unknown check '{check}'", file=original_path(), field=f"claims.{claim['id']}.check"
        )
    return Row(
        "text",
        claim["lines"],
        claim["text"],
        "as stated",
        ours,
        verdict,
        CLAIM_RULES[check],
        claim.get("metric", ""),
    )


def compare(runs: pd.DataFrame, original: dict[str, Any] | None = None) -> pd.DataFrame:
    """Every comparison of the original with ``runs`` (a study of the same design)."""
    original = original or load_original()
    ok = runs[runs["status"] == "ok"] if "status" in runs else runs
    rows = success_rows(ok, original) + claim_rows(ok, original) + mann_whitney_rows(ok, original)
    return pd.DataFrame([r.__dict__ for r in rows])


def summary(rows: pd.DataFrame) -> dict[str, int]:
    """How many comparisons got each verdict."""
    return {v: int((rows["verdict"] == v).sum()) for v in VERDICTS}
