"""The study figures draw what the data says: bar heights are the means (error bars the
sample SD), success bars the percentages, stacked bars sum to the components, the
timeline has one bar per interval, Q–Q points are the standardised sample; and each
figure renders as PNG and SVG from a real swept database."""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd
import pytest
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from mrcomm.analysis import encoding as E
from mrcomm.analysis import figures as F
from mrcomm.analysis import figures_qq as FQ
from mrcomm.analysis import figures_time as FT


def synthetic_runs() -> pd.DataFrame:
    """Two panels (WLAN+SLT, AH+SSD), NB and LF, SPL 0 and 50, 3 runs each."""
    rows = []
    rng = np.random.default_rng(7)
    for network, threshold in (("wlan", "slt"), ("ah", "ssd")):
        for behaviour in ("nb", "lf"):
            for spl in (0.0, 50.0):
                for rep in range(3):
                    lf = behaviour == "lf"
                    rows.append(
                        {
                            "run_id": f"{network}-{threshold}-{behaviour}-{spl:g}-r{rep}",
                            "label": f"{network}_{behaviour}_{spl:g}",
                            "scenario": "S1",
                            "network": network,
                            "threshold": threshold,
                            "behaviour": behaviour,
                            "spl": spl,
                            "repetition": rep,
                            "status": "ok",
                            "successful": rep < (2 if spl else 3),
                            "execution_phase_time": 100 + spl + 10 * rep + (50 if lf else 0),
                            "total_movement_time": 300.0 + rep,
                            "na_movement_time": 100.0 if lf else None,
                            "leader_movement_time": 80.0 if lf else None,
                            "follower_movement_time": 90.0 + rep if lf else None,
                            "leader_disconnect_time": 5.0 if lf else None,
                            "delay_time": float(rng.integers(0, 10)),
                            "idle_time": 20.0,
                            "min_separation": 0.5,
                            "max_separation": 6.0 if lf else 25.0,
                        }
                    )
    return pd.DataFrame(rows)


def bars(ax: Any) -> list[Rectangle]:
    return [p for p in ax.patches if isinstance(p, Rectangle)]


def test_metric_bars_are_means_with_sd_error_bars() -> None:
    runs = synthetic_runs()
    fig = F.metric_bars(runs, "execution_phase_time")
    axes = [ax for ax in fig.axes if ax.get_visible()]
    assert [ax.get_title() for ax in axes] == [  # the original's order; bars above boxes
        "WLAN + SLT · mean ± SD",
        "AH + SSD · mean ± SD",
        "WLAN + SLT · box plot",
        "AH + SSD · box plot",
    ]
    heights = sorted(b.get_height() for b in bars(axes[0]))
    sub = runs[runs["network"] == "wlan"]
    expected = sub.groupby(["behaviour", "spl"])["execution_phase_time"].mean()
    assert heights == pytest.approx(sorted(expected))
    # Error bars: vertical segments of length 2 SD (sample SD, ddof=1 -> 10 here).
    segments = [
        seg
        for coll in axes[0].collections
        for seg in coll.get_segments()  # type: ignore[attr-defined]
    ]
    lengths = {round(abs(s[1][1] - s[0][1]), 6) for s in segments}
    assert lengths == {20.0}
    # The box plots' medians are the samples' medians.
    medians = sorted(
        float(line.get_ydata()[0])  # type: ignore[index]
        for line in axes[2].lines
        if line.get_gid() == "median"
    )
    expected_medians = sub.groupby(["behaviour", "spl"])["execution_phase_time"].median()
    assert medians == pytest.approx(sorted(expected_medians))


def test_a_metric_a_behaviour_lacks_is_not_drawn_as_zero() -> None:
    fig = F.metric_bars(synthetic_runs(), "leader_movement_time")  # LF only
    top = fig.axes[0]
    # Only LF's bars (2 SPL levels), none of height 0 for NB.
    assert sorted(b.get_height() for b in bars(top)) == [80.0, 80.0]
    assert [t.get_text() for t in fig.legends[0].get_texts()] == ["LF"]


def test_success_bars_are_percentages() -> None:
    fig = F.success_figure(synthetic_runs())
    heights = sorted({round(b.get_height(), 4) for b in bars(fig.axes[0])})
    assert heights == [pytest.approx(200 / 3, abs=1e-3), 100.0]
    labels = {t.get_text() for t in fig.axes[0].texts}
    assert labels == {"3/3", "2/3"}


