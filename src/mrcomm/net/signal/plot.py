"""Figure of a signal model: the calibration readings, their mean per distance, both
fitted curves (dashed where the model saturates beyond its trained range), the warning
threshold and where the curves cross it. matplotlib is imported only when plotting."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from mrcomm.errors import InputError
from mrcomm.fileio import atomic_write
from mrcomm.net.signal.calibration import Calibration
from mrcomm.net.signal.svr import SignalModel
from mrcomm.net.signal.table import RssiTable

FORMATS = ("png", "svg", "pdf")
_STYLE = {True: ("line of sight", "#1f77b4"), False: ("obstructed", "#d62728")}


def plot_format(out: str | Path) -> str:
    """The figure format from the file suffix, or an InputError."""
    suffix = Path(out).suffix.lower().lstrip(".")
    if suffix not in FORMATS:
        raise InputError(
            f"unsupported figure format {suffix or '(none)'!r}: use .png, .svg or .pdf",
            file=out,
            field="--out",
        )
    return suffix


def plot_model(
    model: SignalModel,
    out: str | Path,
    *,
    calibration: Calibration | None = None,
    threshold: float | None = None,
) -> None:
    """Draw the model (and optionally its calibration readings) to PNG, SVG or PDF,
    written atomically."""
    from matplotlib.figure import Figure  # heavy import, only needed here

    fmt = plot_format(out)
    thr = model.threshold_dbm if threshold is None else threshold
    table = RssiTable.from_model(model)
    top = max(model.line_of_sight.trained_range[1], model.obstructed.trained_range[1])
    x_max = top + 2.0
    fig = Figure(figsize=(6.4, 4.2), layout="constrained")
    ax = fig.add_subplot()
    for los in (True, False):
        name, colour = _STYLE[los]
        if calibration is not None:
            d, r = calibration.of_class(los)
            tag = " (synthetic)" if calibration.synthetic else ""
            ax.scatter(
                d, r, s=9, alpha=0.18, color=colour, linewidths=0, label=f"readings, {name}{tag}"
            )
            md, mr = calibration.means(los)
            ax.scatter(
                md,
                mr,
                s=28,
                marker="D",
                facecolors="white",
                edgecolors=colour,
                linewidths=1.2,
                zorder=3,
                label=f"mean per distance, {name}",
            )
        lo, hi = model.curve(los).trained_range
        inside = np.linspace(lo, hi, 400)
        ax.plot(
            inside,
            table.rssi(inside, np.full(inside.shape, los)),
            color=colour,
            linewidth=2,
            label=f"SVR model, {name}",
        )
        for seg in (np.linspace(0.0, lo, 20), np.linspace(hi, x_max, 50)):
            if seg[-1] > seg[0]:
                ax.plot(
                    seg,
                    table.rssi(seg, np.full(seg.shape, los)),
                    color=colour,
                    linewidth=1.2,
                    linestyle="--",
                )
        key = "line_of_sight" if los else "obstructed"
        for dist, _ in table.crossings(thr)[key]:
            ax.plot([dist], [thr], marker="o", color=colour, markersize=5, zorder=4)
    ax.axhline(thr, color="0.3", linewidth=1, linestyle=":", label=f"warning threshold {thr:g} dBm")
    ax.plot(
        [],
        [],
        color="0.4",
        linestyle="--",
        linewidth=1.2,
        label="saturated (outside trained range)",
    )
    ax.set_xlim(0.0, x_max)
    ax.set_xlabel("Distance between robots (m)")
    ax.set_ylabel("RSSI (dBm)")
    ax.grid(True, linewidth=0.4, alpha=0.5)
    ax.legend(fontsize=7, loc="upper right", framealpha=0.9)
    atomic_write(out, lambda tmp: fig.savefig(tmp, format=fmt, dpi=200))
