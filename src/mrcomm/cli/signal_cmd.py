"""``mrcomm signal``: fit SSD signal models from measurements, show and plot them.

* ``mrcomm signal fit CSV --out MODEL.json`` — fit and save (atomically), print a summary.
* ``mrcomm signal fit RESULTS.duckdb --out MODEL.json [--config LABEL] [--map MAP.yaml]``
  — the same from the RSSI that a results database's ESD runs measured on the radio
  (the calibration set: distance between the robots, RSSI, line of sight = no wall
  between them on the map; see :mod:`mrcomm.experiment.radio_readings`).
* ``mrcomm signal show [MODEL] [--threshold -42] [--json]`` — threshold crossings and
  RSSI at 1, 2, 4 and 8 m for line of sight and obstructed.
* ``mrcomm signal plot [MODEL] [--csv CSV] --out FIG`` — a figure (PNG, SVG or PDF).

Without MODEL the bundled model (fitted from the synthetic calibration set) is used.
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import Annotated, Any

import typer

from mrcomm.errors import InputError
from mrcomm.output_paths import FIGURE_SUFFIXES, check_output_file

signal_app = typer.Typer(
    help="SSD signal models: fit from RSSI measurements, show, plot.",
    no_args_is_help=True,
    rich_markup_mode=None,
)

SAMPLE_DISTANCES = (1.0, 2.0, 4.0, 8.0)
#: Largest SVR regularisation ``--C`` a fit accepts: scikit-learn's SVR has no iteration
#: limit and its time grows with C (the bundled calibration set: 1 s at C 1e4, 6 s at
#: 1e6, 27 s at 1e10, never done at 1e308), while readings in dB are fitted as closely
#: as they can be long before 1e6.
MAX_C = 1e6
CLASS_LABELS = {"line_of_sight": "line of sight", "obstructed": "obstructed"}

ModelArg = Annotated[
    Path | None,
    typer.Argument(help="Model JSON (default: the bundled model).", show_default=False),
]
ThresholdOpt = Annotated[
    float | None,
    typer.Option("--threshold", help="Warning threshold in dBm (default: the model's, -42)."),
]


def _load(model_path: Path | None) -> tuple[Any, Path]:
    from mrcomm.net.signal.bundled import default_model_path
    from mrcomm.net.signal.svr import load_model

    path = model_path if model_path is not None else default_model_path()
    return load_model(path), path


def summarise(model: Any, threshold: float | None, source: str) -> dict[str, Any]:
    """Crossings, sample RSSI values and training facts of a model, as plain data."""
    from mrcomm.net.signal.table import RssiTable

    table = RssiTable.from_model(model)
    thr = model.threshold_dbm if threshold is None else threshold
    crossings = table.crossings(thr)
    out: dict[str, Any] = {
        "model": source,
        "threshold_dbm": thr,
        "provenance": dict(model.provenance),
    }
    for name in CLASS_LABELS:
        los = name == "line_of_sight"
        curve = model.curve(los)
        lo, hi = curve.trained_range
        out[name] = {
            "crossings": [{"distance_m": d, "direction": how} for d, how in crossings[name]],
            "below_at_start": bool(table.rssi_at(0.0, los) < thr),
            "rssi_dbm": {f"{d:g}": round(table.rssi_at(d, los), 2) for d in SAMPLE_DISTANCES},
            "trained_range_m": [lo, hi],
            "saturation_dbm": round(float(curve.predict(hi)), 2),
            "support_vectors": int(curve.support_vectors.size),
            "readings": curve.n_samples,
        }
    return out


def _print_summary(info: dict[str, Any]) -> None:
    prov = info["provenance"]
    origin = ""
    if prov.get("source"):
        kind = "SYNTHETIC calibration" if prov.get("synthetic") else "calibration"
        origin = f" ({kind} {prov['source']})"
    typer.echo(f"model: {info['model']}{origin}")
    thr = info["threshold_dbm"]
    typer.echo(f"threshold: {thr:g} dBm")
    for name, label in CLASS_LABELS.items():
        cls = info[name]
        events = [f"{c['direction']} at {c['distance_m']:.2f} m" for c in cls["crossings"]]
        if cls["below_at_start"]:
            events.insert(0, "below from 0 m")
        typer.echo(f"{label}: " + (", ".join(events) if events else f"never below {thr:g} dBm"))
        values = ", ".join(f"{d} m {v:.1f}" for d, v in cls["rssi_dbm"].items())
        typer.echo(f"  RSSI (dBm): {values}")
        lo, hi = cls["trained_range_m"]
        typer.echo(
            f"  trained on {cls['readings']} readings at {lo:g}-{hi:g} m "
            f"(saturates at {cls['saturation_dbm']:.1f} dBm beyond), "
            f"{cls['support_vectors']} support vectors"
        )


def calibration_from_database(
    source: Path, config: str | None, map_path: Path | None
) -> tuple[Any, list[str]]:
    """The calibration set of a results database's runs that measured the radio, and
    what was done to build it (one line each)."""
    from mrcomm.experiment.radio_readings import calibration_from_readings, read_database_readings
    from mrcomm.net.radio.profile import DEFAULT_PROFILE, load_profile
    from mrcomm.world.mapio import load_map

    grid = load_map(map_path) if map_path is not None else None
    found = read_database_readings(source, config=config, grid=grid)
    notes = list(found.readings.notes)
    profile_name = found.profiles[0] if len(found.profiles) == 1 else DEFAULT_PROFILE
    try:
        sensitivity = load_profile(profile_name).sensitivity_dbm
    except InputError:
        sensitivity = load_profile(DEFAULT_PROFILE).sensitivity_dbm
    if found.modes == ("sim",):
        notes.insert(0, "SYNTHETIC: RSSI of simulated runs (the radio network model)")
    extra: list[str] = []
    calibration = calibration_from_readings(found.readings, sensitivity, notes=extra)
    # The comments travel into the model's provenance ("SYNTHETIC" marks it so).
    return dataclasses.replace(calibration, comments=(*notes, *extra)), notes + extra


@signal_app.command("fit")
def fit_cmd(
    source: Annotated[
        Path,
        typer.Argument(
            help="Calibration CSV (distance,rssi,line_of_sight), or a results database "
            "(.duckdb, .db, .ddb) whose ESD runs measured the radio."
        ),
    ],
    out: Annotated[Path, typer.Option("--out", "-o", help="Model JSON to write.")],
    gamma: Annotated[float, typer.Option(help="RBF kernel gamma (1/m^2).", min=1e-9)] = 0.1,
    c: Annotated[
        float, typer.Option("--C", help=f"SVR regularisation C (at most {MAX_C:g}).", min=1e-9)
    ] = 100.0,
    epsilon: Annotated[float, typer.Option(help="SVR epsilon tube (dB).", min=0.0)] = 0.1,
    threshold: Annotated[float, typer.Option(help="Default warning threshold (dBm).")] = -42.0,
    config: Annotated[
        str | None,
        typer.Option(
            help="Database: only the runs of this configuration label.", show_default=False
        ),
    ] = None,
    map_path: Annotated[
        Path | None,
        typer.Option(
            "--map",
            help="Database: the ROS map YAML line of sight is cast on (default: each "
            "run's scenario map).",
            show_default=False,
        ),
    ] = None,
) -> None:
    """Fit line-of-sight and obstructed SVR models to a calibration CSV or to the RSSI
    recorded by a results database's ESD runs."""
    from mrcomm.experiment.radio_readings import source_kind
    from mrcomm.net.signal.calibration import load_calibration
    from mrcomm.net.signal.pathloss import fit_log_distance
    from mrcomm.net.signal.svr import fit, save_model

    # Infinite or NaN hyper-parameters hang the SVR fit or write a model that loading
    # then refuses: every one must be a finite number.
    hyper = {"--gamma": gamma, "--C": c, "--epsilon": epsilon, "--threshold": threshold}
    for name, number in hyper.items():
        if not math.isfinite(number):
            raise InputError(f"must be a finite number, got {number:g}", field=name)
    if c > MAX_C:
        raise InputError(
            f"must be at most {MAX_C:g} (a larger C only slows the fit), got {c:g}", field="--C"
        )
    check_output_file(out, "--out", (".json",))
    # A results database by its suffix or content; anything else is read as a CSV,
    # whatever its suffix (as before databases were accepted).
    kind = source_kind(source, strict=False)
    notes: list[str] = []
    if kind == "database":
        calibration, notes = calibration_from_database(source, config, map_path)
    else:
        for option, value in (("--config", config), ("--map", map_path)):
            if value is not None:
                raise InputError(
                    "applies to a results database, not to a calibration CSV",
                    file=source,
                    field=option,
                )
        calibration = load_calibration(source)
    model = fit(calibration, gamma=gamma, C=c, epsilon=epsilon, threshold_dbm=threshold)
    try:
        save_model(model, out)
    except OSError as err:
        raise InputError(f"cannot write: {err.strerror or err}", file=out, field="--out") from None
    for note in notes:
        typer.echo(f"note: {note}")
    typer.echo(f"wrote {out}")
    typer.echo(f"SVR: rbf, gamma {gamma:g}, C {c:g}, epsilon {epsilon:g}")
    for los, label in ((True, "line of sight"), (False, "obstructed")):
        d, r = calibration.of_class(los)
        positive = d > 0
        a_db, n = fit_log_distance(d[positive], r[positive])
        typer.echo(f"log-distance fit, {label}: A = {a_db:.1f} dB, n = {n:.2f}")
    _print_summary(summarise(model, None, str(out)))


