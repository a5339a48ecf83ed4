"""Signal thresholds — the second perturbation of SPEC §3 — as a registry.

A threshold turns the geometry of every link (distance, line of sight) into an RSSI
estimate (where it has one) and a *warning* flag: the link is about to break. Adding a
threshold is one class registered by name::

    @register_threshold("mine")
    class Mine(Threshold): ...

Built in: ``none``, ``slt`` (distance stands in for signal strength); ``ssd`` and
``esd`` live in :mod:`mrcomm.net.signal_thresholds`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from mrcomm.registry import Registry

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


class PairLayout:
    """The unordered pairs (a < b) of ``n`` nodes, and how one value per pair spreads
    into the symmetric (n, n) matrix in one gather."""

    def __init__(self, n: int) -> None:
        self.pairs = [(a, b) for a in range(n) for b in range(a + 1, n)]
        # Index n*(n-1)/2 is the diagonal's value, appended by :meth:`matrix`.
        gather = np.full((n, n), len(self.pairs), dtype=np.intp)
        for k, (a, b) in enumerate(self.pairs):
            gather[a, b] = gather[b, a] = k
        self._gather = gather

    def matrix(self, values: list[float], diagonal: float) -> FloatArray:
        """The (n, n) matrix whose (a, b) and (b, a) hold ``values[k]`` for pair k."""
        return np.array([*values, diagonal])[self._gather]


@dataclass(frozen=True)
class PairGeometry:
    """The geometry of every pair at one step: the distance matrix (NaN for a node
    without a position), the same distances once per unordered pair (in ``layout``'s
    order), and — for thresholds that need it — line of sight per pair. Per-pair plain
    lists because a team has a handful of pairs: a Python loop over them is cheaper than
    a chain of small numpy operations, and one gather makes the matrix."""

    distance: FloatArray
    layout: PairLayout
    pair_distance: list[float]
    pair_sight: list[bool] | None = None


class Threshold:
    """Base class: evaluates RSSI and warnings for all pairs at once."""

    name: ClassVar[str] = ""
    #: Whether :meth:`evaluate` needs the line-of-sight matrix (costly: ray casts).
    needs_line_of_sight: ClassVar[bool] = False
    #: Network types this threshold may be combined with (None: any).
    network_types: ClassVar[frozenset[str] | None] = None

    def evaluate(self, pairs: PairGeometry, now: float) -> tuple[FloatArray | None, BoolArray]:
        """Return (rssi or None, warning), both (n, n), for the pairs' geometry."""
        raise NotImplementedError

    def describe(self) -> dict[str, Any]:
        return {"threshold": self.name}


def _load_builtin() -> None:
    # Signal-model thresholds import their lookup tables' modules; load them on demand.
    from mrcomm.net import signal_thresholds  # noqa: F401


THRESHOLDS: Registry[type[Threshold]] = Registry("threshold", "threshold", _load_builtin)


def register_threshold(name: str) -> Callable[[type[Threshold]], type[Threshold]]:
    def decorate(cls: type[Threshold]) -> type[Threshold]:
        cls.name = name
        return THRESHOLDS.register(name)(cls)

    return decorate


def threshold_names() -> list[str]:
    return THRESHOLDS.names()


def threshold_class(name: str) -> type[Threshold]:
    return THRESHOLDS.get(name)


@register_threshold("none")
class NoThreshold(Threshold):
    """No threshold: links never warn."""

    def evaluate(self, pairs: PairGeometry, now: float) -> tuple[FloatArray | None, BoolArray]:
        return None, np.zeros(pairs.distance.shape, dtype=np.bool_)


@register_threshold("slt")
class DistanceThreshold(Threshold):
    """SLT — simulated loss threshold: distance stands in for signal strength
    (warning beyond 4.0 m by default; the limit is the network's range)."""

    def __init__(self, warning_m: float = 4.0) -> None:
        self.warning_m = warning_m

    def evaluate(self, pairs: PairGeometry, now: float) -> tuple[FloatArray | None, BoolArray]:
        return None, pairs.distance > self.warning_m  # NaN (virtual node) never warns

    def describe(self) -> dict[str, Any]:
        return {"threshold": self.name, "warning_m": self.warning_m}
