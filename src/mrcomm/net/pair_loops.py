"""The per-pair loops of the link model, compiled where numba is there
(:mod:`mrcomm.compiled`): each pair's distance, which pairs' rays must be cast again,
and what the casts found.

A team of n robots has n(n−1)/2 pairs (4,950 for S4's 100): these loops were one Python
iteration per pair and step. They compute what :class:`~mrcomm.net.links.LinkModel` did
pair by pair, in the same arithmetic: distances are Python's ``math.hypot`` (CPython's
correctly rounded algorithm, :func:`hypot`, not the C library's, which differs in the
last bit for about one pair in 150), so every result is the same to the last bit
(``tests/net/test_pair_loops.py``).
"""

from __future__ import annotations

import math
from typing import Any

from mrcomm.compiled import compiled

_VELTKAMP = 134217729.0  # 2^27 + 1: splits a double into two halves of 26 bits


@compiled
def _split(x: float) -> tuple[float, float]:
    t = x * _VELTKAMP
    hi = t - (t - x)
    return hi, x - hi


@compiled
def _product(x: float, y: float) -> tuple[float, float]:
    """x·y exactly, as the sum of two doubles (Dekker)."""
    xh, xl = _split(x)
    yh, yl = _split(y)
    p = xh * yh
    q = xh * yl + xl * yh
    z = p + q
    return z, p - z + q + xl * yl


@compiled
def hypot(x: float, y: float) -> float:
    """√(x² + y²) as CPython's ``math.hypot`` computes it (Modules/mathmodule.c,
    ``vector_norm``: scaled, compensated sums and one differential correction of the
    square root), so the same double."""
    x, y = abs(x), abs(y)
    if math.isinf(x) or math.isinf(y):
        return math.inf
    if math.isnan(x) or math.isnan(y):
        return math.nan
    largest = max(x, y)
    if largest == 0.0:
        return largest
    exponent = math.frexp(largest)[1]
    if exponent < -1023:  # (subnormal: not a distance in metres)
        return math.sqrt(x * x + y * y)
    scale = math.ldexp(1.0, -exponent)
    total, frac1, frac2 = 1.0, 0.0, 0.0
    for value in (x * scale, y * scale):
        hi, lo = _product(value, value)
        s = total + hi
        frac2 += (total - s) + hi
        total = s
        frac1 += lo
    h = math.sqrt(total - 1.0 + (frac1 + frac2))
    hi, lo = _product(-h, h)
    s = total + hi
    frac2 += (total - s) + hi
    total = s
    frac1 += lo
    h += (total - 1.0 + (frac1 + frac2)) / (2.0 * h)
    return h / scale


@compiled
def pair_distances(xy: Any, first: Any, second: Any, out: Any) -> None:
    """``out[k]``: the distance between nodes ``first[k]`` and ``second[k]`` (rows of
    ``xy``; NaN for a node without a position)."""
    for k in range(first.shape[0]):
        a, b = first[k], second[k]
        out[k] = hypot(xy[a, 0] - xy[b, 0], xy[a, 1] - xy[b, 1])


@compiled
def rays_to_cast(
    xy: Any, first: Any, second: Any, distance: Any, reach: float, cast_from: Any,
    cast_slack: Any, cast_walls: Any, walls: Any, recast: Any, segments: Any,
) -> int:  # fmt: skip
    """Each pair's walls as last cast (into ``walls``; beyond ``reach`` 1, without a
    position or at distance 0 none), and the pairs within reach whose ray must be cast
    again (into ``recast`` and their ends into ``segments``; how many returned): never
    cast (``cast_from`` NaN), or an end moved at least its ``cast_slack`` since."""
    count = 0
    for k in range(first.shape[0]):
        dist = distance[k]
        if not (0.0 < dist <= reach):  # also False for NaN (virtual node)
            walls[k] = 1 if dist > reach else 0
            continue
        a, b = first[k], second[k]
        ax, ay, bx, by = xy[a, 0], xy[a, 1], xy[b, 0], xy[b, 1]
        if (
            math.isnan(cast_from[k, 0])
            or hypot(ax - cast_from[k, 0], ay - cast_from[k, 1]) >= cast_slack[k]
            or hypot(bx - cast_from[k, 2], by - cast_from[k, 3]) >= cast_slack[k]
        ):
            recast[count] = k
            segments[count, 0], segments[count, 1] = ax, ay
            segments[count, 2], segments[count, 3] = bx, by
            count += 1
        walls[k] = cast_walls[k]
    return count


@compiled
def record_casts(
    recast: Any, segments: Any, counted: Any, clearances: Any, obstructed_slack: float,
    cast_from: Any, cast_slack: Any, cast_walls: Any, walls: Any,
) -> None:  # fmt: skip
    """What the casts of the pairs ``recast`` found: their walls, and how far an end may
    move before the answer may change (the clearance in line of sight, else
    ``obstructed_slack``)."""
    for j in range(recast.shape[0]):
        k = recast[j]
        walls[k] = cast_walls[k] = counted[j]
        cast_slack[k] = clearances[j] if clearances[j] >= 0.0 else obstructed_slack
        for c in range(4):
            cast_from[k, c] = segments[j, c]


@compiled
def pair_power(
    distance: Any, walls: Any, first: Any, second: Any, field: Any, base: float,
    slope: float, wall_loss: float, reference_m: float, out: Any,
) -> None:  # fmt: skip
    """Mean received power of each pair, dBm: ``base`` − ``slope``·log10(d / d0) −
    ``wall_loss`` per wall + the pair's shadowing (the scaled sum of its ends'
    ``field``); NaN for a pair with a node without a position."""
    scale = 1.0 / math.sqrt(2.0)
    for k in range(distance.shape[0]):
        d = distance[k]
        if math.isnan(d):
            out[k] = math.nan
            continue
        loss = slope * math.log10(max(d, reference_m) / reference_m)
        out[k] = base - loss - wall_loss * walls[k] + (field[first[k]] + field[second[k]]) * scale
