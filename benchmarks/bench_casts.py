"""The radio's ray casts alone: record one mission's casts, replay them on any tree.

``record`` runs S4 · radio · LF · SLT · shared channel · seed 1 for ``--sim-time`` s and
keeps the segments the link model handed to ``OccupancyGrid.cast_many`` over its last
``--steps`` steps (S4's team has spread by then: long, mostly obstructed rays), with
the walls and clearances found, in one ``.npz``. ``replay`` casts the same segments on
the tree it runs from (``PYTHONPATH`` picks it), one step at a time as the mission did,
``--repeats`` times, and prints the CPU time per step (minimum and median of the
repeats), the load, and whether every ray's walls and clearance are the recorded ones.
Alternate the trees yourself, pinned to one core.

Run::

    .venv/bin/python benchmarks/bench_casts.py record --out /tmp/casts.npz
    taskset -c 1 .venv/bin/python benchmarks/bench_casts.py replay /tmp/casts.npz
    PYTHONPATH=/tmp/mrcomm-old/src taskset -c 1 .venv/bin/python \\
        benchmarks/bench_casts.py replay /tmp/casts.npz
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
S4 = ROOT / "data" / "scenarios" / "s4" / "s4.yaml"
S4_MAP = ROOT / "data" / "scenarios" / "s4" / "s4_map.yaml"


def record(out: Path, sim_time: float, steps: int) -> None:
    from mrcomm.run.config import make_config
    from mrcomm.run.resources import ScenarioResources
    from mrcomm.sim.mission import Mission
    from mrcomm.world.occupancy import OccupancyGrid

    kept: list[tuple[Any, ...]] = []
    cast_many = OccupancyGrid.cast_many

    def keeping(grid: OccupancyGrid, segments: Any, count_walls: bool, min_gap: float = 0.3) -> Any:
        walls, clearance = cast_many(grid, segments, count_walls, min_gap)
        kept.append((np.array(segments), walls.copy(), clearance.copy()))
        del kept[:-steps]
        return walls, clearance

    OccupancyGrid.cast_many = keeping  # type: ignore[method-assign]
    options = {"network": "radio", "behaviour": "lf", "threshold": "slt", "seed": 1}
    params = {"network": {"channel": "shared"}}
    config = make_config(None, scenario=S4, **options, params=params, max_time=sim_time)
    mission = Mission(config, ScenarioResources.load(S4))
    while not mission.done:
        mission.step()
    np.savez_compressed(
        out,
        counts=np.array([len(s) for s, _, _ in kept]),
        segments=np.concatenate([s for s, _, _ in kept]),
        walls=np.concatenate([w for _, w, _ in kept]),
        clearance=np.concatenate([c for _, _, c in kept]),
    )
    print(f"{out}: {len(kept)} steps, {sum(len(s) for s, _, _ in kept)} rays")


def replay(path: Path, repeats: int) -> None:
    from mrcomm.world import traversal
    from mrcomm.world.mapio import load_map

    data = np.load(path)
    bounds = np.cumsum(data["counts"])[:-1]
    steps = np.split(data["segments"], bounds)
    grid = load_map(S4_MAP)
    grid.prepare_ray_casts()
    found = [grid.cast_many(segments, True) for segments in steps]
    same = np.array_equal(np.concatenate([w for w, _ in found]), data["walls"]) and (
        np.array_equal(np.concatenate([c for _, c in found]), data["clearance"])
    )
    per_step = []
    load = os.getloadavg()
    for _ in range(repeats):
        start = time.process_time()
        for segments in steps:
            grid.cast_many(segments, True)
        per_step.append((time.process_time() - start) / len(steps) * 1000)
    print(
        f"{traversal.__file__}: {len(steps)} steps, {len(data['walls'])} rays; "
        f"CPU ms a step min {min(per_step):.2f} median {statistics.median(per_step):.2f} "
        f"({repeats} repeats); the recorded answers: {'all the same' if same else 'DIFFERENT'}; "
        f"load {load[0]:.2f} -> {os.getloadavg()[0]:.2f}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    r = sub.add_parser("record")
    r.add_argument("--out", type=Path, required=True)
    r.add_argument("--sim-time", type=float, default=150.0)
    r.add_argument("--steps", type=int, default=200)
    p = sub.add_parser("replay")
    p.add_argument("path", type=Path)
    p.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    if args.command == "record":
        if not args.out.parent.is_dir():
            parser.error(f"--out: no directory {args.out.parent}")
        record(args.out, args.sim_time, args.steps)
    else:
        if not args.path.is_file():
            parser.error(f"no recording {args.path}")
        replay(args.path, args.repeats)


if __name__ == "__main__":
    main()
