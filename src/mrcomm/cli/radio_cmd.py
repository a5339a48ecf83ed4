"""``mrcomm radio``: the radio profiles of the ``radio`` network model.

* ``mrcomm radio list`` — the bundled profiles.
* ``mrcomm radio show [PROFILE] [--bytes N] [--json]`` — the profile's values, and
  mean received power and expected delivery ratio against distance in line of sight and
  through 1, 2 and 3 walls (as a table, or as JSON curves).
* ``mrcomm radio plot [PROFILE] --out FIG [--scenario S --from X,Y --seed N]`` — the
  same curves as a figure, and with a scenario a heat map of the received power from a
  point of its map.
* ``mrcomm radio fit SOURCE --out PROFILE.yaml [--map MAP.yaml] [--base PROFILE]
  [--tx-power DBM] [--config LABEL] [--json]`` — fit L0, n, wall loss, shadowing σ,
  decorrelation distance (and the asymmetry, from a database) to RSSI readings: a CSV
  ``x_tx,y_tx,x_rx,y_rx,rssi`` with the map, or a results database whose ESD runs
  measured the radio; print the fit against the base profile and write the base
  profile with the fitted values (see docs/RADIO.md, "Calibrating a profile").
* ``mrcomm radio validate DATASET [--plot FIG] [--out PROFILE.yaml] [--json]`` — fit on
  a dataset's training readings and report the error on its held-out ones
  (:mod:`mrcomm.cli.radio_validate_cmd`).

The fit lives here, not under ``mrcomm signal fit``: it writes a radio profile (what
``list``/``show``/``plot`` read and ``--set network.profile=`` takes), and shares no
option with the SVR fit of SSD's signal models.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Annotated, Any

import typer

from mrcomm.errors import InputError
from mrcomm.output_paths import FIGURE_SUFFIXES, check_output_file

radio_app = typer.Typer(
    help="Radio model profiles: list, show, plot, fit, validate.",
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

    profile = load_profile(profile_name, "PROFILE")
    return {
        "profile": profile.model_dump(),
        "file": str(profile_path(profile_name, "PROFILE")),
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


#: What an unset optional profile value means, as `radio show` prints it.
_UNSET = {
    "preamble_snr_db": "none (the sensitivity decides)",
    "carrier_sense_dbm": "the sensitivity",
}


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
        shown = _UNSET.get(key, "-") if value is None else str(value)
        values.add_row(key, f"{value:g}" if isinstance(value, float) else shown)
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
    loaded = load_profile(profile, "PROFILE")
    grid, point = None, None
    if scenario is not None:
        from mrcomm.bundled import resolve
        from mrcomm.world.scenario import load_scenario

        world = load_scenario(resolve(scenario, "scenario"))
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


def _fitted_profile(fitted: Any, name: str, source: str, where: Path) -> Any:
    """The fitted profile, or a one-line error when a value is outside a profile's
    limits (e.g. an L0 that says the stated transmit power is wrong)."""
    import pydantic

    try:
        return fitted.profile(name, source)
    except pydantic.ValidationError as err:
        first = err.errors(include_url=False)[0]
        key = ".".join(str(p) for p in first["loc"])
        hint = " (is --tx-power right?)" if key == "reference_loss_db" else ""
        raise InputError(
            f"the fitted {key} = {first.get('input')!r} is outside a profile's limits: "
            f"{first['msg'].lower()}{hint}",
            file=where,
        ) from None


def _print_fit(data: dict[str, Any], out: Path) -> None:
    from rich.console import Console
    from rich.table import Table

    from mrcomm.net.radio.fit import PROFILE_KEYS

    console = Console()
    table = Table(
        title=f"Radio profile fitted to {data['readings']} readings (base {data['base']})",
        title_justify="left",
    )
    rows = [("intercept_dbm", "A = tx − L0 (dBm at 1 m)")]
    rows += [(key, key) for key in PROFILE_KEYS.values()]
    statuses = {"kept": "base value kept (see notes)", "clipped": "at a bound (see notes)"}
    flagged = any(data[key]["status"] in statuses for key, _ in rows)
    columns = ("parameter", "fitted", "95 % CI", "base", *(("",) if flagged else ()))
    for column in columns:
        table.add_column(column, justify="left" if column in ("parameter", "") else "right")
    for key, label in rows:
        entry = data[key]
        ci = entry["ci95"]
        table.add_row(
            label,
            f"{entry['value']:.2f}",
            "" if ci is None else f"{ci[0]:.2f} .. {ci[1]:.2f}",
            f"{entry['base']:g}",
            *((statuses.get(entry["status"], ""),) if flagged else ()),
        )
    console.print(table)
    typer.echo(
        f"transmit power {data['tx_power_dbm']:g} dBm (L0 = tx − A); R² {data['r_squared']:.3f}; "
        f"residual std {data['residual_std_db']:.2f} dB; nugget {data['nugget_db']:.2f} dB; "
        f"{data['groups']} independent group(s)"
    )
    for note in data["notes"]:
        typer.echo(f"note: {note}")
    typer.echo(f"wrote {out}")


@radio_app.command("fit")
def fit_cmd(
    source: Annotated[
        Path,
        typer.Argument(
            help="Readings: a CSV x_tx,y_tx,x_rx,y_rx,rssi (m, dBm) or a results database "
            "(.duckdb, .db, .ddb) whose ESD runs measured the radio."
        ),
    ],
    out: Annotated[Path, typer.Option("--out", "-o", help="Profile YAML to write.")],
    map_path: Annotated[
        Path | None,
        typer.Option(
            "--map",
            help="ROS map YAML the walls are counted on (needed with a CSV; with a "
            "database, instead of each run's scenario map).",
            show_default=False,
        ),
    ] = None,
    base: Annotated[
        str | None,
        typer.Option(
            help="Profile (name or YAML) the fitted one copies its other values from "
            "(default: the runs' profile, else office-2.4ghz).",
            show_default=False,
        ),
    ] = None,
    tx_power: Annotated[
        float | None,
        typer.Option(
            "--tx-power",
            help="Transmit power, dBm (default: the base profile's).",
            show_default=False,
        ),
    ] = None,
    config: Annotated[
        str | None,
        typer.Option(
            help="Database: only the runs of this configuration label.", show_default=False
        ),
    ] = None,
    name: Annotated[
        str | None,
        typer.Option(help="The profile's name (default: the file's stem).", show_default=False),
    ] = None,
    seed: Annotated[int, typer.Option(help="Seed of the reading pairs sampled.", min=0)] = 0,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON.")] = False,
) -> None:
    """Fit a radio profile (L0, n, wall loss, shadowing) to RSSI readings."""
    from mrcomm.experiment.radio_readings import (
        read_csv_readings,
        read_database_readings,
        source_kind,
    )
    from mrcomm.net.radio.fit import fit_profile, write_profile
    from mrcomm.net.radio.profile import DEFAULT_PROFILE, PROFILE_SUFFIXES, load_profile
    from mrcomm.world.mapio import load_map

    # Everything the fit needs is checked before any work.
    check_output_file(out, "--out", PROFILE_SUFFIXES)
    kind = source_kind(source)
    if kind == "csv" and map_path is None:
        raise InputError("a readings CSV needs --map MAP.yaml (the walls are counted on it)",
                         file=source, field="--map")  # fmt: skip
    if kind == "csv" and config is not None:
        raise InputError("--config selects runs of a results database, not of a CSV",
                         file=source, field="--config")  # fmt: skip
    if tx_power is not None and not -30.0 <= tx_power <= 36.0:
        raise InputError(f"must be -30 to 36 dBm, got {tx_power:g}", field="--tx-power")
    if name is not None and not name.strip():
        raise InputError("must not be empty", field="--name")
    from mrcomm.cli.progress import ProgressLine

    status = "reading the readings, counting walls on the map"
    with ProgressLine("radio fit", None, enabled=not as_json, status=status) as line:
        base_profile = load_profile(base, "--base") if base is not None else None
        grid = load_map(map_path) if map_path is not None else None
        notes: list[str] = []
        if kind == "csv":
            assert grid is not None
            readings = read_csv_readings(source, grid, map_path)
            what = f"{source.name} ({len(readings)} readings)"
        else:
            found = read_database_readings(source, config=config, grid=grid)
            readings = found.readings
            if base_profile is None and len(found.profiles) == 1:
                try:
                    base_profile = load_profile(found.profiles[0])
                except InputError as err:
                    notes.append(f"the runs' profile cannot be read here ({err.one_line()})")
            elif base_profile is None and len(found.profiles) > 1:
                notes.append(f"the runs simulated several profiles ({', '.join(found.profiles)}): "
                             "fitted together; choose one with --config")  # fmt: skip
            kind_of = "simulated" if found.modes == ("sim",) else "/".join(found.modes)
            what = (f"{source.name}: {len(readings)} readings of {len(found.runs)} {kind_of} "
                    f"run(s) of {', '.join(found.labels)}")  # fmt: skip
        if base_profile is None:
            base_profile = load_profile(DEFAULT_PROFILE)
        readings = dataclasses.replace(readings, notes=(*readings.notes, *notes))
        line.update(None, f"fitting to {len(readings)} readings")
        fitted = fit_profile(readings, base_profile, tx_power_dbm=tx_power, seed=seed)
    profile = _fitted_profile(
        fitted,
        name or out.stem,
        f"fitted by mrcomm radio fit to {what}; other values from {base_profile.name}",
        source,
    )
    data = fitted.as_dict()
    header = [
        f"Radio profile fitted by `mrcomm radio fit` to {what}.",
        f"Fitted: L0, exponent, wall loss, shadowing sigma and decorrelation (base "
        f"{base_profile.name} for the rest); R2 {data['r_squared']:.3f}.",
        *(f"note: {n}" for n in fitted.notes),
    ]
    try:
        write_profile(out, profile, header)
    except OSError as err:
        raise InputError(f"cannot write: {err.strerror or err}", file=out, field="--out") from None
    if as_json:
        typer.echo(json.dumps({**data, "out": str(out), "profile": profile.model_dump()}, indent=2))
    else:
        _print_fit(data, out)


# `mrcomm radio validate` lives in its own module (which knows nothing of this one).
from mrcomm.cli.radio_validate_cmd import validate_cmd  # noqa: E402

radio_app.command("validate")(validate_cmd)
