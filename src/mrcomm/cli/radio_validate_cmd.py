"""``mrcomm radio validate``: a radio profile fitted on a measured dataset's training
readings and judged on its held-out ones (:mod:`mrcomm.net.radio.validate`).

    mrcomm radio validate wifi-office [--plot FIG] [--out PROFILE.yaml] [--json]
    mrcomm radio validate DIR          # DIR/train.csv and DIR/test.csv, readings CSVs

A dataset is a directory with ``train.csv`` and ``test.csv`` in the readings format of
``mrcomm radio fit`` (``x_tx, y_tx, x_rx, y_rx, rssi``, with a ``walls`` column or
``--map``), or the name of a bundled one (``data/radio/validation``: ``wifi-office``,
``wifi-corridor``, ``wifi-lecture-theatre``, derived from a public measured dataset).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any

import typer

from mrcomm.errors import InputError
from mrcomm.output_paths import FIGURE_SUFFIXES, check_output_file

VALIDATION_FOLDER = "radio/validation"
#: Where the bundled sets come from (data/radio/validation/NOTICE.md).
DATASET_SOURCE = (
    "derived from the Wi-Fi RSS/RTT dataset for model selection, "
    "github.com/Fx386483710/WiFi_RSS_RTT_Dataset_for_Model_Selection, MIT licence"
)


def bundled_datasets() -> dict[str, Path]:
    """Name -> directory of the bundled validation sets."""
    from mrcomm.bundled import data_root

    root = data_root() / VALIDATION_FOLDER
    if not root.is_dir():
        return {}
    return {p.name: p for p in sorted(root.iterdir()) if (p / "train.csv").is_file()}


def dataset_dir(given: str) -> Path:
    """The dataset's directory: ``given`` when it is one, else a bundled set's name."""
    path = Path(given)
    if path.is_dir():
        found = path
    else:
        sets = bundled_datasets()
        if given not in sets:
            from mrcomm.errors import did_you_mean

            raise InputError(
                f"no such directory or bundled validation set{did_you_mean(given, sets)}; "
                f"bundled: {', '.join(sets) or 'none'}",
                field="DATASET",
            )
        found = sets[given]
    for split in ("train", "test"):
        if not (found / f"{split}.csv").is_file():
            raise InputError(f"missing {split}.csv", file=found, field="DATASET")
    return found


def _summary(result: Any, dataset: Path) -> dict[str, Any]:
    profile = result.calibrated
    a, n = result.log_distance
    return {
        "dataset": str(dataset),
        "train_readings": result.fit.readings,
        "test_readings": int(result.measured.size),
        "calibrated": {
            "reference_loss_db": profile.reference_loss_db,
            "tx_power_dbm": profile.tx_power_dbm,
            "exponent": profile.exponent,
            "wall_loss_db": profile.wall_loss_db,
            "shadowing_sigma_db": profile.shadowing_sigma_db,
        },
        "log_distance": {"intercept_dbm": round(a, 2), "exponent": round(n, 3)},
        "errors": [row.as_dict() for row in result.rows],
        "notes": list(result.fit.notes),
    }


def validate_cmd(
    dataset: Annotated[
        str,
        typer.Argument(
            help="A directory with train.csv and test.csv (readings CSVs), or a bundled "
            "validation set: wifi-office, wifi-corridor, wifi-lecture-theatre."
        ),
    ],
    map_path: Annotated[
        Path | None,
        typer.Option(
            "--map",
            help="ROS map YAML the walls are counted on (CSVs without a walls column).",
            show_default=False,
        ),
    ] = None,
    base: Annotated[
        str, typer.Option(help="Profile the fitted one copies its other values from.")
    ] = "office-2.4ghz",
    plot: Annotated[
        Path | None,
        typer.Option(
            help="Figure of predicted against measured power (.png, .svg, .pdf).",
            show_default=False,
        ),
    ] = None,
    out: Annotated[
        Path | None,
        typer.Option(
            "--out", "-o", help="Write the calibrated profile (YAML).", show_default=False
        ),
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON.")] = False,
) -> None:
    """Fit a profile on a dataset's training readings; report the error of its mean
    power on the held-out readings, beside the bundled default and plain log-distance."""
    from mrcomm.experiment.radio_readings import read_csv_readings
    from mrcomm.net.radio.fit import write_profile
    from mrcomm.net.radio.profile import DEFAULT_PROFILE, PROFILE_SUFFIXES, load_profile
    from mrcomm.net.radio.validate import validate
    from mrcomm.world.mapio import load_map

    # Everything is checked before any work.
    if plot is not None:
        check_output_file(plot, "--plot", FIGURE_SUFFIXES)
    if out is not None:
        check_output_file(out, "--out", PROFILE_SUFFIXES)
    folder = dataset_dir(dataset)
    base_profile = load_profile(base, "--base")
    default = load_profile(DEFAULT_PROFILE)
    grid = load_map(map_path) if map_path is not None else None
    train = read_csv_readings(folder / "train.csv", grid, map_path)
    test = read_csv_readings(folder / "test.csv", grid, map_path)
    name = out.stem if out is not None else folder.name
    bundled = bundled_datasets().get(folder.name) == folder
    source = f"{folder.name}/train.csv" + (f" ({DATASET_SOURCE})" if bundled else "")
    result = validate(train, test, base_profile, default, name, source)
    if out is not None:
        header = [
            f"Radio profile calibrated by `mrcomm radio validate` on {folder.name}/train.csv "
            f"({result.fit.readings} readings); other values from {base_profile.name}.",
            *(f"note: {n}" for n in result.fit.notes),
        ]
        write_profile(out, result.calibrated, header)
    if plot is not None:
        from mrcomm.net.radio.plot import validation_figure
        from mrcomm.net.signal.plot import plot_format

        validation_figure(result, folder.name, plot, plot_format(plot))
    summary = _summary(result, folder)
    if as_json:
        typer.echo(json.dumps(summary, indent=2))
        return
    _print(summary, folder.name)
    for path in (p for p in (out, plot) if p is not None):
        typer.echo(f"wrote {path}")


def _print(summary: dict[str, Any], name: str) -> None:
    from rich.console import Console
    from rich.table import Table

    table = Table(
        title=f"{name}: mean power predicted for {summary['test_readings']} held-out readings "
        f"(fitted on {summary['train_readings']})",
        title_justify="left",
    )
    for column in ("model", "where", "readings", "RMSE dB", "bias dB"):
        table.add_column(column, justify="left" if column in ("model", "where") else "right")
    for row in summary["errors"]:
        if not row["readings"]:
            continue
        table.add_row(row["model"], row["where"], str(row["readings"]),
                      f"{row['rmse_db']:.2f}", f"{row['bias_db']:+.2f}")  # fmt: skip
    Console().print(table)
    fitted = summary["calibrated"]
    typer.echo(
        f"calibrated: L0 {fitted['reference_loss_db']:g} dB (tx {fitted['tx_power_dbm']:g} dBm), "
        f"exponent {fitted['exponent']:g}, wall loss {fitted['wall_loss_db']:g} dB, "
        f"shadowing sigma {fitted['shadowing_sigma_db']:g} dB"
    )
    for note in summary["notes"]:
        typer.echo(f"note: {note}")