@signal_app.command("show")
def show_cmd(
    model: ModelArg = None,
    threshold: ThresholdOpt = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON instead of text.")] = False,
) -> None:
    """Where RSSI crosses the threshold, and RSSI at 1, 2, 4 and 8 m."""
    loaded, path = _load(model)
    info = summarise(loaded, threshold, str(path))
    if as_json:
        typer.echo(json.dumps(info, indent=2))
    else:
        _print_summary(info)


@signal_app.command("plot")
def plot_cmd(
    out: Annotated[Path, typer.Option("--out", "-o", help="Figure file: .png, .svg or .pdf.")],
    model: ModelArg = None,
    csv: Annotated[
        Path | None,
        typer.Option(
            "--csv",
            help="Calibration readings to draw (default with the bundled "
            "model: the bundled synthetic set).",
            show_default=False,
        ),
    ] = None,
    threshold: ThresholdOpt = None,
) -> None:
    """Plot readings, per-distance means, both fitted curves and the threshold."""
    from mrcomm.net.signal.bundled import bundled_calibration_path
    from mrcomm.net.signal.calibration import load_calibration
    from mrcomm.net.signal.plot import plot_model

    check_output_file(out, "--out", FIGURE_SUFFIXES)  # before any work
    loaded, _ = _load(model)
    if csv is None and model is None:
        csv = bundled_calibration_path()
    calibration = load_calibration(csv) if csv is not None else None
    try:
        plot_model(loaded, out, calibration=calibration, threshold=threshold)
    except OSError as err:
        raise InputError(f"cannot write: {err.strerror or err}", file=out, field="--out") from None
    typer.echo(f"wrote {out}")