def test_separation_and_failed_tasks() -> None:
    runs = synthetic_runs()
    fig = F.separation_figure(runs)

    def ys(ax: Any) -> set[float]:
        return {round(float(y), 3) for line in ax.lines for y in line.get_ydata()}

    wlan_slt, ah_ssd = fig.axes[0], fig.axes[1]
    assert {0.5, 6.0, 25.0, 4.0} <= ys(wlan_slt) and 8.0 not in ys(wlan_slt)  # SLT warning
    assert {0.5, 6.0, 25.0, 8.0} <= ys(ah_ssd) and 4.0 not in ys(ah_ssd)  # AH range
    legend = {t.get_text() for t in fig.legends[0].get_texts()}
    assert legend == {"NB", "LF", "4 m SLT warning", "8 m AH limit"}
    failed = pd.DataFrame(
        {
            "run_id": [runs["run_id"][0]] * 2 + [runs["run_id"][1]],
            "task_id": ["1", "4", "4"],
            "robot": ["robot_1", "robot_1", "robot_2"],
        }
    )
    table = F.failed_per_robot(runs, failed, ["robot_1", "robot_2", "robot_3"])
    row = table[(table["network"] == "wlan") & (table["behaviour"] == "nb") & (table["spl"] == 0)]
    assert dict(zip(row["robot"], row["failed"], strict=True)) == pytest.approx(
        {"robot_1": 2 / 3, "robot_2": 1 / 3, "robot_3": 0.0}
    )
    fig = F.failed_tasks_figure(runs, failed, ["robot_1", "robot_2", "robot_3"])
    assert len(fig.axes) == 4  # behaviours x panels
    assert max(b.get_height() for b in bars(fig.axes[0])) == pytest.approx(2 / 3)


def test_stacked_time_bars_sum_the_components() -> None:
    runs = synthetic_runs()
    comps = FT.time_components(runs)
    lf = comps[comps["behaviour"] == "lf"].iloc[0]
    assert lf["movement (NB) / NA movement"] == 100.0
    assert lf["other movement (regrouping)"] == pytest.approx(300.0 - 100 - 80 - 90)
    nb = comps[comps["behaviour"] == "nb"].iloc[0]
    assert nb["movement (NB) / NA movement"] == 300.0 and nb["leader movement"] == 0.0
    fig = FT.stacked_time_figure(runs)
    ax = fig.axes[0]
    tops: dict[float, float] = {}
    for b in bars(ax):
        x = round(b.get_x() + b.get_width() / 2, 6)
        tops[x] = max(tops.get(x, 0.0), b.get_y() + b.get_height())
    names = [n for n, _ in FT.TIME_COMPONENTS]
    sub = comps[comps["network"] == "wlan"]
    totals = sub.groupby(["behaviour", "spl"])[names].mean().sum(axis=1)
    assert sorted(tops.values()) == pytest.approx(sorted(totals))


def test_timeline_draws_every_interval_and_event() -> None:
    intervals = pd.DataFrame(
        [
            ("r", "robot_1", "activity", "moving", 0.0, 5.0),
            ("r", "robot_1", "activity", "idle", 5.0, 9.0),
            ("r", "robot_1", "role", "na", 0.0, 9.0),
            ("r", "robot_2", "activity", "moving", 0.0, 9.0),
            ("r", "robot_2", "activity", "odd_label", 9.0, 9.5),
        ],
        columns=["run_id", "robot", "track", "label", "t_start", "t_end"],
    )
    events = pd.DataFrame(
        [("r", "robot_1", 3.0, "near_collision", "{}"), ("r", "robot_2", 4.0, "other", "{}")],
        columns=["run_id", "robot", "t", "label", "data"],
    )
    fig = FT.timeline_figure(intervals, events, "title")
    ax = fig.axes[0]
    spans = [p for c in ax.collections if isinstance(c, PolyCollection) for p in c.get_paths()]
    assert len(spans) == len(intervals)
    ticks = [t.get_text() for t in ax.get_yticklabels()]
    assert ticks == ["robot_1 · activity", "robot_1 · role", "robot_2 · activity", "robot_2 · role"]
    marks = [line for line in ax.lines if line.get_marker() == "x"]
    assert len(marks) == 1 and list(marks[0].get_xdata()) == [3.0]
    legend = {t.get_text() for t in fig.legends[0].get_texts()}
    assert {"moving", "idle", "na", "odd label", "near collision"} <= legend


def test_qq_points_are_standardised_order_statistics() -> None:
    sample = np.array([3.0, 1.0, 2.0, 10.0, 4.0])
    theo, z = FQ.qq_points(sample)
    assert np.all(np.diff(theo) > 0) and np.all(np.diff(z) >= 0)
    assert z == pytest.approx((np.sort(sample) - sample.mean()) / sample.std(ddof=1))
    assert len(FQ.qq_points(np.array([2.0, 2.0, 2.0]))[0]) == 0
    fig = FQ.qq_figure(synthetic_runs(), "execution_phase_time")
    visible = [ax for ax in fig.axes if ax.get_visible()]
    assert len(visible) == 4  # 2 panels x 2 behaviours
    series = [line for line in visible[0].lines if str(line.get_label()).startswith("SPL")]
    assert [line.get_label() for line in series] == ["SPL0", "SPL50"]
    assert sum(len(line.get_xdata()) for line in series) == 6


