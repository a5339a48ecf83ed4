"""Seeded, named random streams.

One run owns one seed; every purpose (each receiver's packet loss, each robot's odometry
noise, tie-breaks, ...) gets its own independent ``numpy.random.Generator`` derived from
(seed, purpose names) with ``SeedSequence``. Adding a stream never changes the others, so
the same configuration and seed always give the same result.
"""

from __future__ import annotations

import hashlib

import numpy as np


def _key(name: str) -> int:
    # A stable 32-bit key per name (Python's hash() is salted per process).
    return int.from_bytes(hashlib.blake2b(name.encode(), digest_size=4).digest(), "little")


def stream(seed: int, *names: str) -> np.random.Generator:
    """The generator for purpose ``names`` of the run seeded with ``seed``."""
    sequence = np.random.SeedSequence(entropy=seed, spawn_key=tuple(_key(n) for n in names))
    return np.random.default_rng(sequence)
