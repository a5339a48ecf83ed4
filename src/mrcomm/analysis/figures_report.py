"""The figure set of a study report: which runs get a timeline and an RSSI figure, and
every figure of the report drawn and encoded (PNG, optionally SVG and PDF), by section."""

from __future__ import annotations

import base64
import json
from collections.abc import Callable, Sequence
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Any

import pandas as pd
from matplotlib.figure import Figure

from mrcomm.analysis import figures as fig_mod
from mrcomm.analysis import figures_comm, figures_qq, figures_time
from mrcomm.analysis import stats as st
from mrcomm.analysis.encoding import Encoded, Encoder
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
    pdf: bytes | None = None

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


def constant_metrics(runs: pd.DataFrame, names: Sequence[str]) -> dict[str, float]:
    """The metrics of ``names`` with one and the same value in every usable run (a
    figure of them shows nothing): name -> that value."""
    runs = st.usable_runs(runs)
    out = {}
    for name in names:
        values = pd.to_numeric(runs[name], errors="coerce").dropna().unique()
        if len(values) == 1:
            out[name] = float(values[0])
    return out


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


@dataclass
class _Pending:
    """A figure handed to the encoder, with what the report says about it."""

    id: str
    title: str
    caption: str
    encoded: Future[Encoded]
    metric: str = ""

    def result(self) -> ReportFigure:
        files = self.encoded.result()
        return ReportFigure(
            self.id, self.title, self.caption, files.png, files.svg, self.metric, files.pdf
        )


def _figure(
    fid: str, title: str, caption: str, fig: Figure, encoder: Encoder, metric: str = ""
) -> _Pending:
    return _Pending(fid, title, caption, encoder.submit(fig), metric)


def build_figures(
    data: Any,
    metrics: Sequence[str],
    timelines: Sequence[str],
    svg: bool = True,
    jobs: int = 1,
    progress: Callable[[str], None] | None = None,
) -> dict[str, list[ReportFigure]]:
    """Every figure of the report, by section: PNG, and SVG and PDF when ``svg``, encoded
    in ``jobs`` processes while the next figures are drawn (``progress``: told how many
    are drawn and encoded)."""
    with Encoder(svg, jobs, progress) as encoder:
        pending = _draw_figures(data, metrics, timelines, encoder)
        return {section: [p.result() for p in items] for section, items in pending.items()}


def _draw_figures(
    data: Any, metrics: Sequence[str], timelines: Sequence[str], encoder: Encoder
) -> dict[str, list[_Pending]]:
    runs = frame_of(data, "runs")
    out: dict[str, list[_Pending]] = {
        "success": [],
        "metrics": [],
        "time": [],
        "qq": [],
        "timelines": [],
        "rssi": [],
        "comm": [],
        "links": [],
        "trajectories": [],
    }
    out["success"].append(
        _figure(
            "success",
            "Successful missions",
            "Percentage of successful missions (label: successful/runs).",
            fig_mod.success_figure(runs),
            encoder,
        )
    )
    constant = constant_metrics(runs, metrics)
    for name in metrics:
        if name in constant:
            continue  # the same value in every run: the report says so instead
        info = st.metric_info(name)
        out["metrics"].append(
            _figure(
                f"metric_{name}",
                info.label,
                f"{info.label} ({info.unit}) per configuration: mean ± SD (top, as the "
                "original study) and box plots (bottom: median, quartiles, whiskers to "
                "1.5 IQR), which show what the rank tests compare.",
                fig_mod.metric_bars(runs, name),
                encoder,
                name,
            )
        )
    _communication_figures(data, runs, timelines, encoder, out)
    out["time"].append(
        _figure(
            "time_breakdown",
            "Where the time went",
            "Team time per component, mean per run, stacked.",
            figures_time.stacked_time_figure(runs),
            encoder,
        )
    )
    out["time"].append(
        _figure(
            "separation",
            "Minimum and maximum separation",
            "Closest and furthest team mate over the run, mean ± SD.",
            fig_mod.separation_figure(runs),
            encoder,
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
                encoder,
            )
        )
    for name in [m for m in st.CORE_METRICS if m in metrics and m not in constant]:
        out["qq"].append(
            _figure(
                f"qq_{name}",
                f"Q–Q: {st.metric_info(name).label}",
                "Standardised samples against normal quantiles.",
                figures_qq.qq_figure(runs, name),
                encoder,
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
                encoder,
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
                figures_time.rssi_figure(
                    rssi, runs, rssi_runs, warning_levels(runs, frame_of(data, "configs"))
                ),
                encoder,
            )
        )
    return out


