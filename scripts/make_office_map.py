"""Draw the office floor map that scenario S1 runs on and write it in ROS map_server
format (``data/maps/office.yaml`` + ``office.pgm``).

The floor is modelled on the original study's (first floor of an office building):

* a long corridor (1.8 m wide, ~52 m) that arches around a courtyard, with three fire
  doors that narrow it to 1.0 m;
* offices on both sides, each with a 0.85-0.9 m door;
* an irregular (asymmetric) half-oval conference room with a table, bulging into the
  courtyard, with two doors;
* a start room with two 0.8 m doors that let only one robot through at a time;
* two stairwells with no door onto this floor (free space no robot can reach).

Everything outside the building is occupied. The geometry is a pure function of the
constants below, so the output is deterministic (same bytes every run). Room layout is
given in corridor arc length ``s`` (metres along the corridor centre line, 0 at the
west end); ``r`` is the distance from the arc's centre.

Usage: ``python scripts/make_office_map.py [--out data/maps/office.yaml] [--preview p.png]``
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from mrcomm.world.mapio import save_map
from mrcomm.world.occupancy import OccupancyGrid

RESOLUTION = 0.05
WIDTH_M, HEIGHT_M = 54.0, 23.5
#: Centre of the corridor arc (map frame) and the corridor centre-line radius.
CENTRE = (27.0, -5.0)
RADIUS = 22.0
CORRIDOR_LENGTH = 52.2  # along the centre line
CORRIDOR_HALF_WIDTH = 0.9
WALL = 0.15  # interior walls
OUTER_DEPTH = 4.2  # offices on the convex (north) side
INNER_DEPTH = 4.0  # offices on the concave (courtyard) side
FIRE_DOORS = (7.0, 34.0, 46.5)  # s of each fire door
FIRE_DOOR_WIDTH = 1.0
FIRE_WALL = 0.2


@dataclass(frozen=True)
class Room:
    """A room in one band of the floor: from ``s0`` to ``s1`` along the corridor."""

    name: str
    side: str  # "outer" (convex side) or "inner" (courtyard side)
    s0: float
    s1: float
    doors: tuple[float, ...] = ()  # s of each door centre
    door_width: float = 0.9
    solid: bool = False  # stairwell: walled all round, no door (unreachable)


ROOMS: tuple[Room, ...] = (
    # Convex (north) side, west to east.
    Room("office N1", "outer", 0.0, 5.0, (2.5,)),
    Room("office N2", "outer", 5.0, 9.0, (8.0,), 0.85),
    Room("office N3", "outer", 9.0, 13.0, (12.0,)),
    Room("start room", "outer", 13.0, 20.0, (14.0, 19.0), 0.8),
    Room("office N5", "outer", 20.0, 24.0, (21.0,), 0.85),
    Room("office N6", "outer", 24.0, 28.0, (25.0,)),
    Room("office N7", "outer", 28.0, 32.0, (31.0,), 0.85),
    Room("office N8", "outer", 32.0, 36.0, (33.0,)),
    Room("office N9", "outer", 36.0, 40.0, (37.0,), 0.85),
    Room("office N10", "outer", 40.0, 44.0, (43.0,)),
    Room("office N11", "outer", 44.0, 48.0, (45.0,), 0.85),
    Room("office N12", "outer", 48.0, CORRIDOR_LENGTH, (50.0,)),
    # Concave (courtyard) side, west to east; the conference room is drawn separately.
    Room("office S1", "inner", 0.0, 5.5, (3.0,)),
    Room("office S2", "inner", 5.5, 10.5, (9.0,), 0.85),
    Room("stair core W", "inner", 10.5, 15.0, solid=True),
    Room("kitchen", "inner", 15.0, 20.0, (16.5,)),
    Room("office S5", "inner", 34.0, 38.5, (35.5,), 0.85),
    Room("stair core E", "inner", 38.5, 43.0, solid=True),
    Room("office S7", "inner", 43.0, 47.5, (44.5,)),
    Room("office S8", "inner", 47.5, CORRIDOR_LENGTH, (49.5,), 0.85),
)

# Conference room: a half-oval on the courtyard side, flat side along the corridor wall,
# asymmetric (longer to the west) so it is irregular, spanning s in [20, 34].
CONF_S0, CONF_S1 = 20.0, 34.0
CONF_CENTRE_S = 27.6
CONF_DEPTH = 7.0
CONF_LEAN = 0.15  # depth change per metre along the room (m/m)
CONF_DOORS = (22.5, 31.5)
CONF_TABLE = (2.2, 1.0)  # semi-axes of the oval table (along, across)
CONF_TABLE_DEPTH = 3.2  # table centre, metres in from the corridor wall


def _polar(shape: tuple[int, int]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(r, s) of every cell centre: distance from the arc centre, corridor arc length."""
    iy, ix = np.indices(shape, dtype=np.float64)
    x = (ix + 0.5) * RESOLUTION - CENTRE[0]
    y = (iy + 0.5) * RESOLUTION - CENTRE[1]
    r = np.hypot(x, y)
    phi = np.arctan2(y, x)
    phi_west = math.pi / 2 + CORRIDOR_LENGTH / (2 * RADIUS)
    return r, (phi_west - phi) * RADIUS


