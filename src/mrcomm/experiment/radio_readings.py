"""RSSI readings with their geometry, for fitting a radio profile (``mrcomm radio
fit``) or SSD's signal models (``mrcomm signal fit``):

* **a readings CSV** — columns ``x_tx, y_tx, x_rx, y_rx, rssi`` (m in the map frame,
  dBm; ``#`` lines are comments, extra columns are ignored), with the map the walls are
  counted on (``--map MAP.yaml``, a ROS map_server map), or a ``walls`` column that
  gives them (a measured dataset with line-of-sight labels and no floor plan: 0 in line
  of sight, 1 obstructed). One group: every reading shares one shadowing field (one
  building).
* **a results database** (``mrcomm run|sweep|live|collect --db``) — the RSSI its
  runs recorded at 2 Hz (table ``rssi``: t, src = the robot that measured, dst = the
  peer it measured) joined with both robots' positions at that time (table
  ``trajectories``, stored every second: interpolated linearly between the two
  samples around the reading; a reading outside a robot's trajectory, or in a gap
  of more than :data:`MAX_GAP_S` between its samples, is left out; a simulation's
  sample at t is where the robot was at t + dt, see :attr:`RunInfo.step_shift`). The
  walls are
  counted on the map of each run's scenario (``configs.options.scenario``, as the
  report finds it) unless ``--map`` is given. Each run is one group: each draws its
  own shadowing field and per-direction offsets.

Only runs whose RSSI **measured the radio** are used: threshold ESD without a trace
(the pulses read the ``radio`` network model's power, as a real card would). SSD's
RSSI is the SVR model's prediction from distance, not a measurement, and ESD with a
trace replays RSSI recorded elsewhere, unrelated to the recorded positions: those runs
are left out (and named, when ``--config`` asks for one of them).

Walls are counted as the radio model counts them: 0 when the straight line between the
antennas is clear (:meth:`OccupancyGrid.line_of_sight`), else the runs of occupied
cells it crosses (:meth:`OccupancyGrid.walls_between`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mrcomm.errors import InputError, did_you_mean
from mrcomm.net.links import cast_ray
from mrcomm.net.radio.fit import censor
from mrcomm.net.radio.fit_data import Readings
from mrcomm.net.radio.profile import DEFAULT_PROFILE
from mrcomm.net.signal.calibration import MIN_READINGS as MIN_CLASS_READINGS
from mrcomm.net.signal.calibration import Calibration
from mrcomm.net.signal.csvio import read_csv
from mrcomm.output_paths import DATABASE_SUFFIXES
from mrcomm.specs import get_spec, variant_names
from mrcomm.world.occupancy import OccupancyGrid

CSV_COLUMNS = ("x_tx", "y_tx", "x_rx", "y_rx", "rssi")
CSV_SUFFIXES = (".csv", ".txt")
#: A reading between two trajectory samples further apart than this (s) is left out.
MAX_GAP_S = 2.5
#: A reading this close (s) before the first or after the last sample of a trajectory
#: takes that sample's position.
EDGE_S = 0.25
#: Readings per line-of-sight class an SVR is fitted to, at most (a seeded sample).
MAX_SVR_READINGS = 2000
#: DuckDB's file magic, at byte 8 of a database file.
_DUCKDB_MAGIC = b"DUCK"


def source_kind(path: Path, option: str = "SOURCE", *, strict: bool = True) -> str:
    """'csv' or 'database', by the file's suffix or else its first bytes (DuckDB's
    magic). Another suffix is a one-line error when ``strict``, else read as a CSV."""
    if not path.exists():
        raise InputError("file not found", file=path, field=option)
    if path.is_dir():
        raise InputError("is a directory, expected a CSV file or a results database", file=path)
    suffix = path.suffix.lower()
    if suffix in DATABASE_SUFFIXES:
        return "database"
    if suffix in CSV_SUFFIXES:
        return "csv"
    try:
        with path.open("rb") as handle:
            head = handle.read(12)
    except OSError as err:
        raise InputError(f"cannot read: {err.strerror or err}", file=path) from None
    if head[8:12] == _DUCKDB_MAGIC:
        return "database"
    if not strict:
        return "csv"
    raise InputError(
        f"unsupported extension {path.suffix or 'none'!r}: give a readings CSV "
        f"({', '.join(CSV_SUFFIXES)}) or a results database ({', '.join(DATABASE_SUFFIXES)})",
        file=path,
        field=option,
    )


class WallCounter:
    """Walls between two points on one map, as the radio model counts them; memoised
    (robots standing still ask the same question again and again)."""

    def __init__(self, grid: OccupancyGrid) -> None:
        self.grid = grid
        grid.prepare_ray_casts()
        self._cache: dict[tuple[int, int, int, int], int] = {}

    def count(self, ax: float, ay: float, bx: float, by: float) -> int:
        a = (round(ax * 1000), round(ay * 1000))
        b = (round(bx * 1000), round(by * 1000))
        key = (*a, *b) if a <= b else (*b, *a)
        found = self._cache.get(key)
        if found is None:
            found = cast_ray(self.grid, ax, ay, bx, by, True)[0]  # the link model's cast
            self._cache[key] = found
        return found

    def many(self, tx: NDArray[np.float64], rx: NDArray[np.float64]) -> NDArray[np.int64]:
        count = self.count
        return np.array(
            [count(a[0], a[1], b[0], b[1]) for a, b in zip(tx.tolist(), rx.tolist(), strict=True)],
            dtype=np.int64,
        )


# -- CSV -------------------------------------------------------------------------------


def read_csv_readings(
    path: Path, grid: OccupancyGrid | None, map_path: Path | None = None
) -> Readings:
    """Readings from a CSV ``x_tx, y_tx, x_rx, y_rx, rssi``, the walls counted on
    ``grid`` or given by the CSV's ``walls`` column (then ``grid`` may be None); any
    problem is a one-line error naming the file, line and column."""
    table = read_csv(path, CSV_COLUMNS)
    given = "walls" in table.columns
    if grid is None and not given:
        raise InputError("needs a walls column, or a map to count the walls on (--map)",
                         file=path, field="walls")  # fmt: skip
    n = len(table.rows)
    values = np.empty((n, 5))
    counted = np.zeros(n, dtype=np.int64)
    for k, (lineno, row) in enumerate(table.rows):
        for c, column in enumerate(CSV_COLUMNS):
            values[k, c] = table.number(lineno, row, column)
        if given:
            cell = table.number(lineno, row, "walls")
            if cell < 0 or cell != int(cell):
                raise table.error(lineno, "walls", f"{cell:g} is not a whole number >= 0")
            counted[k] = int(cell)
        if grid is None:
            continue
        for end, (x, y) in (("x_tx", values[k, 0:2]), ("x_rx", values[k, 2:4])):
            if not grid.in_bounds(float(x), float(y)):
                raise table.error(
                    lineno,
                    end,
                    f"({x:g}, {y:g}) is off the map"
                    + (f" {map_path}" if map_path is not None else "")
                    + " (check the frame of the positions)",
                )
    tx, rx = values[:, 0:2], values[:, 2:4]
    if given:
        walls = counted
        where = "walls as the CSV gives them"
    else:
        assert grid is not None
        walls = WallCounter(grid).many(tx, rx)
        where = "walls counted on " + (str(map_path) if map_path is not None else "the map")
    notes = [f"{n} readings from {path.name}; {where}"]
    return Readings.of(tx, rx, values[:, 4], walls, source=str(path), notes=notes)


# -- results database ------------------------------------------------------------------


@dataclass(frozen=True)
class RunInfo:
    run_id: str
    label: str
    threshold: str
    mode: str
    options: dict[str, Any]

    @property
    def trace(self) -> str | None:
        value = self.options.get("params", {}).get("threshold", {}).get("trace")
        return None if value is None else str(value)

    @property
    def step_shift(self) -> float:
        """How much later (s) than its time a trajectory sample was taken: one step in a
        simulation (:meth:`mrcomm.sim.mission.Mission.step` measures the links, moves
        the robots, then samples), none in live mode."""
        if self.mode != "sim":
            return 0.0
        dt = self.options.get("dt", 0.1)
        return float(dt) if isinstance(dt, int | float) else 0.1

    @property
    def measures_radio(self) -> bool:
        return self.pulse and self.trace is None

    @property
    def pulse(self) -> bool:
        """Whether its threshold measured with pulses (ESD)."""
        return self.threshold in variant_names("threshold") and bool(
            get_spec("threshold", self.threshold).pulse
        )

    @property
    def profile(self) -> str | None:
        if self.options.get("network") != "radio":
            return None
        return str(
            self.options.get("params", {}).get("network", {}).get("profile", DEFAULT_PROFILE)
        )

    def why_not(self) -> str:
        if self.pulse:
            return (
                f"replays the RSSI trace {self.trace}, recorded elsewhere: its RSSI does "
                "not follow the robots' positions"
            )
        if self.threshold == "ssd":
            return "uses SSD: its RSSI is the SVR model's prediction, not a measurement"
        return f"uses threshold {self.threshold!r}, which records no RSSI"


@dataclass(frozen=True)
class DatabaseReadings:
    """Readings joined from a results database, and where they come from."""

    readings: Readings
    runs: tuple[str, ...]
    labels: tuple[str, ...]
    #: The radio profiles the runs simulated (their ``network.profile``).
    profiles: tuple[str, ...]
    #: 'sim' and/or 'live'.
    modes: tuple[str, ...]


def _runs(con: Any, path: Path, config: str | None) -> list[RunInfo]:
    rows = con.execute(
        "SELECT r.run_id, r.label, r.threshold, r.mode, c.options "
        "FROM runs r JOIN configs c USING (config_id) ORDER BY r.run_id"
    ).fetchall()
    runs = []
    for run_id, label, threshold, mode, options in rows:
        try:
            parsed = json.loads(options or "{}")
        except ValueError:
            parsed = {}
        runs.append(RunInfo(str(run_id), str(label), str(threshold), str(mode), parsed))
    if not runs:
        raise InputError("the database holds no runs", file=path)
    labels = sorted({r.label for r in runs})
    if config is not None:
        chosen = [r for r in runs if r.label == config]
        if not chosen:
            raise InputError(
                f"no configuration labelled {config!r}{did_you_mean(config, labels)} "
                f"(labels: {', '.join(labels)})",
                file=path,
                field="--config",
            )
        usable = [r for r in chosen if r.measures_radio]
        if not usable:
            raise InputError(
                f"configuration {config} {chosen[0].why_not()}; pick one with threshold "
                "ESD on the radio, without a trace",
                file=path,
                field="--config",
            )
        return usable
    usable = [r for r in runs if r.measures_radio]
    if not usable:
        raise InputError(
            "no run measured RSSI: only runs with threshold ESD on the radio (no trace) "
            f"do; the database has {', '.join(labels)}",
            file=path,
        )
    return usable


def _grid_of(
    run: RunInfo, path: Path, grid: OccupancyGrid | None, grids: dict[str, OccupancyGrid]
) -> OccupancyGrid:
    if grid is not None:
        return grid
    scenario = str(run.options.get("scenario", ""))
    if scenario not in grids:
        from mrcomm.world.scenario import load_scenario

        if not scenario or not Path(scenario).is_file():
            raise InputError(
                f"the scenario of configuration {run.label} ({scenario or 'not recorded'}) "
                "is not found here: give its map with --map MAP.yaml",
                file=path,
                field="--map",
            )
        try:
            grids[scenario] = load_scenario(scenario).grid
        except InputError as err:
            raise InputError(
                f"the scenario of configuration {run.label}: {err.one_line()} "
                "(or give the map with --map MAP.yaml)",
                file=path,
                field="--map",
            ) from None
    return grids[scenario]


def read_database_readings(
    path: Path, *, config: str | None = None, grid: OccupancyGrid | None = None
) -> DatabaseReadings:
    """The RSSI readings of the runs that measured the radio (see the module docstring),
    with both robots' positions and the walls between them."""
    import pandas as pd

    from mrcomm.experiment.store import open_readonly

    con = open_readonly(path)
    try:
        runs = _runs(con, path, config)
        ids = [r.run_id for r in runs]
        rssi = con.execute(
            "SELECT run_id, t, src, dst, rssi FROM rssi WHERE run_id IN "
            "(SELECT unnest(?)) ORDER BY run_id, t, src, dst",
            [ids],
        ).df()
        traj = con.execute(
            "SELECT run_id, robot, t, x, y FROM trajectories WHERE run_id IN "
            "(SELECT unnest(?)) ORDER BY run_id, robot, t",
            [ids],
        ).df()
    finally:
        con.close()
    labels = ", ".join(sorted({r.label for r in runs}))
    what = f"configuration {config}" if config else f"the ESD runs on the radio ({labels})"
    if rssi.empty:
        raise InputError(f"no RSSI readings in {what}", file=path, field="rssi")
    if traj.empty:
        raise InputError(f"no trajectories in {what}", file=path, field="trajectories")
    info = {r.run_id: r for r in runs}
    grids: dict[str, OccupancyGrid] = {}
    parts: dict[str, list[Any]] = {
        k: [] for k in ("time", "tx", "rx", "rssi", "walls", "pair", "dir")
    }
    group: list[NDArray[np.int64]] = []
    used: list[str] = []
    outside = 0
    pair_ids: dict[tuple[str, str, str], int] = {}
    by_run = dict(tuple(traj.groupby("run_id", sort=False)))
    for run_id, frame in rssi.groupby("run_id", sort=True):
        run = info[str(run_id)]
        paths = {
            str(robot): (g["t"].to_numpy(), g["x"].to_numpy(), g["y"].to_numpy())
            for robot, g in by_run.get(run_id, pd.DataFrame(columns=traj.columns)).groupby(
                "robot", sort=False
            )
        }
        t = frame["t"].to_numpy(dtype=np.float64)
        src = frame["src"].astype(str).to_numpy()
        dst = frame["dst"].astype(str).to_numpy()
        # A simulation measures the links of a step before it moves the robots and
        # samples the trajectory after: its sample at t is where a robot was at t + dt.
        at = t - run.step_shift
        rx, ok_rx = positions_at(paths, src, at)
        tx, ok_tx = positions_at(paths, dst, at)
        ok = ok_rx & ok_tx
        outside += int(np.count_nonzero(~ok))
        if not ok.any():
            continue
        counter = WallCounter(_grid_of(run, path, grid, grids))
        tx, rx = tx[ok], rx[ok]
        src, dst = src[ok], dst[ok]
        parts["time"].append(t[ok])
        parts["tx"].append(tx)
        parts["rx"].append(rx)
        parts["rssi"].append(frame["rssi"].to_numpy(dtype=np.float64)[ok])
        parts["walls"].append(counter.many(tx, rx))
        parts["pair"].append(
            np.array(
                [
                    pair_ids.setdefault((str(run_id), min(a, b), max(a, b)), len(pair_ids))
                    for a, b in zip(src.tolist(), dst.tolist(), strict=True)
                ],
                dtype=np.int64,
            )
        )
        parts["dir"].append(np.where(src < dst, 1, -1).astype(np.int64))
        group.append(np.full(tx.shape[0], len(used), dtype=np.int64))
        used.append(str(run_id))
    if not used:
        raise InputError(
            f"no RSSI reading falls within the robots' trajectories in {what}",
            file=path,
            field="trajectories",
        )
    notes = [
        f"{sum(len(p) for p in parts['rssi'])} readings of {len(used)} run(s) "
        f"({', '.join(sorted({info[r].label for r in used}))}) in {path.name}; positions "
        "interpolated linearly between the trajectories' samples (every 1 s)"
    ]
    if outside:
        notes.append(
            f"left out {outside} readings outside the robots' trajectories or in a gap "
            f"of more than {MAX_GAP_S:g} s between their samples"
        )
    skipped = sorted({r.label for r in runs} - {info[r].label for r in used})
    if skipped:
        notes.append(f"no usable readings in {', '.join(skipped)}")
    readings = Readings.of(
        np.concatenate(parts["tx"]),
        np.concatenate(parts["rx"]),
        np.concatenate(parts["rssi"]),
        np.concatenate(parts["walls"]),
        group=np.concatenate(group),
        pair=np.concatenate(parts["pair"]),
        direction=np.concatenate(parts["dir"]),
        time=np.concatenate(parts["time"]),
        source=str(path),
        notes=notes,
    )
    chosen = [info[r] for r in used]
    return DatabaseReadings(
        readings=readings,
        runs=tuple(used),
        labels=tuple(sorted({r.label for r in chosen})),
        profiles=tuple(sorted({p for r in chosen if (p := r.profile) is not None})),
        modes=tuple(sorted({r.mode for r in chosen})),
    )


