"""Path quality: whether a robot reaches a team mate through a chain of links, none of
them in warning, when its own link to that mate warns.

With relaying on (``network.relay``) a task status crosses a chain of robots, so a
robot out of good direct contact with a mate may still be in good contact through the
mates between them. A behaviour asks :func:`chain_links` for the best chain — the one
with the fewest links among the chains whose every link is inside the warning
threshold, at most ``hops`` links long — and may act on it instead of on the direct
link alone (LF's ``chain_hops``).

What a robot can know of links it is not on: the chain is judged from the positions
the robot knows (its mates' last poses), each mate-to-mate link by the robot's own
link sensor rule (:meth:`~mrcomm.ports.LinkSensor.warning_between`: distance for SLT,
the signal model with the robot's map for SSD). A sensor that only measures the
robot's own links (ESD) cannot judge the others: then only the direct link counts.
"""

from __future__ import annotations

from collections.abc import Mapping

from mrcomm.ports import LinkSensor
from mrcomm.world.geometry import Pose


def chain_links(
    sensor: LinkSensor,
    own: Pose,
    target: str,
    positions: Mapping[str, tuple[float, float]],
    hops: int,
    now: float,
) -> int | None:
    """The number of links of the best chain from this robot (at ``own``) to the mate
    ``target`` through the mates at ``positions`` (target included): the fewest links,
    every one outside warning, at most ``hops``; None when there is no such chain."""
    if target not in positions or hops < 1:
        return None
    # Breadth first: level k holds the mates reached over k good links.
    reached: dict[str, tuple[float, float]] = {}
    level: dict[str, tuple[float, float]] = {}
    for mate, (x, y) in positions.items():
        if not sensor.warning(mate, own, x, y, now):
            level[mate] = (x, y)
    links = 1
    while level:
        if target in level:
            return links
        if links == hops:
            return None
        reached.update(level)
        following: dict[str, tuple[float, float]] = {}
        for mate, (x, y) in positions.items():
            if mate in reached:
                continue
            for ax, ay in level.values():
                if sensor.warning_between(ax, ay, x, y) is False:
                    following[mate] = (x, y)
                    break
        level = following
        links += 1
    return None
