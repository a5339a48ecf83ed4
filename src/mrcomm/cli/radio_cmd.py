"""``mrcomm radio``: the radio profiles of the ``radio`` network model.

* ``mrcomm radio list`` — the bundled profiles.
* ``mrcomm radio show [PROFILE] [--bytes N] [--json]`` — the profile's values, and
  mean received power and expected delivery ratio against distance in line of sight and
  through 1, 2 and 3 walls (as a table, or as JSON curves).
* ``mrcomm radio plot [PROFILE] --out FIG [--scenario S --from X,Y --seed N]`` — the
  same curves as a figure, and with a scenario a heat map of the received power from a
  point of its map.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any

import typer

from mrcomm.errors import InputError
from mrcomm.output_paths import FIGURE_SUFFIXES, check_output_file

radio_app = typer.Typer(
    help="Radio profiles of the radio network model: list, show, plot.",
    no_args_is_help=True,
    rich_markup_mode=None,
)

#: Distances of the table and the curves, m.
DISTANCES = (1.0, 2.0, 5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 40.0, 50.0, 60.0, 80.0)
WALLS = (0, 1, 2, 3)


def curves(profile_name: str, message_bytes: int) -> dict[str, Any]:
    """The profile and its curves, as plain data."""
    from mrcomm.net.radio.model import delivery_ratio, mean_power_dbm, reach_m
    from mrcomm.net.radio.profile import load_profile, profile_path

    profile = load_profile(profile_name)
    return {
        "profile": profile.model_dump(),
        "file": str(profile_path(profile_name)),
        "message_bytes": message_bytes,
        "reach_m": round(reach_m(profile), 1),
        "distance_m": list(DISTANCES),
        "curves": [
            {
                "walls": walls,
                "mean_power_dbm": [
                    round(float(v), 2) for v in mean_power_dbm(profile, DISTANCES, walls)
                ],
                "delivery_ratio": [
                    round(float(v), 4)
                    for v in delivery_ratio(profile, DISTANCES, walls, message_bytes)
                ],
            }
            for walls in WALLS
        ],
    }


@radio_app.command("list")
def list_profiles() -> None:
    """The bundled radio profiles."""
    from mrcomm.net.radio.profile import bundled_profiles, load_profile

    for name in bundled_profiles():
        typer.echo(f"{name}: {load_profile(name).source}")


@radio_app.command()
def show(
    profile: Annotated[
        str, typer.Argument(help="A bundled profile name or a profile YAML file.")
    ] = "office-2.4ghz",
    message_bytes: Annotated[
        int, typer.Option("--bytes", help="Message size before the header, bytes.")
    ] = 150,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON.")] = False,
) -> None:
    """The profile's values, and power and delivery ratio against distance and walls."""
    if not 1 <= message_bytes <= 65_000:
        raise InputError(f"must be 1 to 65000, got {message_bytes}", field="--bytes")
    data = curves(profile, message_bytes)
    if as_json:
        typer.echo(json.dumps(data, indent=2))
        return
    from rich.console import Console
    from rich.table import Table

    console = Console()
    values = Table(title=f"Radio profile {data['profile']['name']}", title_justify="left")
    values.add_column("parameter")
    values.add_column("value", justify="right")
    for key, value in data["profile"].items():
        values.add_row(key, f"{value:g}" if isinstance(value, float) else str(value))
    console.print(values)
    table = Table(
        title=(
            f"Mean power (dBm) / expected delivery ratio of a {message_bytes}-byte message, "
            "averaged over shadowing"
        ),
        title_justify="left",
    )
    table.add_column("distance m", justify="right")
    for walls in WALLS:
        table.add_column(
            "line of sight" if walls == 0 else f"{walls} wall{'s' * (walls > 1)}", justify="right"
        )
    for i, d in enumerate(data["distance_m"]):
        table.add_row(
            f"{d:g}",
            *(
                f"{c['mean_power_dbm'][i]:.1f} / {c['delivery_ratio'][i]:.2f}"
                for c in data["curves"]
            ),
        )
    console.print(table)


def _point(text: str) -> tuple[float, float]:
    try:
        x, y = (float(v) for v in text.split(","))
    except ValueError:
        raise InputError(f"must be X,Y in metres, got {text!r}", field="--from") from None
    if not all(abs(v) < 1e6 for v in (x, y)):
        raise InputError(f"must be finite map coordinates, got {text!r}", field="--from")
    return x, y


@radio_app.command()
def plot(
    out: Annotated[Path, typer.Option("--out", "-o", help="Figure file: .png, .svg or .pdf.")],
    profile: Annotated[
        str, typer.Argument(help="A bundled profile name or a profile YAML file.")
    ] = "office-2.4ghz",
    scenario: Annotated[
        Path | None,
        typer.Option(help="Scenario whose map gets a heat map of the received power."),
    ] = None,
    source: Annotated[
        str | None,
        typer.Option("--from", help="Transmitter X,Y on the map, m (default: the first robot)."),
    ] = None,
    seed: Annotated[int, typer.Option(help="Seed of the shadowing field drawn.", min=0)] = 1,
    message_bytes: Annotated[
        int, typer.Option("--bytes", help="Message size before the header, bytes.")
    ] = 150,
) -> None:
    """Delivery ratio and received power against distance and walls (and a heat map)."""
    from mrcomm.net.radio.plot import plot_profile
    from mrcomm.net.radio.profile import load_profile
    from mrcomm.net.signal.plot import plot_format

    check_output_file(out, "--out", FIGURE_SUFFIXES)  # before any work
    if not 1 <= message_bytes <= 65_000:
        raise InputError(f"must be 1 to 65000, got {message_bytes}", field="--bytes")
    loaded = load_profile(profile)
    grid, point = None, None
    if scenario is not None:
        from mrcomm.world.scenario import load_scenario

        world = load_scenario(scenario)
        grid = world.grid
        point = (
            _point(source)
            if source is not None
            else (world.robots[0].pose.x, world.robots[0].pose.y)
        )
        if not grid.is_free(*point):
            raise InputError(f"{point} is not a free cell of the map", field="--from")
    elif source is not None:
        raise InputError("--from needs --scenario (the map to draw)", field="--from")
    try:
        plot_profile(loaded, out, plot_format(out), message_bytes=message_bytes, grid=grid,
                     source=point, seed=seed)  # fmt: skip
    except OSError as err:
        raise InputError(f"cannot write: {err.strerror or err}", file=out, field="--out") from None
    typer.echo(f"wrote {out}")