def positions_at(
    paths: dict[str, tuple[Any, Any, Any]], robots: NDArray[Any], t: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Each robot's position at each time (linear between the samples around it) and
    whether it is known (within the trajectory, in no gap longer than MAX_GAP_S)."""
    xy = np.full((t.size, 2), np.nan)
    ok = np.zeros(t.size, dtype=np.bool_)
    for robot in np.unique(robots).tolist():
        mask = robots == robot
        found = paths.get(str(robot))
        if found is None or len(found[0]) == 0:
            continue
        ts, xs, ys = (np.asarray(v, dtype=np.float64) for v in found)
        at = t[mask]
        # The sample at or after each time, and the one before it.
        after = np.clip(np.searchsorted(ts, at, side="left"), 0, ts.size - 1)
        before = np.clip(after - 1, 0, ts.size - 1)
        exact = np.isclose(ts[after], at, atol=1e-6)
        inside = (at >= ts[0] - EDGE_S) & (at <= ts[-1] + EDGE_S)
        gap = ts[after] - ts[before]
        known = inside & (exact | (gap <= MAX_GAP_S))
        xy[mask, 0] = np.interp(at, ts, xs)
        xy[mask, 1] = np.interp(at, ts, ys)
        ok[mask] = known
    return xy, ok


# -- SSD calibration from readings -----------------------------------------------------


def calibration_from_readings(
    readings: Readings,
    sensitivity_dbm: float,
    *,
    min_readings: int = MIN_CLASS_READINGS,
    max_readings: int = MAX_SVR_READINGS,
    seed: int = 0,
    notes: list[str] | None = None,
) -> Calibration:
    """A calibration set (distance, rssi, line of sight = no wall between the robots)
    from readings, censored readings left out as for a radio fit; each class capped at
    ``max_readings`` (a seeded sample). Too few readings of a class is a one-line
    error."""
    notes = notes if notes is not None else []
    kept, _ = censor(readings, sensitivity_dbm, notes=notes)
    distance = kept.distance
    los = kept.walls == 0
    where = readings.source or None
    for flag, label in ((True, "line-of-sight"), (False, "obstructed")):
        count = int(np.count_nonzero(los == flag))
        if count < min_readings:
            raise InputError(
                f"only {count} {label} readings, need at least {min_readings}",
                file=where,
                field="rssi",
            )
        if np.unique(np.round(distance[los == flag], 2)).size < 2:
            raise InputError(
                f"{label} readings are all at one distance, need two or more distances",
                file=where,
                field="rssi",
            )
    rng = np.random.default_rng(seed)
    keep = np.ones(len(kept), dtype=np.bool_)
    for flag, label in ((True, "line-of-sight"), (False, "obstructed")):
        members = np.flatnonzero(los == flag)
        if members.size > max_readings:
            drop = rng.choice(members, members.size - max_readings, replace=False)
            keep[drop] = False
            notes.append(f"{label}: a seeded sample of {max_readings} of {members.size} readings")
    return Calibration(
        distance[keep],
        kept.rssi[keep],
        los[keep],
        source=str(readings.source),
        comments=tuple(readings.notes) + tuple(notes),
    )
