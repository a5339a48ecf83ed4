"""The radio seen one link at a time: for live mode, where each process judges the
messages that reach its own agents and queues the ones they send.

In simulation the link model evaluates every pair once per step and the in-process bus
consults the :class:`~mrcomm.net.radio.channel.RadioChannel` with that step's power
matrix. A live receiver knows only its own position and where each sender was last
heard, so it evaluates the one link a message came over, with the same pieces: the
same ray cast (:func:`mrcomm.net.links.cast_ray`, walls only within the radio's reach,
beyond it counted as one), the same reciprocal power with shadowing
(:meth:`RadioNetwork.pair_power`), the same per-direction offset of the same node
index, the same sensitivity cut and the same packet error with the receiver's own
fading stream. A sender's transmit queue lives where the sender is: its process
queues what its agents publish (:meth:`RadioLinks.transmit`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from mrcomm.net.links import cast_ray
from mrcomm.net.radio.channel import RadioChannel
from mrcomm.world.occupancy import OccupancyGrid

# The one pair of a link: node 0 and node 1 (for the network model's pair power).
_FIRST = np.array([0], dtype=np.int64)
_SECOND = np.array([1], dtype=np.int64)

if TYPE_CHECKING:  # the model makes these: only its type is needed here
    from mrcomm.net.radio.model import RadioNetwork

Point = tuple[float, float]


class RadioLinks:
    """One run's radio for the agents of one live process (see the module docstring).

    ``node_ids`` are the run's nodes in the link model's order (robots, then the task
    assigner) and ``aliases`` the nodes that share another's position (an assigner
    hosted on a robot): they are what fix each node's index, hence its offsets."""

    def __init__(
        self,
        network: RadioNetwork,
        grid: OccupancyGrid,
        node_ids: Sequence[str],
        aliases: Mapping[str, str],
    ) -> None:
        self.network = network
        self.grid = grid
        evaluated = [node for node in node_ids if node not in aliases]
        #: Each node's row in the offsets (an alias has its host's).
        self._row = {node: evaluated.index(aliases.get(node, node)) for node in node_ids}
        #: Each node's place in the channel (its fading stream, its queue).
        self._slot = {node: i for i, node in enumerate(node_ids)}
        self._offsets = network.offsets(len(evaluated)).tolist()
        self.channel: RadioChannel = network.channel(tuple(node_ids))
        self._sensitivity = network.profile.sensitivity_dbm
        grid.prepare_ray_casts()

    def knows(self, node: str) -> bool:
        return node in self._slot

    def power(
        self, sender: str, at: Point | None, receiver: str, to: Point | None
    ) -> tuple[float, int]:
        """Received power (dBm) of ``sender``'s packets at ``receiver`` with the two at
        ``at`` and ``to`` (NaN when either has no position: no radio), and the walls
        between them (0: line of sight)."""
        row, column = self._row[sender], self._row[receiver]
        if at is None or to is None or row == column:
            # No position, or one antenna (an assigner and its host robot): no radio.
            return math.nan, 0
        reach = self.network.reach_m
        distance = math.hypot(at[0] - to[0], at[1] - to[1])
        if 0.0 < distance <= reach:
            walls, _ = cast_ray(self.grid, at[0], at[1], to[0], to[1], True)
        else:  # as the link model: beyond the reach counts as obstructed, uncast
            walls = 1 if distance > reach else 0
        mean = float(
            self.network.pair_power(
                [at, to], (_FIRST, _SECOND), np.array([distance]), np.array([walls])
            )[0]
        )
        return mean + self._offsets[row][column], walls

    def judge(
        self, sender: str, at: Point | None, receiver: str, to: Point | None, bits: int
    ) -> tuple[bool, float]:
        """Whether the link is in range, and the probability that this message of
        ``bits`` is lost to packet error (fading drawn from the receiver's stream)."""
        power, walls = self.power(sender, at, receiver, to)
        if power < self._sensitivity:
            return False, 0.0
        return True, self.channel.error_at(self._slot[receiver], power, walls == 0, bits)

    def bits_of(self, wire_bytes: int) -> int:
        """Bits on the air for a message of ``wire_bytes`` (see :class:`RadioChannel`)."""
        return self.channel.bits_of(wire_bytes)

    def transmit(self, sender: str, stamp: float, bits: int) -> float | None:
        """Queue one message of ``sender`` at mission time ``stamp``: its delay, or None
        when its queue overflows (see :meth:`RadioChannel.transmit`)."""
        return self.channel.transmit(self._slot[sender], stamp, bits)