def _between_radial_walls(
    r: NDArray[np.float64], s: NDArray[np.float64], s0: float, s1: float, wall: float
) -> NDArray[np.bool_]:
    """Cells between the radial walls at ``s0`` and ``s1`` (each ``wall`` m thick,
    measured in metres at the cell's own radius so thickness is constant)."""
    scale = r / RADIUS
    return ((s - s0) * scale >= wall / 2) & ((s1 - s) * scale >= wall / 2)


def _across(
    r: NDArray[np.float64], s: NDArray[np.float64], s_c: float, width: float
) -> NDArray[np.bool_]:
    """Cells within ``width``/2 metres (at their radius) of the radial line at ``s_c``."""
    return np.abs(s - s_c) * (r / RADIUS) <= width / 2


def _band(side: str, depth: float) -> tuple[float, float]:
    """Radial extent (r_min, r_max) of a room band on one side of the corridor."""
    near = CORRIDOR_HALF_WIDTH + WALL
    if side == "outer":
        return RADIUS + near, RADIUS + near + depth
    return RADIUS - near - depth, RADIUS - near


def draw_office() -> OccupancyGrid:
    """Rasterise the floor: start fully occupied and carve out every free space."""
    shape = (round(HEIGHT_M / RESOLUTION), round(WIDTH_M / RESOLUTION))
    r, s = _polar(shape)
    free = np.zeros(shape, dtype=np.bool_)
    in_corridor_band = np.abs(r - RADIUS) <= CORRIDOR_HALF_WIDTH
    free |= in_corridor_band & _between_radial_walls(r, s, 0.0, CORRIDOR_LENGTH, 2 * WALL)
    for s_f in FIRE_DOORS:
        # A fire wall across the corridor leaves a 1.0 m opening in the middle.
        wall = _across(r, s, s_f, FIRE_WALL) & in_corridor_band
        free &= ~(wall & (np.abs(r - RADIUS) > FIRE_DOOR_WIDTH / 2))
    # A door is cut through the corridor wall: a little deeper than the wall on both
    # sides so it always joins the room to the corridor.
    door_r = {
        "outer": (RADIUS + CORRIDOR_HALF_WIDTH - 0.05, RADIUS + CORRIDOR_HALF_WIDTH + WALL + 0.05),
        "inner": (RADIUS - CORRIDOR_HALF_WIDTH - WALL - 0.05, RADIUS - CORRIDOR_HALF_WIDTH + 0.05),
    }
    for room in ROOMS:
        r0, r1 = _band(room.side, OUTER_DEPTH if room.side == "outer" else INNER_DEPTH)
        free |= (r >= r0) & (r <= r1) & _between_radial_walls(r, s, room.s0, room.s1, WALL)
        if room.solid:
            # A stairwell: enclosed, no door, the two flights split by a central wall.
            free &= ~(_across(r, s, (room.s0 + room.s1) / 2, WALL) & (r >= r0 + 1.0) & (r <= r1))
            continue
        lo, hi = door_r[room.side]
        for s_d in room.doors:
            free |= (r >= lo) & (r <= hi) & _across(r, s, s_d, room.door_width)
    free |= _conference_room(r, s)
    lo, hi = door_r["inner"]
    for s_d in CONF_DOORS:
        free |= (r >= lo) & (r <= hi) & _across(r, s, s_d, 0.9)
    return OccupancyGrid(~free, RESOLUTION, (0.0, 0.0))


