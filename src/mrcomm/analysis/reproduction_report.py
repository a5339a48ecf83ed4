"""The reproduction report's generated part: the verdict summary, the comparison table
and its figures (docs/REPRODUCTION.md, written by ``make reproduce``).

The comparisons and their verdicts are :mod:`mrcomm.analysis.reproduction`'s; this module
only lays them out, for two studies of the original's design side by side: MRComm's
defaults and the original robots' profile.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from mrcomm.analysis.reproduction import (
    CLAIM_RULES,
    DIRECTION,
    NOT_REPRODUCED,
    REPRODUCED,
    VERDICTS,
    r_tolerance,
    select,
    summary,
)

#: The studies of a report: column title -> what it is.
DEFAULTS = "MRComm defaults"
ORIGINAL = "original robots' profile"
COLOURS = {REPRODUCED: "#1b9e77", DIRECTION: "#e6ab02", NOT_REPRODUCED: "#d95f02"}
MARK = {REPRODUCED: "✔ reproduced", DIRECTION: "➚ direction", NOT_REPRODUCED: "✘ not reproduced"}


#: The LF metrics the followers' mechanism explains (docs/REPRODUCTION.md).
FOLLOWERS_METRICS = ("leader_disconnect_time", "idle_time", "total_distance")


def mechanism(row: pd.Series) -> str:
    """The section of docs/REPRODUCTION.md that explains a difference in ``row``."""
    if row["metric"] == "near_collisions":
        return "near-collisions"
    lf = " LF " in row["what"] or row["what"].startswith("LF")
    if lf and row["table"] != "text" and row["metric"] in FOLLOWERS_METRICS:
        return "followers-drive-to-the-leaders-pose"
    if lf:
        return "what-is-left"
    if row["table"] in ("4.9", "5.7", "5.8", "5.10") or row["what"].startswith("NB"):
        return "small-effects"
    return ""


def summary_table(studies: Mapping[str, pd.DataFrame]) -> str:
    """How many comparisons each study reproduces, in direction only, or not."""
    lines = [
        "| study | comparisons | " + " | ".join(VERDICTS) + " |",
        "|---|---|" + "---|" * len(VERDICTS),
    ]
    for name, rows in studies.items():
        counts = summary(rows)
        cells = " | ".join(f"{counts[v]} ({100 * counts[v] / len(rows):.0f} %)" for v in VERDICTS)
        lines.append(f"| {name} | {len(rows)} | {cells} |")
    return "\n".join(lines)


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def comparison_table(studies: Mapping[str, pd.DataFrame]) -> str:
    """Every comparison: the original's figure, each study's and its verdict, and the
    mechanism section that explains a difference (by metric)."""
    names = list(studies)
    first = studies[names[0]]
    head = "| # | table (lines) | comparison | original | " + " | ".join(
        f"{name} | verdict" for name in names
    )
    lines = [head + " | why (section) | note |", "|---" * (6 + 2 * len(names)) + "|"]
    for i, row in enumerate(first.itertuples()):
        cells = [str(i + 1), f"{row.table} ({row.lines})", _cell(row.what), _cell(row.theirs)]
        worst = REPRODUCED
        for name in names:
            other = studies[name].iloc[i]
            cells += [_cell(other["ours"]), MARK[other["verdict"]]]
            if other["verdict"] != REPRODUCED:
                worst = other["verdict"]
        section = mechanism(first.iloc[i]) if worst != REPRODUCED else ""
        note = row.note if row.table != "text" else ""
        cells += [f"[{section}](#{section})" if section else "", _cell(note)]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def rules_list() -> str:
    """The rules of the statements' verdicts, as the report lists them."""
    return "\n".join(f"* `{check}`: {rule}." for check, rule in CLAIM_RULES.items())