def _communication_figures(
    data: Any,
    runs: pd.DataFrame,
    timelines: Sequence[str],
    encoder: Encoder,
    out: dict[str, list[_Pending]],
) -> None:
    """Messages lost per topic and cause, AON, and for each timeline run its link
    states and trajectories (only the figures that have data)."""
    messages = frame_of(data, "messages")
    if not messages.empty:
        out["comm"].append(
            _figure(
                "messages_lost",
                "Messages lost by topic and cause",
                "Share of deliveries (one per receiver) that did not arrive, mean per run, "
                "per topic and cause (lost to SPL, out of range); bar label: the SPL level. "
                "A topic without bars lost nothing (e.g. topics exempt from SPL).",
                figures_comm.message_loss_figure(runs, messages),
                encoder,
            )
        )
    aon = figures_comm.aon_figure(runs)
    if aon is not None:
        out["comm"].append(
            _figure(
                "aon",
                "All-Or-Nothing messaging",
                "AON publications per run (top) and the time the slowest status took "
                "from its first publication until every member had it (bottom).",
                aon,
                encoder,
            )
        )
    link_states, trajectories = frame_of(data, "link_states"), frame_of(data, "trajectories")
    failed_tasks = frame_of(data, "failed_tasks")
    info = runs.set_index("run_id")
    scenarios = _scenarios(frame_of(data, "configs"))
    for run_id in timelines:
        if run_id not in info.index:
            continue
        row = info.loc[run_id]
        title = f"{row['label']} ({run_id})"
        robots = (
            sorted(set(trajectories.loc[trajectories["run_id"] == run_id, "robot"].astype(str)))
            if not trajectories.empty
            else []
        )
        if len(robots) >= 2 and not link_states.empty:
            out["links"].append(
                _figure(
                    f"links_{run_id}",
                    f"Link states of {run_id}",
                    "Each robot pair's link over the run: connected, in warning (the "
                    "threshold's), out of range (the worse of the two directions).",
                    figures_comm.link_state_figure(
                        link_states, run_id, float(row["sim_time_s"]), robots, title
                    ),
                    encoder,
                )
            )
        scenario = scenarios.get(str(row["config_id"]))
        if robots and scenario is not None:
            grid = scenario.grid
            tasks = [(t.task_id, t.x, t.y) for t in scenario.tasks]
            failed = (
                set(failed_tasks.loc[failed_tasks["run_id"] == run_id, "task_id"].astype(str))
                if not failed_tasks.empty
                else set()
            )
            out["trajectories"].append(
                _figure(
                    f"trajectory_{run_id}",
                    f"Trajectories of {run_id}",
                    "Every robot's path (sampled each second): start ○, end ■, tasks ★ "
                    "(crimson: its status never reached the assigner).",
                    figures_comm.trajectory_figure(
                        trajectories, run_id, grid.occupied, grid.extent, tasks, title, failed
                    ),
                    encoder,
                )
            )


def config_options(configs: pd.DataFrame) -> dict[str, dict[str, Any]]:
    """config_id -> its stored options (the run configuration as JSON; an unreadable
    one is left out)."""
    out: dict[str, dict[str, Any]] = {}
    for record in configs.to_dict("records"):
        try:
            out[str(record["config_id"])] = json.loads(str(record.get("options") or "{}"))
        except ValueError:
            continue
    return out


def warning_levels(runs: pd.DataFrame, configs: pd.DataFrame) -> dict[str, float]:
    """run id -> the RSSI warning level (dBm) its threshold had: the configuration's
    ``warning_dbm`` parameter, or the threshold's default (runs of thresholds without
    one are left out)."""
    from mrcomm.errors import InputError
    from mrcomm.net.signal_thresholds import EsdParams, esd_warning_dbm
    from mrcomm.specs import get_spec

    options = config_options(configs)
    levels: dict[str, float] = {}
    for run in runs[["run_id", "config_id", "threshold"]].to_dict("records"):
        stored = options.get(str(run["config_id"]), {})
        given = stored.get("params", {}).get("threshold", {})
        if "warning_dbm" in given:
            levels[str(run["run_id"])] = float(given["warning_dbm"])
            continue
        try:
            spec = get_spec("threshold", str(run["threshold"]))
            params = spec.make_params(given)
            if isinstance(params, EsdParams):  # its default follows the network
                network = str(stored.get("network", "wlan"))
                network_params = get_spec("network", network).make_params(
                    stored.get("params", {}).get("network", {})
                )
                levels[str(run["run_id"])] = esd_warning_dbm(params, network, network_params)
                continue
        except InputError:
            continue  # a variant of a plugin not installed here
        level = getattr(params, "warning_dbm", None)
        if level is not None:
            levels[str(run["run_id"])] = float(level)
    return levels


def _scenarios(configs: pd.DataFrame) -> dict[str, Any]:
    """config_id -> its scenario, loaded from the stored path (missing files skipped:
    the report then has no trajectory figure for it)."""
    from mrcomm.errors import InputError
    from mrcomm.world.scenario import load_scenario

    loaded: dict[str, Any] = {}
    out: dict[str, Any] = {}
    for config_id, options in config_options(configs).items():
        path = str(options.get("scenario", ""))
        if path and path not in loaded:
            try:
                loaded[path] = load_scenario(path)
            except (InputError, OSError):
                loaded[path] = None
        if loaded.get(path) is not None:
            out[config_id] = loaded[path]
    return out