def _conference_room(r: NDArray[np.float64], s: NDArray[np.float64]) -> NDArray[np.bool_]:
    """The half-oval room: in (u, v) = (arc length along its corridor wall, depth into
    the courtyard) it is half an ellipse whose west and east halves differ in width."""
    r_top = RADIUS - CORRIDOR_HALF_WIDTH - WALL
    # u in metres at the cell's own radius, so the oval stays round as it deepens.
    u = (s - CONF_CENTRE_S) * (r / RADIUS)
    v = r_top - r
    west = (CONF_CENTRE_S - CONF_S0) * (r_top / RADIUS) - WALL
    east = (CONF_S1 - CONF_CENTRE_S) * (r_top / RADIUS) - WALL
    half_width = np.where(u < 0, west, east)
    # Deeper to the west than to the east: the bulge leans, as the original's did.
    depth = CONF_DEPTH - CONF_LEAN * u
    room = (v >= 0) & ((u / half_width) ** 2 + (v / depth) ** 2 <= 1.0)
    # The oval table in the middle of the room.
    tu = u / CONF_TABLE[0]
    tv = (v - CONF_TABLE_DEPTH) / CONF_TABLE[1]
    table = tu**2 + tv**2 <= 1.0
    # Walls to the neighbouring rooms where the office band runs alongside; below the
    # band the oval bulges freely into the courtyard.
    beside_offices = r >= _band("inner", INNER_DEPTH)[0] - WALL
    walls_ok = ~beside_offices | _between_radial_walls(r, s, CONF_S0, CONF_S1, WALL)
    return np.asarray(room & ~table & walls_ok)


def point_at(s_pos: float, offset: float) -> tuple[float, float]:
    """Map-frame point at corridor arc length ``s_pos``, ``offset`` metres outward from
    the corridor centre line (negative: towards the courtyard). For placing poses."""
    phi = math.pi / 2 + CORRIDOR_LENGTH / (2 * RADIUS) - s_pos / RADIUS
    rad = RADIUS + offset
    return CENTRE[0] + rad * math.cos(phi), CENTRE[1] + rad * math.sin(phi)


def check(grid: OccupancyGrid, radius: float = 0.2) -> None:
    """Fail loudly if any room with a door is cut off for a robot of ``radius``."""
    labels, _ = ndimage.label(~grid.inflated(radius).occupied)
    corridor = labels[grid.world_to_cell(*point_at(1.0, 0.0))]
    assert corridor > 0, "corridor blocked"
    for room in ROOMS:
        depth = OUTER_DEPTH if room.side == "outer" else INNER_DEPTH
        sign = 1.0 if room.side == "outer" else -1.0
        x, y = point_at(
            (room.s0 + room.s1) / 2 - 1.0, sign * (CORRIDOR_HALF_WIDTH + WALL + depth / 2)
        )
        if room.solid:
            assert labels[grid.world_to_cell(x, y)] != corridor, f"{room.name} reachable"
            continue
        assert labels[grid.world_to_cell(x, y)] == corridor, f"{room.name} unreachable"
    x, y = point_at(CONF_S0 + 1.2, -(CORRIDOR_HALF_WIDTH + WALL + 1.0))
    assert labels[grid.world_to_cell(x, y)] == corridor, "conference room unreachable"


def render(grid: OccupancyGrid, path: Path) -> None:
    """A PNG preview with room names (for looking at the map, not used by the code)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(16, 7.5))
    ax.imshow(~grid.occupied, origin="lower", extent=grid.extent, cmap="gray", vmin=0, vmax=1)
    for room in ROOMS:
        depth = OUTER_DEPTH if room.side == "outer" else INNER_DEPTH
        sign = 1.0 if room.side == "outer" else -1.0
        x, y = point_at((room.s0 + room.s1) / 2, sign * (CORRIDOR_HALF_WIDTH + WALL + depth / 2))
        ax.text(x, y, room.name, ha="center", va="center", fontsize=6, color="tab:blue")
    x, y = point_at(CONF_CENTRE_S, -(CORRIDOR_HALF_WIDTH + WALL + 5.5))
    ax.text(x, y, "conference", ha="center", fontsize=7, color="tab:blue")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    root = Path(__file__).resolve().parent.parent
    parser.add_argument("--out", type=Path, default=root / "data" / "maps" / "office.yaml")
    parser.add_argument("--preview", type=Path, default=None, help="also render a PNG here")
    args = parser.parse_args(argv)
    grid = draw_office()
    check(grid)
    save_map(
        grid,
        args.out,
        comment="Office floor for scenario S1. Generated by scripts/make_office_map.py;\n"
        "edit the script and re-run it rather than editing this file or the image.",
    )
    if args.preview is not None:
        render(grid, args.preview)
    free = float((~grid.occupied).sum()) * RESOLUTION**2
    print(f"wrote {args.out}: {grid.width}x{grid.height} cells, {free:.0f} m^2 free")


if __name__ == "__main__":
    main()