def test_rssi_figure_one_curve_per_pair_with_warning() -> None:
    runs = pd.DataFrame(
        {"run_id": ["a", "b"], "label": ["SSD", "ESD"], "threshold": ["ssd", "esd"]}
    )
    t = np.arange(0, 5, 0.5)
    rows = [
        (rid, ti, s, d, -40.0 - ti)
        for rid in ("a", "b")
        for ti in t
        for s, d in (("robot_1", "robot_2"), ("robot_2", "robot_1"))
    ]
    rssi = pd.DataFrame(rows, columns=["run_id", "t", "src", "dst", "rssi"])
    fig = FT.rssi_figure(rssi, runs, ["a", "b"], {"a": -42.0, "b": -41.0})
    first, second = fig.axes[0], fig.axes[1]
    curves = [line for line in first.lines if len(line.get_xdata()) > 2]
    assert len(curves) == 1 and len(curves[0].get_xdata()) == len(t)
    assert [line.get_ydata()[0] for line in first.lines if len(line.get_xdata()) == 2] == [-42.0]
    assert [line.get_ydata()[0] for line in second.lines if len(line.get_xdata()) == 2] == [-41.0]


def test_warning_levels_are_each_runs_own() -> None:
    """A run's warning line is the level it ran with: a parameter of its configuration,
    else its threshold's default; thresholds without an RSSI level have none."""
    from mrcomm.analysis.figures_report import warning_levels

    runs = pd.DataFrame(
        {
            "run_id": ["r1", "r2", "r3"],
            "config_id": ["c1", "c2", "c3"],
            "threshold": ["esd", "ssd", "slt"],
        }
    )
    configs = pd.DataFrame(
        {
            "config_id": ["c1", "c2", "c3"],
            "options": [
                '{"params": {"threshold": {"warning_dbm": -70.0}}}',
                '{"params": {}}',
                '{"params": {"threshold": {"warning_m": 3.0}}}',
            ],
        }
    )
    assert warning_levels(runs, configs) == {"r1": -70.0, "r2": -42.0}


def test_figures_of_a_real_study_render(study: Any, tmp_path: Any) -> None:
    runs = study.runs
    figures: dict[str, Figure] = {
        "bars": F.metric_bars(runs, "total_distance"),
        "success": F.success_figure(runs),
        "separation": F.separation_figure(runs),
        "failed": F.failed_tasks_figure(runs, study.failed_tasks),
        "stacked": FT.stacked_time_figure(runs),
        "qq": FQ.qq_figure(runs, "execution_phase_time"),
    }
    run_id = runs.loc[runs["behaviour"] == "lf", "run_id"].iloc[0]
    iv = study.intervals[study.intervals["run_id"] == run_id]
    assert not iv.empty
    figures["timeline"] = FT.timeline_figure(iv, study.events[study.events["run_id"] == run_id])
    for name, fig in figures.items():
        png = E.render(fig, "png")
        assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 5_000, name
        (tmp_path / f"{name}.png").write_bytes(png)
    svg = E.render(figures["bars"], "svg")
    assert b"<svg" in svg[:400]
    # The bars of the real study are its per-configuration means.
    heights = sorted(b.get_height() for b in bars(figures["bars"].axes[0]))
    means = runs.groupby(["behaviour", "spl"])["total_distance"].mean()
    assert heights == pytest.approx(sorted(means), rel=1e-9)


def test_rssi_of_a_real_ssd_mission(s1_resources: Any) -> None:
    from tests.analysis.fixture_data import run_study
    from tests.conftest import S1_PATH

    frames = run_study(
        s1_resources, S1_PATH, reps=1, threshold="ssd", spls=(0,), behaviours=("lf",), max_time=120
    )
    run_id = str(frames.runs["run_id"].iloc[0])
    assert not frames.rssi.empty
    from mrcomm.analysis.figures_report import warning_levels

    levels = warning_levels(frames.runs, frames.configs)
    assert levels == {run_id: -42.0}
    fig = FT.rssi_figure(frames.rssi, frames.runs, [run_id], levels)
    ax = fig.axes[0]
    curves = [line for line in ax.lines if len(line.get_xdata()) > 2]
    assert len(curves) == 3  # robot pairs of a team of three, one curve each
    assert all(max(c.get_xdata()) <= 120.0 + 1e-9 for c in curves)
    assert [line.get_ydata()[0] for line in ax.lines if len(line.get_xdata()) == 2] == [-42.0]
    assert E.render(fig)[:4] == b"\x89PNG"
