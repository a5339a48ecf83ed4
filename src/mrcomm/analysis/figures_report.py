"""The figure set of a study report: which runs get a timeline and an RSSI figure, and
every figure of the report drawn and encoded (PNG, optionally SVG), by section."""

from __future__ import annotations

import base64
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import pandas as pd
from matplotlib.figure import Figure

from mrcomm.analysis import figures as fig_mod
from mrcomm.analysis import figures_qq, figures_time
from mrcomm.analysis import stats as st
from mrcomm.errors import InputError, did_you_mean

#: Timelines drawn when the caller names none: one per behaviour.
MAX_DEFAULT_TIMELINES = 2


@dataclass
class ReportFigure:
    id: str
    title: str
    caption: str
    png: bytes
    svg: bytes | None
    metric: str = ""  # the metric a per-metric figure shows

    @property
    def data_uri(self) -> str:
        return "data:image/png;base64," + base64.b64encode(self.png).decode("ascii")


def frame_of(data: Any, name: str) -> pd.DataFrame:
    frame = getattr(data, name, None)
    return frame if isinstance(frame, pd.DataFrame) else pd.DataFrame()


def metrics_with_data(runs: pd.DataFrame, names: Sequence[str] | None = None) -> list[str]:
    """Metrics (of ``names``, default all) with at least one value in usable runs."""
    runs = st.usable_runs(runs)
    return [
        m.name
        for m in st.resolve_metrics(names)
        if m.name in runs.columns and pd.to_numeric(runs[m.name], errors="coerce").notna().any()
    ]


def pick_timeline_runs(runs: pd.DataFrame, wanted: Sequence[str] | None) -> list[str]:
    """The runs whose timeline is drawn: those asked for (checked), else the first
    repetition at the highest SPL of the first panel, one per behaviour."""
    ok = st.usable_runs(runs)
    if wanted:
        known = set(runs["run_id"])
        for run_id in wanted:
            if run_id not in known:
                hint = did_you_mean(run_id, known)
                raise InputError(f"no run {run_id!r} in the database{hint}", field="--timeline")
        return list(wanted)
    keys = fig_mod.panel_keys(ok)
    if not keys:
        return []
    first = ok[(ok["scenario"] == keys[0][0]) & (ok["network"] == keys[0][1])]
    first = first[first["threshold"] == keys[0][2]]
    chosen = []
    for beh in fig_mod.behaviours(first)[:MAX_DEFAULT_TIMELINES]:
        sub = first[first["behaviour"] == beh].sort_values(
            ["spl", "repetition"], ascending=[False, True]
        )
        chosen.append(str(sub["run_id"].iloc[0]))
    return chosen


def pick_rssi_runs(runs: pd.DataFrame, rssi: pd.DataFrame) -> list[str]:
    """An ESD run and its SSD counterpart (same SPL, behaviour, repetition) when both
    exist; otherwise the first run with RSSI samples."""
    if rssi.empty:
        return []
    have = runs[runs["run_id"].isin(set(rssi["run_id"]))].sort_values("run_id")
    esd, ssd = have[have["threshold"] == "esd"], have[have["threshold"] == "ssd"]
    if not esd.empty and not ssd.empty:
        e = esd.iloc[0]
        match = ssd[(ssd["spl"] == e["spl"]) & (ssd["behaviour"] == e["behaviour"])]
        same = match[match["repetition"] == e["repetition"]]
        s = (same if not same.empty else match if not match.empty else ssd).iloc[0]
        return [str(s["run_id"]), str(e["run_id"])]
    return [str(have["run_id"].iloc[0])] if not have.empty else []


def _figure(
    fid: str, title: str, caption: str, fig: Figure, svg: bool, metric: str = ""
) -> ReportFigure:
    png = fig_mod.render(fig, "png")
    # The layout is settled by the first render; freezing it makes the SVG render cheaper.
    fig.set_layout_engine("none")
    svg_bytes = fig_mod.render(fig, "svg") if svg else None
    return ReportFigure(fid, title, caption, png, svg_bytes, metric)


def build_figures(
    data: Any, metrics: Sequence[str], timelines: Sequence[str], svg: bool = True
) -> dict[str, list[ReportFigure]]:
    """Every figure of the report, by section."""
    runs = frame_of(data, "runs")
    out: dict[str, list[ReportFigure]] = {
        "success": [],
        "metrics": [],
        "time": [],
        "qq": [],
        "timelines": [],
        "rssi": [],
    }
    out["success"].append(
        _figure(
            "success",
            "Successful missions",
            "Percentage of successful missions (label: successful/runs).",
            fig_mod.success_figure(runs),
            svg,
        )
    )
    for name in metrics:
        info = st.METRICS[name]
        out["metrics"].append(
            _figure(
                f"metric_{name}",
                info.label,
                f"{info.label} ({info.unit}): mean ± SD per configuration.",
                fig_mod.metric_bars(runs, name),
                svg,
                name,
            )
        )
    out["time"].append(
        _figure(
            "time_breakdown",
            "Where the time went",
            "Team time per component, mean per run, stacked.",
            figures_time.stacked_time_figure(runs),
            svg,
        )
    )
    out["time"].append(
        _figure(
            "separation",
            "Minimum and maximum separation",
            "Closest and furthest team mate over the run, mean ± SD.",
            fig_mod.separation_figure(runs),
            svg,
        )
    )
    failed = frame_of(data, "failed_tasks")
    robot_metrics = frame_of(data, "robot_metrics")
    robots = sorted(set(robot_metrics["robot"].astype(str))) if not robot_metrics.empty else None
    if not failed.empty or robots:
        failed = (
            failed if not failed.empty else pd.DataFrame(columns=["run_id", "task_id", "robot"])
        )
        out["time"].append(
            _figure(
                "failed_per_robot",
                "Failed tasks per robot",
                "Tasks whose status never reached the assigner, mean per run.",
                fig_mod.failed_tasks_figure(runs, failed, robots),
                svg,
            )
        )
    for name in [m for m in st.CORE_METRICS if m in metrics]:
        out["qq"].append(
            _figure(
                f"qq_{name}",
                f"Q–Q: {st.METRICS[name].label}",
                "Standardised samples against normal quantiles.",
                figures_qq.qq_figure(runs, name),
                svg,
            )
        )
    intervals, events = frame_of(data, "intervals"), frame_of(data, "events")
    labels = runs.set_index("run_id")["label"].to_dict() if "label" in runs else {}
    for run_id in timelines:
        iv = intervals[intervals["run_id"] == run_id] if not intervals.empty else intervals
        if iv.empty:
            continue
        ev = events[events["run_id"] == run_id] if not events.empty else None
        title = f"{labels.get(run_id, '')} ({run_id})"
        out["timelines"].append(
            _figure(
                f"timeline_{run_id}",
                f"Timeline of {run_id}",
                "Every robot's labelled intervals and events.",
                figures_time.timeline_figure(iv, ev, title),
                svg,
            )
        )
    rssi = frame_of(data, "rssi")
    rssi_runs = pick_rssi_runs(runs, rssi)
    if rssi_runs:
        out["rssi"].append(
            _figure(
                "rssi",
                "Signal strength over time",
                "RSSI of every robot pair" + (" (SSD vs ESD)." if len(rssi_runs) > 1 else "."),
                figures_time.rssi_figure(rssi, runs, rssi_runs),
                svg,
            )
        )
    return out
