"""One-lane passages found on a map: doors and corridors narrower than the width
asked for, joining two wider areas, at any orientation; nooks and wide doors are not."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mrcomm.world.occupancy import OccupancyGrid
from mrcomm.world.passages import find_passages

RES = 0.05


def two_rooms(door: float, wall: float = 0.15, nook: bool = False) -> OccupancyGrid:
    """A 10 x 6 m box split by a wall at x = 5 with a door of width ``door`` centred
    at y = 3; ``nook``: also a 0.9 m wide, 1 m deep alcove in the box's top wall."""
    width, height = int(10 / RES), int(6 / RES)
    occupied = np.zeros((height, width), dtype=bool)
    occupied[:3, :] = occupied[-3:, :] = True
    occupied[:, :3] = occupied[:, -3:] = True
    x0 = int(5 / RES)
    occupied[:, x0 : x0 + int(wall / RES)] = True
    y0, y1 = int((3 - door / 2) / RES), int((3 + door / 2) / RES)
    occupied[y0:y1, x0 : x0 + int(wall / RES)] = False
    if nook:  # the top wall is 1 m thick there, less an alcove 0.9 m wide
        occupied[-int(1 / RES) :, : int(2 / RES)] = True
        occupied[-int(1 / RES) : -3, int(0.5 / RES) : int(1.4 / RES)] = False
    return OccupancyGrid(occupied, RES)


def test_a_door_narrower_than_the_width_is_one_passage_across_its_wall() -> None:
    passages = find_passages(two_rooms(0.9), max_width=1.3)
    assert len(passages) == 1
    door = passages.passages[0]
    assert door.cx == pytest.approx(5.075, abs=0.05)
    assert door.cy == pytest.approx(3.0, abs=0.05)
    assert abs(door.ax) == pytest.approx(1.0, abs=0.02)  # the way through: along x
    assert door.width == pytest.approx(0.9, abs=0.1)
    assert passages.at(5.07, 3.0) == 0
    assert passages.at(4.0, 3.0) is None  # the room before it
    assert passages.near(3.5, 3.0, 2.0) == (0,)  # within reach (2 m)
    assert passages.near(0.5, 0.5, 2.0) == ()
    assert passages.near(0.5, 0.5, 4.0) == (0,)
    # In the room 2.55 m down the wall from the door: nearer its centre than the
    # corners of its box grown by the reach (1.5 m), but farther than the reach across
    # its axis (by more than a cell of the lookup)
    assert math.hypot(0.2, 2.55) < math.hypot(door.half_length + 1.5, door.half_width + 1.5)
    assert passages.near(door.cx - 0.2, door.cy + 2.55, 1.5) == ()
    assert passages.near(door.cx - 0.2, door.cy + 1.9, 1.5) == (0,)


def test_wide_doors_nooks_and_gaps_no_robot_fits_are_not_passages() -> None:
    assert len(find_passages(two_rooms(2.0), max_width=1.3)) == 0
    assert len(find_passages(two_rooms(0.9), max_width=0.0)) == 0  # switched off
    assert len(find_passages(two_rooms(0.9), max_width=1.3, min_width=1.2)) == 0
    with_nook = find_passages(two_rooms(0.9, nook=True), max_width=1.3)
    assert len(with_nook) == 1  # the door; the alcove opens on one room only
    assert with_nook.at(0.9, 5.5) is None


@pytest.mark.parametrize("angle", [0.0, 0.3, math.pi / 4, 1.1])
def test_a_door_in_a_thin_wall_is_found_at_any_orientation(angle: float) -> None:
    """A one-cell wall through the middle of a 12 m box, turned by ``angle``, with a
    0.8 m door at the centre: the door is found, its axis across the wall."""
    n = int(12 / RES)
    yy, xx = np.mgrid[0:n, 0:n]
    cx = cy = n / 2
    u = (xx - cx) * math.cos(angle) + (yy - cy) * math.sin(angle)  # along the wall
    v = -(xx - cx) * math.sin(angle) + (yy - cy) * math.cos(angle)
    occupied = (np.abs(v) < 0.75) & (np.abs(u) > 0.4 / RES)
    occupied[:2, :] = occupied[-2:, :] = occupied[:, :2] = occupied[:, -2:] = True
    passages = find_passages(OccupancyGrid(occupied, RES), max_width=1.3, min_width=0.4)
    assert len(passages) == 1
    door = passages.passages[0]
    assert math.hypot(door.cx - 6.0, door.cy - 6.0) < 0.1
    across_wall = (-math.sin(angle), math.cos(angle))
    assert abs(door.ax * across_wall[0] + door.ay * across_wall[1]) > 0.95


def test_a_narrow_corridor_is_one_passage_along_it() -> None:
    """Two rooms joined by a 1 m wide, 4 m long corridor."""
    occupied = np.ones((int(6 / RES), int(14 / RES)), dtype=bool)
    occupied[3:-3, 3 : int(5 / RES)] = False  # west room
    occupied[3:-3, int(9 / RES) : -3] = False  # east room
    occupied[int(2.5 / RES) : int(3.5 / RES), int(5 / RES) : int(9 / RES)] = False
    passages = find_passages(OccupancyGrid(occupied, RES), max_width=1.3)
    assert len(passages) == 1
    corridor = passages.passages[0]
    assert abs(corridor.ax) == pytest.approx(1.0, abs=0.02)
    assert corridor.half_length == pytest.approx(2.0, abs=0.15)
    assert passages.at(7.0, 3.0) == 0


@pytest.mark.parametrize("angle", [0.0, 0.3, math.pi / 4, 1.1])
def test_the_passages_near_a_point_are_those_within_reach_along_and_across_the_axis(
    angle: float,
) -> None:
    """Every point within reach of a door's box (along its axis and across it) is handed
    the door, and nearly every point beyond is not (those in cells the grown box
    touches are)."""
    n = int(12 / RES)
    yy, xx = np.mgrid[0:n, 0:n]
    u = (xx - n / 2) * math.cos(angle) + (yy - n / 2) * math.sin(angle)
    v = -(xx - n / 2) * math.sin(angle) + (yy - n / 2) * math.cos(angle)
    occupied = (np.abs(v) < 0.75) & (np.abs(u) > 0.4 / RES)
    occupied[:2, :] = occupied[-2:, :] = occupied[:, :2] = occupied[:, -2:] = True
    passages = find_passages(OccupancyGrid(occupied, RES), max_width=1.3, min_width=0.4)
    door = passages.passages[0]
    rng = np.random.default_rng(3)
    reach = 1.5
    listed = unlisted = 0
    for x, y in rng.uniform(1.0, 11.0, size=(4000, 2)).tolist():
        within = (
            abs(door.along(x, y)) - door.half_length <= reach
            and abs(door.across(x, y)) - door.half_width <= reach
        )
        near = passages.near(x, y, reach)
        if within:
            assert near == (0,)
            listed += 1
        elif near == ():
            unlisted += 1
    assert listed > 200
    # Beyond the box grown by the reach, only points in its border cells are listed.
    assert unlisted > 0.85 * (4000 - listed)
