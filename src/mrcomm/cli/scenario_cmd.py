"""``mrcomm scenario``: scenarios of any size.

* ``mrcomm scenario make --map office|warehouse|campus|grid|corridor --size WxH --robots N
  --tasks T --start clustered|scattered|depots --assigner base|virtual|robot_K --seed S
  --out DIR`` — a map (ROS map_server YAML + PGM), a scenario and a task file, every
  start and task reachable (checked by loading the result), the same files for the same
  options;
* ``mrcomm scenario tasks LOCATIONS --out TASKS.yaml [--robots N]`` — a task file from
  a list of locations (CSV ``x,y`` or YAML ``[{x, y}, ...]``), in the order the
  assigner's round robin hands them out (with ``--robots``, it prints who gets what);
* ``mrcomm scenario show SCENARIO|DIR [--plot FIG]`` — what a scenario holds, and a
  picture of its map with the starts and tasks;
* ``mrcomm scenario list`` — the bundled scenarios, experiments and RSSI traces, which
  commands take by name (``mrcomm run s1``, ``mrcomm sweep demo``);
* ``mrcomm scenario copy NAME DIR`` — a bundled scenario's files, to edit.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path
from typing import Annotated

import typer

from mrcomm.errors import InputError
from mrcomm.output_paths import FIGURE_SUFFIXES, check_output_file

scenario_app = typer.Typer(
    help="Scenarios of any size: make, tasks, show; the bundled ones: list, copy.",
    no_args_is_help=True,
    rich_markup_mode=None,
)


@scenario_app.command()
def make(
    out: Annotated[Path, typer.Option(help="Output directory (absent or empty).")],
    map_kind: Annotated[
        str, typer.Option("--map", help="office | warehouse | campus | grid | corridor.")
    ] = "office",
    size: Annotated[str, typer.Option(help="Map size WIDTHxHEIGHT in metres.")] = "60x40",
    robots: Annotated[int, typer.Option(help="Team size.")] = 10,
    tasks: Annotated[int, typer.Option(help="Number of tasks.")] = 20,
    start: Annotated[str, typer.Option(help="clustered | scattered | depots.")] = "clustered",
    assigner: Annotated[
        str,
        typer.Option(help="Task assigner: base (a base station), virtual, or robot_K."),
    ] = "robot_1",
    seed: Annotated[int, typer.Option(help="Random seed: same options, same files.")] = 1,
    name: Annotated[
        str | None, typer.Option(help="Scenario name and file stem (default: DIR's name).")
    ] = None,
    quiet: Annotated[
        bool, typer.Option("--quiet", help="No progress line (there is none when piped).")
    ] = False,
) -> None:
    """Generate a map, a scenario and a task file."""
    from mrcomm.run.resources import checked_scenario, planning_reach
    from mrcomm.world.generate.make import Request, make_scenario, parse_size

    width, height = parse_size(size)
    request = Request(
        map_kind, width, height, robots, tasks, start, assigner, seed, name or out.name
    )
    from mrcomm.cli.progress import ProgressLine

    with ProgressLine("scenario make", None, enabled=not quiet) as line:
        path = make_scenario(
            request, out, checked_scenario, lambda s: line.update(None, s), planning_reach
        )
    typer.echo(f"scenario {path} ({robots} robots, {tasks} tasks, {map_kind} {size} m)")


@scenario_app.command("tasks")
def tasks_cmd(
    locations: Annotated[Path, typer.Argument(help="CSV with x,y columns, or YAML list.")],
    out: Annotated[Path, typer.Option(help="The task file to write (YAML).")],
    robots: Annotated[
        int | None,
        typer.Option(help="Print which of robot_1..robot_N the round robin gives each task."),
    ] = None,
) -> None:
    """Write a task file from a list of locations (round-robin order)."""
    from mrcomm.fileio import atomic_write_text
    from mrcomm.world.generate.make import MAX_ROBOTS, tasks_from_locations

    if robots is not None and not 1 <= robots <= MAX_ROBOTS:
        raise InputError(f"must be 1-{MAX_ROBOTS}, got {robots}", field="--robots")
    check_output_file(out, "--out", (".yaml", ".yml"))
    points = _read_locations(locations)
    atomic_write_text(out, tasks_from_locations(points))
    typer.echo(f"{len(points)} tasks in {out}")
    if robots is not None:
        from mrcomm.agents.assignment import round_robin
        from mrcomm.world.scenario import load_tasks

        # The assigner's own function, on the file just written: what a run will do.
        team = [f"robot_{i + 1}" for i in range(robots)]
        for robot, agenda in round_robin(load_tasks(out), team).items():
            typer.echo(f"{robot}: {', '.join(t.task_id for t in agenda) or '-'}")


def _read_locations(path: Path) -> list[tuple[float, float]]:
    if not path.is_file():
        raise InputError("file not found", file=path)
    rows: list[tuple[object, object]] = []
    if path.suffix.lower() == ".csv":
        with path.open(newline="", encoding="utf-8") as handle:
            reader = csv.DictReader(handle)
            if reader.fieldnames is None or not {"x", "y"} <= set(reader.fieldnames):
                raise InputError("needs a header with columns x and y", file=path)
            rows = [(row["x"], row["y"]) for row in reader]
    else:
        from mrcomm.world.yamlfile import read_yaml

        data = read_yaml(path)
        if not isinstance(data, list) or not all(isinstance(p, dict) for p in data):
            raise InputError("must be a list of {x, y} mappings", file=path)
        rows = [(p.get("x"), p.get("y")) for p in data]
    if not rows:
        raise InputError("holds no location", file=path)
    points = []
    for i, (x, y) in enumerate(rows):
        try:
            fx, fy = float(x), float(y)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            raise InputError(f"location {i + 1}: x and y must be numbers", file=path) from None
        if not (math.isfinite(fx) and math.isfinite(fy) and abs(fx) <= 1e6 and abs(fy) <= 1e6):
            raise InputError(f"location {i + 1}: coordinates must be finite, within 1e6 m",
                             file=path)  # fmt: skip
        points.append((fx, fy))
    return points


@scenario_app.command("list")
def list_cmd() -> None:
    """The bundled scenarios, experiments and RSSI traces (commands take their names)."""
    from mrcomm.bundled import bundled, data_root
    from mrcomm.world.yamlfile import read_yaml

    typer.echo(f"bundled data: {data_root()}")
    for kind in ("scenario", "experiment", "trace"):
        typer.echo(f"{kind}s:")
        for name, path in bundled(kind).items():
            about = ""
            if path.suffix == ".yaml":
                raw = read_yaml(path)
                about = str(raw.get("description", "")) if isinstance(raw, dict) else ""
            typer.echo(f"  {name:<20} {about}".rstrip())


@scenario_app.command()
def copy(
    name: Annotated[
        Path, typer.Argument(help="A bundled scenario (s1, s2, ...) or a scenario file.")
    ],
    directory: Annotated[Path, typer.Argument(help="Where to copy it (absent or empty).")],
) -> None:
    """Copy a scenario's files (scenario, tasks, map) into DIR, to edit them."""
    from mrcomm.world.scenario_copy import copy_scenario

    source = _scenario_file(name)
    if not source.is_file():
        raise InputError("no such scenario file or bundled scenario (see `mrcomm scenario list`)",
                         file=name)  # fmt: skip
    copied = copy_scenario(source, directory)
    typer.echo(f"scenario {copied} (from {source})")


