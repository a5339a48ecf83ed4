"""``mrcomm radio``: the radio profiles of the ``radio`` network model.

* ``mrcomm radio list`` — the bundled profiles.
* ``mrcomm radio show [PROFILE] [--bytes N] [--json]`` — the profile's values, and
  mean received power and expected delivery ratio against distance in line of sight and
  through 1, 2 and 3 walls (as a table, or as JSON curves).
"""

from __future__ import annotations

import json
from typing import Annotated, Any

import typer

from mrcomm.errors import InputError

radio_app = typer.Typer(
    help="Radio profiles of the radio network model: list, show.",
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
