"""Time figures of a study: stacked time bars per configuration (where the team's time
went: movement by role, leader disconnect, follower waiting, delay, idle, role
assignment, switching), the timeline chart of one run (every robot's labelled
intervals and its events) and RSSI over time of one run or two (SSD vs ESD).

Inputs are DataFrames of the results database contract; outputs matplotlib Figures.
"""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib

matplotlib.use("Agg")  # figures are files; never open a window
import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from mrcomm.analysis.figures import (
    _bar_offsets,
    _hide_unused,
    behaviours,
    in_panel,
    panel_grid,
    panel_keys,
    panel_title,
    spl_levels,
)
from mrcomm.analysis.stats import usable_runs
from mrcomm.metrics import labels as L

#: Components of the stacked time bars: (name, colour). "movement (NB) / NA" is an NB
#: robot's whole movement and an LF robot's movement while not assigned a role;
#: "other movement" is LF movement in no NA/leader/follower role (regrouping).
TIME_COMPONENTS: tuple[tuple[str, str], ...] = (
    ("movement (NB) / NA movement", "#4C72B0"),
    ("leader movement", "#DD8452"),
    ("follower movement", "#55A868"),
    ("other movement (regrouping)", "#8C8C8C"),
    ("leader disconnect", "#C44E52"),
    ("follower waiting", "#8172B3"),
    ("delay", "#937860"),
    ("idle", "#DA8BC3"),
    ("role assignment", "#CCB974"),
    ("switching", "#64B5CD"),
)

#: Colours of timeline labels (activity and role tracks).
LABEL_COLOURS: dict[str, str] = {
    L.INIT: "#BBBBBB",
    L.MOVING: "#4C72B0",
    L.DELAY: "#937860",
    L.TASK: "#2CA02C",
    L.WAITING: "#E5D8A9",
    L.IDLE: "#DA8BC3",
    L.ROLE_ASSIGNMENT: "#CCB974",
    L.LEADER_DISCONNECT: "#C44E52",
    L.FOLLOWER_WAITING: "#8172B3",
    L.SWITCHING: "#64B5CD",
    L.ROLE_NA: "#D0D8E8",
    L.ROLE_LEADER: "#DD8452",
    L.ROLE_FOLLOWER: "#55A868",
    L.ROLE_ASSIGNING: "#F0E442",
    L.ROLE_REGROUPING: "#8C8C8C",
}
_FALLBACK = matplotlib.colormaps["tab20"]
#: Events drawn on the timeline: label -> (marker, colour).
EVENT_MARKERS: dict[str, tuple[str, str]] = {
    L.NEAR_COLLISION: ("x", "red"),
    L.TASK_COMPLETED: ("*", "black"),
    # A triangle with a white edge: readable on every interval colour (a thin tick was not).
    L.DISCONNECT_DETECTED: ("v", "black"),
}
#: Warning thresholds drawn on the RSSI figure (the SSD and ESD defaults).


def _col(frame: pd.DataFrame, name: str) -> np.ndarray:
    if name not in frame.columns:
        return np.zeros(len(frame))
    return pd.to_numeric(frame[name], errors="coerce").fillna(0.0).to_numpy(dtype=float)


def time_components(runs: pd.DataFrame) -> pd.DataFrame:
    """Per run (team totals, s): the stacked-bar components of :data:`TIME_COMPONENTS`."""
    # Runs with LF's roles (lf, lf-wait, plugins built on LF) have NA movement recorded.
    if "na_movement_time" in runs:
        is_lf = runs["na_movement_time"].notna().to_numpy()
    else:
        is_lf = np.zeros(len(runs), dtype=bool)
    total = _col(runs, "total_movement_time")
    na, lead, fol = (
        _col(runs, "na_movement_time"),
        _col(runs, "leader_movement_time"),
        _col(runs, "follower_movement_time"),
    )
    values = {
        "movement (NB) / NA movement": np.where(is_lf, na, total),
        "leader movement": np.where(is_lf, lead, 0.0),
        "follower movement": np.where(is_lf, fol, 0.0),
        "other movement (regrouping)": np.where(
            is_lf, np.clip(total - na - lead - fol, 0, None), 0.0
        ),
        "leader disconnect": _col(runs, "leader_disconnect_time"),
        "follower waiting": _col(runs, "follower_waiting_time"),
        "delay": _col(runs, "delay_time"),
        "idle": _col(runs, "idle_time"),
        "role assignment": _col(runs, "role_assignment_time"),
        "switching": _col(runs, "switching_time"),
    }
    out = runs[["run_id", "scenario", "network", "threshold", "behaviour", "spl"]].copy()
    if "setting" in runs:
        out["setting"] = runs["setting"].to_numpy()
    for name, vals in values.items():
        out[name] = vals
    return out