def effects_figure(studies: Mapping[str, pd.DataFrame], n: int) -> Figure:
    """The original's effect size against ours, one point a Mann–Whitney row, one
    panel a study; the band is where two samples of one effect fall 95 % of the time."""
    fig, axes = plt.subplots(1, len(studies), figsize=(5.2 * len(studies), 5.0), squeeze=False)
    band = r_tolerance(n)
    lim = 1.3
    for ax, (name, rows) in zip(axes[0], studies.items(), strict=True):
        mw = rows[np.isfinite(rows["r_ours"].astype(float))]
        line = np.array([-lim, lim])
        ax.fill_between(line, line - band, line + band, color="0.9", label=f"±{band:.2f}")
        ax.plot(line, line, color="0.5", lw=0.8)
        ax.axhline(0, color="0.8", lw=0.6)
        ax.axvline(0, color="0.8", lw=0.6)
        for verdict in VERDICTS:
            part = mw[mw["verdict"] == verdict]
            ax.scatter(
                part["r_theirs"],
                part["r_ours"],
                s=22,
                color=COLOURS[verdict],
                label=f"{verdict} ({len(part)})",
                edgecolor="white",
                linewidth=0.5,
            )
        ax.set_xlim(-lim, lim)
        ax.set_ylim(-lim, lim)
        ax.set_aspect("equal")
        ax.set_xlabel("original's effect size r = Z/√n")
        ax.set_ylabel("ours, same statistic")
        ax.set_title(name)
        ax.legend(loc="upper left", fontsize=8, frameon=False)
    fig.suptitle("Mann–Whitney rows of Tables 4.9 and 5.4–5.10: SPL0 vs SPLX")
    fig.tight_layout()
    return fig


def success_figure(runs: Mapping[str, pd.DataFrame], original: Mapping[str, Any]) -> Figure:
    """Successful missions per configuration: each study's share, and the original's
    where it gives one (Table 4.7 for NB on WLAN; 100 % for every LF configuration)."""
    first = next(iter(runs.values()))
    keys = (
        first[["network", "threshold", "behaviour"]]
        .drop_duplicates()
        .sort_values(["behaviour", "network", "threshold"], ascending=[False, False, True])
    )
    spls = sorted(first["spl"].unique())
    fig, axes = plt.subplots(1, len(keys), figsize=(2.3 * len(keys), 3.4), sharey=True)
    stated: dict[tuple[str, str, str], dict[float, float]] = {}
    for item in original["success"]:
        key = (item["network"], item["threshold"], item["behaviour"])
        stated[key] = {float(s): 100 * k / 30 for s, k in item["successful"].items()}
    width = 0.8 / len(runs)
    for ax, key in zip(np.atleast_1d(axes), keys.itertuples(index=False), strict=True):
        where = dict(zip(("network", "threshold", "behaviour"), key, strict=True))
        for j, (name, study) in enumerate(runs.items()):
            counts = [select(study, {**where, "spl": s})["successful"] for s in spls]
            share = [100 * c.mean() for c in counts]
            x = np.arange(len(spls)) + (j - (len(runs) - 1) / 2) * width
            ax.bar(x, share, width, label=name, color=("#7570b3", "#66a61e")[j % 2])
            for xi, yi, c in zip(x, share, counts, strict=True):
                # The count on every bar: a bar of 0 % is otherwise not there to see.
                ax.text(xi, yi + 2, f"{int(c.sum())}/{len(c)}", rotation=90, ha="center",
                        va="bottom", fontsize=6, zorder=4,
                        bbox={"facecolor": "white", "edgecolor": "none", "pad": 0.3})  # fmt: skip
        theirs = stated.get(tuple(key)) or (
            {float(s): 100.0 for s in spls} if where["behaviour"] == "lf" else None
        )
        if theirs:
            ax.scatter(
                range(len(spls)),
                [theirs[float(s)] for s in spls],
                marker="_",
                s=300,
                color="black",
                zorder=3,
                label="original",
            )
        ax.set_xticks(range(len(spls)), [f"{s:g}" for s in spls])
        ax.set_xlabel("SPL %")
        ax.set_title(" ".join(v.upper() for v in key), fontsize=9)
    np.atleast_1d(axes)[0].set_ylabel("successful missions %")
    np.atleast_1d(axes)[0].set_ylim(0, 125)
    np.atleast_1d(axes)[0].set_yticks(range(0, 101, 20))
    handles, labels = np.atleast_1d(axes)[0].get_legend_handles_labels()
    for ax in np.atleast_1d(axes):
        h, lab = ax.get_legend_handles_labels()
        if len(h) > len(handles):
            handles, labels = h, lab
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), frameon=False, fontsize=8)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    return fig