@scenario_app.command()
def show(
    scenario: Annotated[
        Path,
        typer.Argument(
            help="Scenario YAML, the directory scenario make wrote, or a bundled scenario's "
            "name (s1, s2, ...)."
        ),
    ],
    plot: Annotated[
        Path | None, typer.Option(help="Write the map with starts and tasks (PNG/SVG/PDF).")
    ] = None,
) -> None:
    """Summarise a scenario; with --plot, draw it."""
    from mrcomm.world.scenario import load_scenario

    if plot is not None:
        check_output_file(plot, "--plot", FIGURE_SUFFIXES)
    sc = load_scenario(_scenario_file(scenario))
    xmin, xmax, ymin, ymax = sc.grid.extent
    free = float((~sc.grid.occupied).sum()) * sc.grid.resolution**2
    typer.echo(f"{sc.name}: {sc.description}")
    typer.echo(
        f"map {xmax - xmin:g} x {ymax - ymin:g} m at {sc.grid.resolution:g} m, free "
        f"{free:,.0f} m²; {len(sc.robots)} robots, {len(sc.tasks)} tasks, assigner "
        f"{sc.assigner.kind}{' on ' + sc.assigner.host if sc.assigner.host else ''}"
    )
    passages = None
    if sc.one_lane_width > 0:
        from mrcomm.world.passages import find_passages

        passages = find_passages(sc.grid, sc.one_lane_width, 2 * sc.robot_radius)
        typer.echo(
            f"{len(passages)} one-lane passages (doors and corridors narrower than "
            f"{sc.one_lane_width:g} m): robots queue at them"
        )
    if plot is not None:
        _plot(sc, plot, passages)
        typer.echo(f"figure {plot}")


