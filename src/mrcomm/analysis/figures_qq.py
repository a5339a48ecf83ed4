"""Normal Q–Q plots of a metric: one panel per configuration group (network, threshold,
behaviour), one series per SPL level. Each sample is standardised (z-scores, ddof=1)
so that every level shares the y = x reference line: points on it mean the sample
looks normal (the Shapiro–Wilk table gives the test)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")  # figures are files; never open a window
import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from scipy import stats as sps

from mrcomm.analysis.figures import (
    behaviours,
    in_panel,
    panel_grid,
    panel_keys,
    panel_title,
    spl_levels,
)
from mrcomm.analysis.stats import metric_info, usable_runs

_SPL_COLOURS = matplotlib.colormaps["viridis"]
_MARKERS = ("o", "s", "^", "D", "v", "P")


def qq_points(sample: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(theoretical normal quantiles, standardised ordered sample); empty when the
    sample has fewer than 3 values or no spread."""
    x = np.asarray(sample, dtype=float)
    x = x[np.isfinite(x)]
    if len(x) < 3 or np.ptp(x) == 0.0:
        return np.empty(0), np.empty(0)
    (theoretical, ordered), _ = sps.probplot(x, dist="norm")
    return theoretical, (ordered - x.mean()) / x.std(ddof=1)


def qq_figure(runs: pd.DataFrame, metric: str) -> Figure:
    """Q–Q plots of ``metric`` for every configuration group and SPL level."""
    info = metric_info(metric)
    runs = usable_runs(runs)
    keys = panel_keys(runs)
    multi = len({k[0] for k in keys}) > 1
    groups = [(k, b) for k in keys for b in behaviours(runs)]
    levels = spl_levels(runs)
    fig, axes = panel_grid(len(groups), width=3.0, height=2.8)
    used = 0
    for key, beh in groups:
        frame = in_panel(runs, key)
        frame = frame[frame["behaviour"] == beh]
        values = pd.to_numeric(frame[metric], errors="coerce") if metric in frame else None
        if frame.empty or values is None or values.notna().sum() == 0:
            continue
        ax = axes.flat[used]
        used += 1
        for i, spl in enumerate(levels):
            sample = values[frame["spl"] == spl].dropna().to_numpy(dtype=float)
            theo, z = qq_points(sample)
            if len(theo):
                colour = _SPL_COLOURS(i / max(len(levels) - 1, 1) * 0.9)
                marker = _MARKERS[i % len(_MARKERS)]  # overlapping levels stay distinguishable
                ax.plot(theo, z, marker, ms=3.5, color=colour, alpha=0.8, label=f"SPL{spl:g}")
            elif len(sample):
                # Nothing to standardise (all equal, or too few): say so in the legend.
                why = "all equal" if len(sample) > 1 and np.ptp(sample) == 0 else "too few"
                ax.plot([], [], " ", label=f"SPL{spl:g}: {why}, not drawn")
        ax.axline((0, 0), slope=1, color="grey", lw=0.8, ls="--")
        ax.set_title(f"{panel_title(key, multi)} · {beh.upper()}", fontsize=9)
        ax.set_xlabel("normal quantile", fontsize=8)
        ax.set_ylabel("standardised value", fontsize=8)
        ax.tick_params(labelsize=7)
        if ax.get_legend_handles_labels()[0]:  # samples too small to plot have no series
            ax.legend(fontsize=6, loc="upper left")
    for ax in axes.flat[used:]:
        ax.set_visible(False)
    fig.suptitle(f"Normal Q–Q plots: {info.label}")
    return fig