def stacked_time_figure(runs: pd.DataFrame) -> Figure:
    """Mean team time per component, stacked, per configuration (bars: SPL × behaviour)."""
    runs = usable_runs(runs)
    comps = time_components(runs)
    keys = panel_keys(runs)
    multi = len({k[0] for k in keys}) > 1
    levels = spl_levels(runs)
    behs = behaviours(runs)
    fig, axes = panel_grid(len(keys), width=5.0, height=3.8)
    offsets, width = _bar_offsets(len(behs), 0.84)
    for ax, key in zip(axes.flat, keys, strict=False):
        frame = in_panel(comps, key)
        ticks, labels = [], []
        for off, beh in zip(offsets, behs, strict=True):
            for i, spl in enumerate(levels):
                sub = frame[(frame["behaviour"] == beh) & (frame["spl"] == spl)]
                if sub.empty:
                    continue
                bottom = 0.0
                for name, colour in TIME_COMPONENTS:
                    height = float(sub[name].mean())
                    if height > 0:
                        ax.bar(i + off, height, width * 0.92, bottom=bottom, color=colour)
                        bottom += height
                ticks.append(i + off)
                labels.append(f"{beh.upper()}\n{spl:g}")
        ax.set_xticks(ticks, labels, fontsize=7)
        ax.set_xlabel("behaviour / SPL (%)")
        ax.set_ylabel("team time, mean per run (s)")
        ax.set_title(panel_title(key, multi))
        ax.grid(axis="y", alpha=0.3)
    _hide_unused(axes, len(keys))
    handles = [Patch(color=c, label=n) for n, c in TIME_COMPONENTS]
    fig.legend(
        handles=handles, loc="outside lower center", ncols=min(5, max(2, len(keys) * 2)), fontsize=8
    )
    fig.suptitle("Where the team's time went (stacked means)")
    return fig


def timeline_figure(
    intervals: pd.DataFrame,
    events: pd.DataFrame | None = None,
    title: str = "",
    tracks: Sequence[str] = ("activity", "role"),
) -> Figure:
    """Timeline chart of one run: one row per robot and track, intervals coloured by
    label; near collisions, task completions and disconnects as markers."""
    robots = sorted(set(intervals["robot"].astype(str)))
    present = [t for t in tracks if t in set(intervals["track"])]
    present += sorted(set(intervals["track"]) - set(present))
    rows = [(r, t) for r in robots for t in present]
    fig = Figure(figsize=(12, 0.5 * len(rows) + 1.8), layout="constrained")
    ax = fig.subplots()
    seen: dict[str, str] = {}
    for y, (robot, track) in enumerate(rows):
        sub = intervals[(intervals["robot"] == robot) & (intervals["track"] == track)]
        for label, group in sub.groupby("label"):
            colour = _label_colour(str(label), seen)
            spans = list(zip(group["t_start"], group["t_end"] - group["t_start"], strict=True))
            ax.broken_barh(spans, (y - 0.38, 0.76), facecolors=colour, edgecolor="none")
    if events is not None and not events.empty:
        row_of = {r: i for i, (r, t) in enumerate(rows) if t == present[0]}
        for label, (marker, colour) in EVENT_MARKERS.items():
            sub = events[(events["label"] == label) & events["robot"].isin(row_of)]
            if not sub.empty:
                ax.plot(
                    sub["t"],
                    sub["robot"].map(row_of),
                    marker,
                    color=colour,
                    mec="white" if marker == "v" else colour,
                    mew=0.8 if marker == "v" else 1.5,
                    ms=8,
                    ls="none",
                    label=label.replace("_", " "),
                )
    ax.set_yticks(range(len(rows)), [f"{r} · {t}" for r, t in rows])
    ax.invert_yaxis()
    ax.set_xlabel("time (s)")
    ax.grid(axis="x", alpha=0.3)
    handles = [Patch(color=c, label=lbl.replace("_", " ")) for lbl, c in seen.items()]
    marker_handles, _ = ax.get_legend_handles_labels()
    fig.legend(handles=handles + marker_handles, loc="outside lower center", ncols=8, fontsize=8)
    ax.set_title(title or "Timeline")
    return fig


def _label_colour(label: str, seen: dict[str, str]) -> str:
    if label not in seen:
        colour = LABEL_COLOURS.get(label)
        if colour is None:
            colour = matplotlib.colors.to_hex(_FALLBACK(len(seen) % 20))
        seen[label] = colour
    return seen[label]


def rssi_figure(
    rssi: pd.DataFrame,
    runs: pd.DataFrame,
    run_ids: Sequence[str],
    warnings: dict[str, float] | None = None,
) -> Figure:
    """RSSI of every robot pair over time, one panel per run (e.g. SSD next to ESD),
    with the run's warning level (``warnings``: run id -> dBm, as the run had it)."""
    warnings = warnings or {}
    info = runs.set_index("run_id")
    fig, axes = panel_grid(len(run_ids), width=6.0, height=3.6, ncols=min(len(run_ids), 2))
    for ax, run_id in zip(axes.flat, run_ids, strict=False):
        sub = rssi[rssi["run_id"] == run_id]
        # A link is measured both ways; one curve per unordered pair is what one reads.
        pairs = sub.assign(
            a=np.minimum(sub["src"].astype(str), sub["dst"].astype(str)),
            b=np.maximum(sub["src"].astype(str), sub["dst"].astype(str)),
        )
        pairs = pairs[pairs["src"].astype(str) == pairs["a"]]
        for (a, b), group in pairs.groupby(["a", "b"]):
            group = group.sort_values("t")
            ax.plot(group["t"], group["rssi"], lw=0.9, label=f"{a}–{b}")
        if run_id in warnings:
            ax.axhline(
                warnings[run_id],
                color="firebrick",
                ls="--",
                lw=1,
                label=f"warning {warnings[run_id]:g} dBm",
            )
        label = info.loc[run_id, "label"] if run_id in info.index else run_id
        ax.set_title(f"{label} ({run_id})", fontsize=10)
        ax.set_xlabel("time (s)")
        ax.set_ylabel("RSSI (dBm)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="lower right")
    _hide_unused(axes, len(run_ids))
    fig.suptitle("Signal strength over time")
    return fig
