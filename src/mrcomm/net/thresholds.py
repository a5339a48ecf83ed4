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


@dataclass(frozen=True)
class PairGeometry:
    """The geometry of every pair at one step, in the forms thresholds use: the
    distance matrix (NaN for a node without a position), and — for thresholds that need
    line of sight — the same distances and the line-of-sight flags as nested lists
    (cheaper than numpy for a team's handful of pairs)."""

    distance: FloatArray
    distance_rows: list[list[float]] | None = None
    sight_rows: list[list[bool]] | None = None


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
