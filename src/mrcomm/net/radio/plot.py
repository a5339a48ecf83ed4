"""The figure of a radio profile, for a paper: expected delivery ratio and mean received
power against distance, in line of sight and through 1, 2 and 3 walls, and — given a
map — a heat map of the received power from one transmitter (path loss, the walls the
ray crosses, and the shadowing field of one seed). matplotlib is imported only here."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from mrcomm.fileio import atomic_write
from mrcomm.net.radio.model import RadioNetwork, RadioParams, delivery_ratio, mean_power_dbm
from mrcomm.net.radio.profile import RadioProfile
from mrcomm.world.occupancy import OccupancyGrid

WALL_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728")
#: Spacing of the heat map's samples, m.
HEAT_SPACING_M = 0.25


def power_map(
    network: RadioNetwork, grid: OccupancyGrid, source: tuple[float, float]
) -> tuple[np.ndarray, tuple[float, float, float, float]]:
    """Received power (dBm) at every free sample point of the map from a transmitter at
    ``source``: mean power through the walls crossed, plus the run's shadowing (NaN on
    occupied cells)."""
    xmin, xmax, ymin, ymax = grid.extent
    xs = np.arange(xmin + HEAT_SPACING_M / 2, xmax, HEAT_SPACING_M)
    ys = np.arange(ymin + HEAT_SPACING_M / 2, ymax, HEAT_SPACING_M)
    sx, sy = source
    out = np.full((len(ys), len(xs)), np.nan)
    for i, y in enumerate(ys.tolist()):
        for j, x in enumerate(xs.tolist()):
            if not grid.is_free(x, y):
                continue
            d = float(np.hypot(x - sx, y - sy))
            walls = grid.walls_between(sx, sy, x, y)
            out[i, j] = float(mean_power_dbm(network.profile, d, walls)) + network.field.link(
                sx, sy, x, y
            )
    return out, (xmin, xmax, ymin, ymax)


def plot_profile(
    profile: RadioProfile,
    out: str | Path,
    fmt: str,
    *,
    message_bytes: int,
    grid: OccupancyGrid | None = None,
    source: tuple[float, float] | None = None,
    seed: int = 1,
    max_distance: float = 80.0,
) -> None:
    """Draw the profile (and the heat map when ``grid`` and ``source`` are given),
    written atomically as ``fmt`` (png, svg or pdf)."""
    from matplotlib.figure import Figure  # heavy import, only needed here

    panels = 3 if grid is not None and source is not None else 2
    fig = Figure(figsize=(4.4 * panels, 3.8), layout="constrained")
    axes: Sequence = fig.subplots(1, panels, squeeze=True)
    distance = np.linspace(0.5, max_distance, 400)
    for walls, colour in enumerate(WALL_COLOURS):
        label = "line of sight" if walls == 0 else f"{walls} wall{'s' * (walls > 1)}"
        axes[0].plot(
            distance,
            delivery_ratio(profile, distance, walls, message_bytes),
            color=colour,
            label=label,
        )
        axes[1].plot(distance, mean_power_dbm(profile, distance, walls), color=colour, label=label)
    los = mean_power_dbm(profile, distance, 0)
    sigma = profile.shadowing_sigma_db
    axes[1].fill_between(distance, los - sigma, los + sigma, color=WALL_COLOURS[0], alpha=0.15,
                         lw=0, label=f"line of sight ± σ ({sigma:g} dB)")  # fmt: skip
    axes[1].axhline(profile.sensitivity_dbm, color="0.3", ls=":", lw=1,
                    label=f"sensitivity {profile.sensitivity_dbm:g} dBm")  # fmt: skip
    axes[0].set_ylabel(f"expected delivery ratio ({message_bytes}-byte message)")
    axes[0].set_ylim(-0.02, 1.02)
    axes[1].set_ylabel("mean received power (dBm)")
    for ax in axes[:2]:
        ax.set_xlabel("distance between robots (m)")
        ax.set_xlim(0, max_distance)
        ax.grid(True, lw=0.4, alpha=0.5)
        ax.legend(fontsize=7)
    axes[0].set_title("Delivery (averaged over shadowing)")
    axes[1].set_title("Path loss and walls")
    if panels == 3 and grid is not None and source is not None:
        network = RadioNetwork(
            RadioParams.model_validate({}), profile=profile, extent=grid.extent, seed=seed
        )
        power, extent = power_map(network, grid, source)
        ax = axes[2]
        ax.imshow(grid.occupied, origin="lower", extent=grid.extent, cmap="Greys",
                  vmin=0, vmax=1.4, interpolation="nearest")  # fmt: skip
        # Below the sensitivity nothing is received: those points stay uncoloured.
        shown = np.where(power >= profile.sensitivity_dbm, power, np.nan)
        image = ax.imshow(shown, origin="lower", extent=extent, cmap="viridis",
                          vmin=profile.sensitivity_dbm, interpolation="nearest")  # fmt: skip
        ax.plot([source[0]], [source[1]], marker="*", color="red", ms=12, mec="white")
        fig.colorbar(image, ax=ax, label="received power (dBm; blank: out of range)", shrink=0.85)
        ax.set_title(f"Power from the ★ (shadowing seed {seed})")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_aspect("equal")
    fig.suptitle(f"Radio profile {profile.name}")
    atomic_write(out, lambda tmp: fig.savefig(tmp, format=fmt, dpi=300))


def validation_figure(result: Any, name: str, out: str | Path, fmt: str) -> None:
    """Predicted against measured mean power of a validation's held-out readings
    (:mod:`mrcomm.net.radio.validate`), one panel a model, line of sight and obstructed
    marked apart, each panel titled with its RMSE; written atomically as ``fmt``."""
    from matplotlib.figure import Figure

    from mrcomm.net.radio.validate import MODELS

    fig = Figure(figsize=(4.2 * len(MODELS), 4.2), layout="constrained")
    axes: Sequence = fig.subplots(1, len(MODELS), squeeze=True, sharex=True, sharey=True)
    measured, walls = result.measured, result.walls
    values = np.concatenate([measured, *result.predicted.values()])
    low = float(np.floor(values.min() / 5) * 5) - 2.0
    high = float(np.ceil(values.max() / 5) * 5) + 2.0
    for ax, model in zip(axes, MODELS, strict=True):
        predicted = result.predicted[model]
        ax.plot([low, high], [low, high], color="0.5", lw=0.8)
        for obstructed, colour, label in ((False, WALL_COLOURS[0], "line of sight"),
                                          (True, WALL_COLOURS[1], "obstructed")):  # fmt: skip
            mask = (walls > 0) == obstructed
            if mask.any():
                ax.scatter(measured[mask], predicted[mask], s=10, color=colour, alpha=0.7,
                           label=f"{label} ({int(mask.sum())})", edgecolor="none")  # fmt: skip
        rmse = result.row(model, "all").rmse_db
        ax.set_title(f"{model}: RMSE {rmse:.1f} dB")
        ax.set_xlabel("measured mean power (dBm)")
        ax.set_xlim(low, high)
        ax.set_ylim(low, high)
        ax.set_aspect("equal")
        ax.grid(True, lw=0.4, alpha=0.5)
        ax.legend(fontsize=7, loc="upper left")
    axes[0].set_ylabel("predicted mean power (dBm)")
    fig.suptitle(f"{name}: held-out readings")
    atomic_write(out, lambda tmp: fig.savefig(tmp, format=fmt, dpi=300))
