"""Figures and tables about communication: what the network did to the messages
(per topic and cause), each robot pair's link state over a run, AON's publications
and finish times, and the robots' trajectories on the map.

Like :mod:`figures`, every function takes DataFrames of the results database contract
and returns a matplotlib Figure (or a DataFrame for tables).
"""

from __future__ import annotations

from collections.abc import Collection, Sequence

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from mrcomm.analysis.figures import (
    _bar_offsets,
    _hide_unused,
    _spl_axis,
    behaviour_colour,
    box_plots,
    in_panel,
    panel_grid,
    panel_keys,
    panel_title,
    spl_levels,
)
from mrcomm.analysis.mission_map import draw_mission_map
from mrcomm.analysis.stats import GROUP, usable_runs
from mrcomm.net.delivery import COUNT_KEYS, DROP_CAUSES, DROPPED_COLLISION, RADIO_COUNT_KEYS

#: Why a message was not received, in the order the bars stack.
CAUSES = DROP_CAUSES
CAUSE_COLOURS = {
    "dropped_loss": "#E1812C",
    "dropped_range": "#C03D3E",
    "dropped_radio": "#8172B3",
    "dropped_queue": "#937860",
    "dropped_collision": "#DA8BC3",
}
#: The count columns of the messages table (the radio's are NULL without a radio).
COUNTS = [*COUNT_KEYS, DROPPED_COLLISION]
DROPS = list(DROP_CAUSES)
LINK_COLOURS = {"warning": "#F2C14E", "out of range": "#C03D3E"}
CONNECTED_COLOUR = "#DCEFD8"
TOPIC_ORDER = ("pose", "task_status", "aon", "utility", "role", "clock")


def _config_name(key: Sequence[str], multi_scenario: bool) -> str:
    scenario, network, threshold, behaviour, setting = (str(k) for k in key)
    parts = [network.upper()] + ([threshold.upper()] if threshold != "none" else [])
    name = "+".join([*parts, behaviour.upper()]) + (f" ({setting})" if setting else "")
    return f"{scenario} {name}" if multi_scenario else name


def _topics(messages: pd.DataFrame) -> list[str]:
    present = set(messages["topic"].astype(str))
    ordered = [t for t in TOPIC_ORDER if t in present]
    return ordered + sorted(present - set(ordered))


def per_run_messages(runs: pd.DataFrame, messages: pd.DataFrame) -> pd.DataFrame:
    """Messages per run and topic (summed over agents), joined to the runs'
    configuration: sent, received, dropped by each cause."""
    ok = usable_runs(runs)
    if messages.empty or ok.empty:
        return pd.DataFrame(columns=["run_id", "topic", *COUNTS, *GROUP, "spl"])
    messages = messages.reindex(columns=["run_id", "topic", *COUNTS]).fillna(
        dict.fromkeys(COUNTS, 0)
    )
    per_run = messages.groupby(["run_id", "topic"], as_index=False)[COUNTS].sum()
    return per_run.merge(ok[["run_id", *GROUP, "spl"]], on="run_id")


def message_table(runs: pd.DataFrame, messages: pd.DataFrame) -> pd.DataFrame:
    """Mean per run of each topic's sent, received and dropped (by cause) messages,
    and the share of deliveries lost, per configuration and SPL level."""
    data = per_run_messages(runs, messages)
    if data.empty:
        return pd.DataFrame()
    keys = [*GROUP, "spl", "topic"]
    mean = data.groupby(keys, as_index=False)[COUNTS].mean()
    lost = mean[DROPS].sum(axis=1)
    attempts = mean["received"] + lost
    mean["lost_percent"] = np.where(attempts > 0, 100.0 * lost / attempts, np.nan)
    mean["runs"] = data.groupby(keys)["run_id"].nunique().to_numpy()
    return mean


def message_loss_figure(runs: pd.DataFrame, messages: pd.DataFrame) -> Figure:
    """Share of deliveries that did not arrive, stacked by cause: one panel per
    configuration, the topics on the x axis, one bar per SPL level (labelled above)."""
    table = message_table(runs, messages)
    configs = list(table.groupby(list(GROUP), sort=True).groups)
    multi = len({c[0] for c in configs}) > 1
    levels = spl_levels(table)
    fig, axes = panel_grid(len(configs), width=4.8, height=3.6)
    offsets, width = _bar_offsets(len(levels))
    # Loss and range always; the radio's causes where a run had them.
    colours = {
        cause: colour
        for cause, colour in CAUSE_COLOURS.items()
        if cause not in (*RADIO_COUNT_KEYS, DROPPED_COLLISION) or table[cause].sum() > 0
    }
    for ax, key in zip(axes.flat, configs, strict=False):
        frame = table[(table[list(GROUP)] == pd.Series(key, index=list(GROUP))).all(axis=1)]
        topics = _topics(frame)
        for off, spl in zip(offsets, levels, strict=True):
            rows = frame[frame["spl"] == spl].set_index("topic").reindex(topics)
            attempts = (rows["received"] + rows[DROPS].sum(axis=1)).to_numpy()
            bottom = np.zeros(len(topics))
            for cause, colour in colours.items():
                with np.errstate(divide="ignore", invalid="ignore"):
                    share = np.where(attempts > 0, 100.0 * rows[cause].to_numpy() / attempts, 0.0)
                share = np.nan_to_num(share)
                ax.bar(
                    np.arange(len(topics)) + off,
                    share,
                    width * 0.92,
                    bottom=bottom,
                    color=colour,
                    edgecolor="white",
                    lw=0.3,
                )
                bottom += share
            for i, total in enumerate(bottom):
                # Zero-height bars stay unlabelled: the caption says what no bar means.
                if np.isfinite(attempts[i]) and attempts[i] > 0 and total > 0.5:
                    ax.annotate(
                        f"{spl:g}",
                        (i + off, total),
                        xytext=(0, 1),
                        textcoords="offset points",
                        ha="center",
                        fontsize=6.5,
                    )
        ax.set_xticks(range(len(topics)), topics, rotation=30, ha="right")
        ax.set_title(_config_name(key, multi))
        ax.set_ylabel("deliveries not received (%)")
        ax.set_ylim(0, 105)
        ax.grid(axis="y", alpha=0.3)
    _hide_unused(axes, len(configs))
    handles = [Patch(color=c, label=CAUSES[k]) for k, c in colours.items()]
    fig.legend(handles=handles, loc="outside lower center", ncols=len(handles))
    fig.suptitle("Messages not received, by topic and cause (mean share per run; bar label: SPL %)")
    return fig


