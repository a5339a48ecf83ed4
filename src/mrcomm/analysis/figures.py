"""Figures of a study, per configuration, grouped like the original thesis: one panel per
network + threshold (WLAN+SLT, AH+SLT, AH+SSD, AH+ESD, ...), SPL on the x axis, NB and
LF side by side. Here: mean ± standard deviation of a metric, successful-mission
percentages, minimum/maximum separation and failed tasks per robot; the time
breakdowns, timelines and RSSI are in :mod:`figures_time`, Q–Q plots in
:mod:`figures_qq`.

Every function takes the DataFrames of the results database contract and returns a
matplotlib Figure (backend Agg); :mod:`encoding` turns one into PNG/SVG/PDF bytes.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable, Sequence
from typing import Any

import matplotlib

matplotlib.use("Agg")  # figures are files; never open a window
import numpy as np
import pandas as pd
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from mrcomm.analysis.stats import metric_info, usable_runs

NETWORK_ORDER = {"wlan": 0, "ah": 1}
THRESHOLD_ORDER = {"none": 0, "slt": 1, "ssd": 2, "esd": 3}
BEHAVIOUR_ORDER = {"nb": 0, "lf": 1, "lf-wait": 2, "rps": 3, "serried": 4}
BEHAVIOUR_COLOURS = {
    "nb": "#4C72B0",
    "lf": "#DD8452",
    "lf-wait": "#55A868",
    "rps": "#C44E52",
    "serried": "#8172B3",
}
#: Colours of other behaviours (plugins, or a behaviour with its own parameters), picked
#: by name so that a behaviour keeps its colour from figure to figure.
OTHER_COLOURS = ("#937860", "#DA8BC3", "#8C8C8C", "#CCB974", "#64B5CD")
#: SLT warning and the AH range (m), drawn on separation figures for reference.
SLT_WARNING_M = 4.0
AH_LIMIT_M = 8.0

PanelKey = tuple[str, str, str, str]  # (scenario, network, threshold, setting)


def _order(mapping: dict[str, int], value: str) -> tuple[int, str]:
    return (mapping.get(str(value).lower(), len(mapping)), str(value))


def panel_keys(runs: pd.DataFrame) -> list[PanelKey]:
    """The (scenario, network, threshold, setting) panels present, in the original's
    order (setting: the variant parameters a panel's runs share, "" for none)."""
    settings = runs["setting"] if "setting" in runs else pd.Series("", index=runs.index)
    columns = runs[["scenario", "network", "threshold"]].assign(setting=settings.fillna(""))
    keys = {(str(s), str(n), str(t), str(p)) for s, n, t, p in columns.itertuples(index=False)}
    return sorted(
        keys,
        key=lambda k: (k[0], _order(NETWORK_ORDER, k[1]), _order(THRESHOLD_ORDER, k[2]), k[3]),
    )


def in_panel(frame: pd.DataFrame, key: PanelKey) -> pd.DataFrame:
    """The rows of ``frame`` that belong to panel ``key`` (a frame without a setting
    column has the default setting only)."""
    mask = (
        (frame["scenario"] == key[0])
        & (frame["network"] == key[1])
        & (frame["threshold"] == key[2])
    )
    if "setting" in frame:
        mask &= frame["setting"].fillna("") == key[3]
    return frame[mask]


def panel_title(key: PanelKey, with_scenario: bool) -> str:
    scenario, network, threshold, setting = key
    text = network.upper() if threshold == "none" else f"{network.upper()} + {threshold.upper()}"
    text += f" · {setting}" if setting else ""
    return f"{scenario} · {text}" if with_scenario else text


def behaviours(runs: pd.DataFrame) -> list[str]:
    return sorted(
        {str(b) for b in runs["behaviour"].dropna()}, key=lambda b: _order(BEHAVIOUR_ORDER, b)
    )


def spl_levels(runs: pd.DataFrame) -> list[float]:
    return sorted(float(s) for s in runs["spl"].dropna().unique())


def behaviour_colour(behaviour: str) -> str:
    known = BEHAVIOUR_COLOURS.get(behaviour.lower())
    if known is not None:
        return known
    index = int(hashlib.sha256(behaviour.lower().encode()).hexdigest(), 16) % len(OTHER_COLOURS)
    return OTHER_COLOURS[index]


def panel_grid(
    n: int, width: float = 4.2, height: float = 3.4, rows: int = 1, ncols: int | None = None
) -> tuple[Figure, np.ndarray]:
    """A figure with ``rows`` × ``n`` axes (at most 4 panels to a row)."""
    cols = ncols or max(1, min(n, 4))
    rows_total = rows * math.ceil(n / cols)
    # At least 7 in wide so that titles and legends fit above/below a single panel.
    fig = Figure(figsize=(max(7.0, width * cols), height * rows_total), layout="constrained")
    axes = fig.subplots(rows_total, cols, squeeze=False)
    return fig, axes


def _hide_unused(axes: np.ndarray, used: int) -> None:
    for ax in axes.flat[used:]:
        ax.set_visible(False)


def _spl_axis(ax: Axes, levels: Sequence[float]) -> None:
    """SPL levels as categories: tick i at x = i, what belongs to it within ±0.4 of
    it, and the axis a unit per level wide (with two levels, autoscaling squeezed the
    range to the markers and drew them far from their tick)."""
    ax.set_xticks(range(len(levels)), [f"{s:g}" for s in levels])
    ax.set_xlim(-0.5, len(levels) - 0.5)
    ax.set_xlabel("SPL (%)")
    ax.grid(axis="y", alpha=0.3)


def _bar_offsets(count: int, width: float = 0.8) -> tuple[np.ndarray, float]:
    bar = width / max(count, 1)
    return (np.arange(count) - (count - 1) / 2.0) * bar, bar


def _per_panel(
    runs: pd.DataFrame,
    draw: Callable[[Axes, pd.DataFrame, list[float], list[str]], None],
    title: str,
    ylabel: str,
    extra_handles: Sequence[Artist] = (),
) -> Figure:
    runs = usable_runs(runs)
    keys = panel_keys(runs)
    multi = len({k[0] for k in keys}) > 1
    levels = spl_levels(runs)
    behs = behaviours(runs)
    fig, axes = panel_grid(len(keys))
    for ax, key in zip(axes.flat, keys, strict=False):
        frame = in_panel(runs, key)
        draw(ax, frame, levels, behs)
        ax.set_title(panel_title(key, multi))
        _spl_axis(ax, levels)
        ax.set_ylabel(ylabel)
    _hide_unused(axes, len(keys))
    handles: list[Artist] = [Patch(color=behaviour_colour(b), label=b.upper()) for b in behs]
    handles += list(extra_handles)
    fig.legend(handles=handles, loc="outside lower center", ncols=len(handles))
    fig.suptitle(title)
    return fig


def metric_bars(runs: pd.DataFrame, metric: str) -> Figure:
    """``metric`` per configuration: mean ± standard deviation (ddof=1) bars, as the
    original study drew them, above box plots (median, quartiles, 1.5 IQR whiskers),
    which show what the rank tests compare. Behaviours without the metric (NB for
    Leader–Follower metrics) are left out, not drawn as zero."""
    info = metric_info(metric)
    runs = usable_runs(runs)
    runs = runs[pd.to_numeric(runs[metric], errors="coerce").notna()]
    keys = panel_keys(runs)
    multi = len({k[0] for k in keys}) > 1
    levels = spl_levels(runs)
    behs = behaviours(runs)
    fig, axes = panel_grid(len(keys), rows=2, height=3.0)
    cols = axes.shape[1]
    for k, key in enumerate(keys):
        frame = in_panel(runs, key)
        top, bottom = axes[2 * (k // cols), k % cols], axes[2 * (k // cols) + 1, k % cols]
        _mean_sd_bars(top, frame, metric, levels, behs)
        box_plots(bottom, frame, metric, levels, behs)
        for ax, kind in ((top, "mean ± SD"), (bottom, "box plot")):
            ax.set_title(f"{panel_title(key, multi)} · {kind}", fontsize=10)
            _spl_axis(ax, levels)
            ax.set_ylabel(f"{info.label} ({info.unit})")
    for k in range(len(keys), (axes.shape[0] // 2) * cols):
        axes[2 * (k // cols), k % cols].set_visible(False)
        axes[2 * (k // cols) + 1, k % cols].set_visible(False)
    handles = [Patch(color=behaviour_colour(b), label=b.upper()) for b in behs]
    fig.legend(handles=handles, loc="outside lower center", ncols=max(len(handles), 1))
    fig.suptitle(info.label)
    return fig


def _mean_sd_bars(
    ax: Axes, frame: pd.DataFrame, column: str, levels: list[float], behs: list[str]
) -> None:
    offsets, width = _bar_offsets(len(behs))
    for off, beh in zip(offsets, behs, strict=True):
        for i, spl in enumerate(levels):
            vals = pd.to_numeric(
                frame.loc[(frame["behaviour"] == beh) & (frame["spl"] == spl), column],
                errors="coerce",
            ).dropna()
            if not len(vals):
                continue  # no runs here: nothing drawn (not a zero bar)
            sd = float(vals.std(ddof=1)) if len(vals) > 1 else 0.0
            ax.bar(
                i + off,
                float(vals.mean()),
                width * 0.95,
                yerr=sd,
                capsize=3,
                color=behaviour_colour(beh),
                error_kw={"elinewidth": 1},
            )


def box_plots(
    ax: Axes, frame: pd.DataFrame, column: str, levels: list[float], behs: list[str]
) -> bool:
    """Box plots of ``column`` per behaviour and SPL level; False when there is no data."""
    offsets, width = _bar_offsets(len(behs))
    drawn = False
    for off, beh in zip(offsets, behs, strict=True):
        samples, positions = [], []
        for i, spl in enumerate(levels):
            values = pd.to_numeric(
                frame.loc[(frame["behaviour"] == beh) & (frame["spl"] == spl), column],
                errors="coerce",
            ).dropna()
            if len(values):
                samples.append(values.to_numpy())
                positions.append(i + off)
        if samples:
            drawn = True
            parts = ax.boxplot(
                samples,
                positions=positions,
                widths=width * 0.8,
                patch_artist=True,
                manage_ticks=False,
                medianprops={"color": "black", "gid": "median"},
                flierprops={"markersize": 3},
            )
            for patch in parts["boxes"]:
                patch.set_facecolor(behaviour_colour(beh))
                patch.set_alpha(0.75)
            # A box without spread (every run the same) is only its median line: draw
            # that line in the behaviour's colour, thick, so whose it is shows.
            for sample, median in zip(samples, parts["medians"], strict=True):
                if np.ptp(sample) == 0:
                    median.set_color(behaviour_colour(beh))
                    median.set_linewidth(4)
                    median.set_gid("median-flat")
    return drawn


def success_figure(runs: pd.DataFrame) -> Figure:
    """Percentage of successful missions per configuration, labelled k/n."""

    def draw(ax: Axes, frame: pd.DataFrame, levels: list[float], behs: list[str]) -> None:
        offsets, width = _bar_offsets(len(behs))
        # More than two bars to a level: the k/n labels stand upright, or they overlap.
        upright = len(behs) > 2
        for off, beh in zip(offsets, behs, strict=True):
            for i, spl in enumerate(levels):
                ok = frame.loc[(frame["behaviour"] == beh) & (frame["spl"] == spl), "successful"]
                ok = ok.dropna().astype(bool)
                if not len(ok):
                    continue
                pct = 100.0 * float(ok.mean())
                ax.bar(i + off, pct, width * 0.95, color=behaviour_colour(beh))
                ax.annotate(
                    f"{int(ok.sum())}/{len(ok)}",
                    (i + off, pct),
                    xytext=(0, 2),
                    textcoords="offset points",
                    ha="center",
                    va="bottom",
                    rotation=90 if upright else 0,
                    fontsize=7,
                    gid="success-label",
                )
        ax.set_ylim(0, 130 if upright else 112)

    return _per_panel(runs, draw, "Successful missions", "successful missions (%)")


def separation_figure(runs: pd.DataFrame) -> Figure:
    """Minimum (▼) and maximum (▲) separation, mean ± SD, with the 4 m SLT warning and
    the 8 m AH limit for reference."""

    def draw(ax: Axes, frame: pd.DataFrame, levels: list[float], behs: list[str]) -> None:
        offsets, _ = _bar_offsets(len(behs), 0.5)
        for off, beh in zip(offsets, behs, strict=True):
            for column, marker in (("min_separation", "v"), ("max_separation", "^")):
                means, sds = [], []
                for spl in levels:
                    vals = pd.to_numeric(
                        frame.loc[(frame["behaviour"] == beh) & (frame["spl"] == spl), column],
                        errors="coerce",
                    ).dropna()
                    means.append(vals.mean() if len(vals) else np.nan)
                    sds.append(vals.std(ddof=1) if len(vals) > 1 else 0.0)
                ax.errorbar(
                    np.arange(len(levels)) + off,
                    means,
                    yerr=sds,
                    fmt=marker,
                    color=behaviour_colour(beh),
                    capsize=3,
                    ms=6,
                )
        # Reference lines only where they apply: SLT's warning, the AH range.
        if set(frame["threshold"]) == {"slt"}:
            ax.axhline(SLT_WARNING_M, **_SLT_LINE)
        if set(frame["network"]) == {"ah"}:
            ax.axhline(AH_LIMIT_M, **_AH_LINE)
        ax.set_ylim(bottom=0)

    # Only the reference lines some panel draws appear in the legend.
    ok = usable_runs(runs)
    refs = []
    if (ok["threshold"] == "slt").any():
        refs.append(Line2D([], [], label="4 m SLT warning", **_SLT_LINE))
    if (ok["network"] == "ah").any():
        refs.append(Line2D([], [], label="8 m AH limit", **_AH_LINE))
    return _per_panel(
        runs,
        draw,
        "Separation from the closest ▼ and the furthest ▲ team mate (mean ± SD)",
        "separation (m)",
        extra_handles=refs,
    )


_SLT_LINE: dict[str, Any] = {"color": "grey", "ls": "--", "lw": 0.8}
_AH_LINE: dict[str, Any] = {"color": "firebrick", "ls": ":", "lw": 0.8}


def failed_per_robot(
    runs: pd.DataFrame, failed_tasks: pd.DataFrame, robots: Sequence[str] | None = None
) -> pd.DataFrame:
    """Mean failed tasks per run, per (configuration, robot); runs without failures count
    as zero."""
    runs = usable_runs(runs)
    if robots is None:
        robots = sorted(set(failed_tasks["robot"].dropna().astype(str)))
    counts = (
        failed_tasks[failed_tasks["run_id"].isin(runs["run_id"])]
        .groupby(["run_id", "robot"])
        .size()
        .rename("failed")
    )
    index = pd.MultiIndex.from_product([runs["run_id"], list(robots)], names=["run_id", "robot"])
    full = counts.reindex(index, fill_value=0).reset_index()
    keys = ["scenario", "network", "threshold", "setting", "behaviour", "spl"]
    full = full.merge(runs[["run_id", *keys]], on="run_id")
    return full.groupby([*keys, "robot"], as_index=False)["failed"].mean()


def failed_tasks_figure(
    runs: pd.DataFrame, failed_tasks: pd.DataFrame, robots: Sequence[str] | None = None
) -> Figure:
    """Mean failed tasks per run for each robot: one row of panels per behaviour."""
    runs = usable_runs(runs)
    table = failed_per_robot(runs, failed_tasks, robots)
    robot_ids = list(robots) if robots is not None else sorted(set(table["robot"]))
    keys = panel_keys(runs)
    multi = len({k[0] for k in keys}) > 1
    behs = behaviours(runs)
    levels = spl_levels(runs)
    fig = Figure(figsize=(max(7.0, 4.2 * len(keys)), 3.0 * len(behs)), layout="constrained")
    axes = fig.subplots(len(behs), len(keys), squeeze=False, sharey=True)
    cmap = matplotlib.colormaps["Set2"]
    offsets, width = _bar_offsets(max(len(robot_ids), 1))
    for row, beh in enumerate(behs):
        for col, key in enumerate(keys):
            ax = axes[row, col]
            sub = in_panel(table, key)
            sub = sub[sub["behaviour"] == beh]
            for k, (off, robot) in enumerate(zip(offsets, robot_ids, strict=True)):
                heights = [
                    float(sub.loc[(sub["spl"] == s) & (sub["robot"] == robot), "failed"].sum())
                    for s in levels
                ]
                ax.bar(
                    np.arange(len(levels)) + off,
                    heights,
                    width * 0.95,
                    color=cmap(k % 8),
                    label=robot,
                )
            if not sub.empty and float(sub["failed"].sum()) == 0.0:
                ax.text(
                    0.5, 0.5, "no failed tasks", transform=ax.transAxes, ha="center", color="grey"
                )
            ax.set_title(f"{panel_title(key, multi)} · {beh.upper()}")
            _spl_axis(ax, levels)
            if col == 0:
                ax.set_ylabel("failed tasks per run")
    if robot_ids:
        handles, labels = axes[0, 0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="outside lower center", ncols=len(robot_ids))
    fig.suptitle("Failed tasks per robot (mean per run)")
    return fig
