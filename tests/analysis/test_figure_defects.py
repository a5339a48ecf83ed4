"""The figure defects a user reported, each held: the separation figure's y label inside
the canvas and its markers by their SPL tick; failed tasks drawn distinctly in the
report's trajectory maps (as ``run --plot`` draws them) and "task (failed)" in a legend
only when a task failed; a box without spread in its behaviour's colour; a colour of its
own for every robot of any team; glossary headings without Markdown backticks."""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_hex

from mrcomm.analysis import figures as F
from mrcomm.analysis import figures_comm as FC
from mrcomm.analysis.glossary import glossary_sections
from mrcomm.analysis.mission_map import robot_colours
from tests.analysis.test_figures import synthetic_runs


def _inside_canvas(fig: Any, artist: Any) -> bool:
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    box = artist.get_window_extent(canvas.get_renderer())
    width, height = canvas.get_width_height()
    return box.x0 >= 0 and box.y0 >= 0 and box.x1 <= width and box.y1 <= height


def test_separation_label_in_the_canvas_and_markers_by_their_tick() -> None:
    runs = synthetic_runs()
    fig = F.separation_figure(runs)
    ax = fig.axes[0]
    assert _inside_canvas(fig, ax.yaxis.label)
    ticks = ax.get_xticks()
    xs = [float(x) for line in ax.lines for x in np.atleast_1d(line.get_xdata())]
    markers = [x for x in xs if np.isfinite(x) and -1 < x < len(ticks)]
    assert markers and all(min(abs(x - t) for t in ticks) <= 0.3 for x in markers)
    left, right = ax.get_xlim()
    assert (left, right) == (-0.5, len(ticks) - 0.5)  # a unit per level, whatever the data


def _tracks() -> pd.DataFrame:
    rows = [
        {"run_id": "r1", "robot": robot, "t": t, "x": 1.0 + t + k, "y": 2.0 + k}
        for k, robot in enumerate(["robot_1", "robot_2"])
        for t in range(5)
    ]
    return pd.DataFrame(rows)


def _star_colours(fig: Any) -> dict[tuple[float, float], str]:
    return {
        (float(line.get_xdata()[0]), float(line.get_ydata()[0])): to_hex(line.get_color())
        for line in fig.axes[0].lines
        if line.get_marker() == "*" and len(line.get_xdata())
    }


def _legend(fig: Any) -> set[str]:
    return {t.get_text() for t in fig.axes[0].get_legend().get_texts()}


def test_report_trajectories_draw_failed_tasks_distinctly() -> None:
    occupied = np.zeros((40, 40), dtype=bool)
    tasks = [("1", 3.0, 3.0), ("2", 8.0, 8.0)]
    fig = FC.trajectory_figure(_tracks(), "r1", occupied, (0, 20, 0, 20), tasks, "t", {"2"})
    stars = _star_colours(fig)
    assert stars[(3.0, 3.0)] != stars[(8.0, 8.0)]
    assert "task (failed)" in _legend(fig) and "task (communicated)" in _legend(fig)
    fig = FC.trajectory_figure(_tracks(), "r1", occupied, (0, 20, 0, 20), tasks, "t")
    assert len(set(_star_colours(fig).values())) == 1
    assert "task (failed)" not in _legend(fig)  # nothing failed: not in the legend


def test_run_plot_has_no_failed_legend_when_nothing_failed(
    tmp_path: Any, s1_resources: Any
) -> None:
    from matplotlib import pyplot as plt

    from mrcomm.analysis import mission_plot
    from mrcomm.run.config import make_config
    from mrcomm.sim.mission import run_mission

    config = make_config(None, scenario=s1_resources.scenario.path, network="wlan", seed=1)
    result = run_mission(config, s1_resources)
    assert result.mission["successful"]
    seen: list[set[str]] = []
    original = plt.Figure.savefig

    def keep(fig: Any, *args: Any, **kwargs: Any) -> None:
        seen.append({t.get_text() for t in fig.axes[0].get_legend().get_texts()})
        original(fig, *args, **kwargs)

    plt.Figure.savefig = keep  # type: ignore[method-assign]
    try:
        mission_plot.save_mission_plot(result, tmp_path / "s1.png")
    finally:
        plt.Figure.savefig = original  # type: ignore[method-assign]
    (legend,) = seen
    assert "task (failed)" not in legend and "task (communicated)" in legend


def test_a_box_without_spread_has_its_behaviour_colour() -> None:
    runs = synthetic_runs()  # min_separation is 0.5 in every run: no spread at all
    fig = F.metric_bars(runs, "min_separation")
    box_axes = [ax for ax in fig.axes if "box plot" in ax.get_title()]
    flat = [line for ax in box_axes for line in ax.lines if line.get_gid() == "median-flat"]
    assert {to_hex(line.get_color()) for line in flat} == {
        to_hex(F.behaviour_colour("nb")), to_hex(F.behaviour_colour("lf"))
    }  # fmt: skip


def test_every_robot_has_a_colour_of_its_own() -> None:
    for n in (3, 10, 11, 20, 21, 100, 1000, 10_000):
        colours = robot_colours(n)
        assert len(colours) == n == len(set(colours)), n
    assert robot_colours(3) == robot_colours(10)[:3]  # small teams look as before


def test_glossary_headings_have_no_markdown() -> None:
    titles = [str(s.title) for s in glossary_sections()]
    assert titles and not any("`" in t for t in titles)
    assert any("<code>behaviour.utility</code>" in t for t in titles)


def test_success_labels_do_not_overlap_with_five_behaviours() -> None:
    # The behaviours study's shape: 5 behaviours x 4 SPL levels x 10 runs ("10/10").
    base = synthetic_runs().iloc[0].to_dict()
    runs = pd.DataFrame([
        {**base, "run_id": f"{net}-{th}-{b}-{spl}-{k}", "network": net, "threshold": th,
         "behaviour": b, "spl": spl, "successful": True}
        for net in ("wlan", "ah") for th in ("slt", "ssd")  # four panels side by side
        for b in ("nb", "lf", "lf-wait", "rps", "serried")
        for spl in (0.0, 25.0, 50.0, 75.0)
        for k in range(10)
    ])  # fmt: skip
    fig = F.success_figure(runs)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    ax = fig.axes[0]
    boxes = [t.get_window_extent(renderer) for t in ax.texts if t.get_gid() == "success-label"]
    assert len(boxes) == 5 * 4  # behaviours x SPL levels
    for i, a in enumerate(boxes):
        for b in boxes[i + 1 :]:
            assert not a.overlaps(b), (a, b)
        assert a.y1 <= ax.get_window_extent(renderer).y1  # inside the axes