def link_state_figure(
    link_states: pd.DataFrame, run_id: str, end: float, robots: Sequence[str], title: str
) -> Figure:
    """One row per robot pair: connected (pale), in warning, out of range, over the run."""
    pairs = [(a, b) for i, a in enumerate(robots) for b in robots[i + 1 :]]
    fig = Figure(figsize=(12, 0.42 * len(pairs) + 1.6), layout="constrained")
    ax = fig.subplots()
    sub = link_states[link_states["run_id"] == run_id]
    for y, (a, b) in enumerate(pairs):
        ax.broken_barh([(0.0, end)], (y - 0.38, 0.76), facecolors=CONNECTED_COLOUR)
        rows = sub[(sub["robot_a"] == a) & (sub["robot_b"] == b)]
        for state, colour in LINK_COLOURS.items():
            spans = rows[rows["state"] == state]
            if not spans.empty:
                ax.broken_barh(
                    list(zip(spans["t_start"], spans["t_end"] - spans["t_start"], strict=True)),
                    (y - 0.38, 0.76),
                    facecolors=colour,
                )
    ax.set_yticks(range(len(pairs)), [f"{a}–{b}" for a, b in pairs])
    ax.invert_yaxis()
    ax.set_xlim(0, end)
    ax.set_xlabel("time (s)")
    ax.grid(axis="x", alpha=0.4)
    handles = [Patch(color=CONNECTED_COLOUR, label="connected")]
    handles += [Patch(color=c, label=s) for s, c in LINK_COLOURS.items()]
    fig.legend(handles=handles, loc="outside lower center", ncols=3)
    ax.set_title(title)
    return fig


def aon_figure(runs: pd.DataFrame) -> Figure | None:
    """AON publications per run and the time the slowest status took to reach every
    member, box plots per configuration and SPL level (runs with AON only)."""
    ok = usable_runs(runs)
    if "aon_publications" not in ok or ok["aon_publications"].isna().all():
        return None
    ok = ok[ok["aon_publications"].notna()]
    keys = panel_keys(ok)
    levels = spl_levels(ok)
    behs = sorted({str(b) for b in ok["behaviour"]})
    fig, axes = panel_grid(len(keys), rows=2, width=4.4, height=3.0)
    cols = axes.shape[1]
    columns = (
        ("aon_publications", "AON publications per run"),
        ("aon_max_finish_time", "slowest AON finish (s)"),
    )
    for k, key in enumerate(keys):
        frame = in_panel(ok, key)
        for r, (column, label) in enumerate(columns):
            ax = axes[2 * (k // cols) + r, k % cols]
            box_plots(ax, frame, column, levels, behs)
            _spl_axis(ax, levels)
            ax.set_ylabel(label)
            ax.set_title(panel_title(key, False))
    for k in range(len(keys), axes.shape[0] // 2 * cols):
        for r in range(2):
            axes[2 * (k // cols) + r, k % cols].set_visible(False)
    handles = [Patch(color=behaviour_colour(b), label=b.upper()) for b in behs]
    fig.legend(handles=handles, loc="outside lower center", ncols=len(handles))
    fig.suptitle("All-Or-Nothing messaging: publications and finish times (box plots)")
    return fig


def trajectory_figure(
    trajectories: pd.DataFrame,
    run_id: str,
    occupied: np.ndarray,
    extent: tuple[float, float, float, float],
    tasks: Sequence[tuple[str, float, float]],
    title: str,
    failed: Collection[str] = (),
) -> Figure:
    """Every robot's path in one run on the map, start (○) and end (■) marked, tasks (★,
    crimson when ``failed``), as ``mrcomm run --plot`` draws it."""
    xmin, xmax, ymin, ymax = extent
    width = 10.0
    height = max(3.5, width * (ymax - ymin) / (xmax - xmin) + 0.8)
    fig = Figure(figsize=(width, height), layout="constrained")
    ax = fig.subplots()
    sub = trajectories[trajectories["run_id"] == run_id]
    tracks = {
        str(robot): track.sort_values("t")[["x", "y"]].to_numpy(dtype=float)
        for robot, track in sub.groupby("robot", sort=True)
    }
    draw_mission_map(ax, occupied, extent, tracks, tasks, failed=failed,
                     task_labels=len(tasks) <= 100)  # fmt: skip
    ax.set_title(title)
    return fig