def _scenario_file(path: Path) -> Path:
    """``path`` itself, a bundled scenario by name, or the scenario file in the
    directory ``scenario make`` wrote: ``DIR/DIR.yaml`` or its only YAML that is
    neither a map nor a task file."""
    from mrcomm.bundled import resolve

    path = resolve(path, "scenario")
    if not path.is_dir():
        return path
    named = path / f"{path.name}.yaml"
    if named.is_file():
        return named
    found = sorted(p for p in path.glob("*.yaml") if not p.stem.endswith(("_map", "_tasks")))
    if len(found) != 1:
        raise InputError(
            f"a directory with {len(found)} scenario files: name one of them", file=path
        )
    return found[0]


def _plot(sc: object, path: Path, passages: object = None) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from mrcomm.fileio import atomic_write
    from mrcomm.world.scenario import Scenario

    assert isinstance(sc, Scenario)
    xmin, xmax, ymin, ymax = sc.grid.extent
    side = 7.0
    aspect = (ymax - ymin) / max(xmax - xmin, 1e-9)
    fig, ax = plt.subplots(figsize=(side, max(2.5, side * aspect)))
    ax.imshow(sc.grid.occupied, origin="lower", extent=(xmin, xmax, ymin, ymax), cmap="gray_r")
    small = 6 if len(sc.robots) > 100 else 14
    ax.scatter([r.pose.x for r in sc.robots], [r.pose.y for r in sc.robots], s=small,
               color="tab:blue", label=f"{len(sc.robots)} starts")  # fmt: skip
    ax.scatter([t.x for t in sc.tasks], [t.y for t in sc.tasks], s=small, marker="x",
               color="tab:red", label=f"{len(sc.tasks)} tasks")  # fmt: skip
    if sc.assigner.position is not None:
        ax.scatter(*sc.assigner.position, s=60, marker="^", color="tab:green", label="base")
    if passages is not None:
        from mrcomm.world.passages import Passages

        assert isinstance(passages, Passages)
        found = passages.passages
        ax.quiver([p.cx for p in found], [p.cy for p in found], [p.ax for p in found],
                  [p.ay for p in found], angles="xy", scale_units="xy", scale=0.8,
                  color="tab:orange", pivot="middle", width=0.004,
                  label=f"{len(found)} one-lane passages")  # fmt: skip
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(sc.name)
    ax.legend(loc="upper right", fontsize=8, framealpha=0.9)
    fig.tight_layout()
    atomic_write(path, lambda tmp: fig.savefig(tmp, format=path.suffix.lstrip(".").lower()))
    plt.close(fig)
