"""Signal thresholds — the second perturbation, after packet loss — as a registry.

A threshold turns the geometry of every link (distance, line of sight) into an RSSI
estimate (where it has one) and a *warning* flag: the link is about to break. Each
threshold also makes the agent-side :class:`~mrcomm.ports.LinkSensor` with which a
robot judges its own links (:meth:`Threshold.sensor`).

A threshold is a registered variant: a :class:`Threshold` subclass with a pydantic
model of its parameters and a :class:`~mrcomm.specs.VariantSpec` naming both. Built in:
``none``, ``slt`` (distance stands in for signal strength) here; ``ssd`` and ``esd`` in
:mod:`mrcomm.net.signal_thresholds`.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from mrcomm.net.link_sensors import DistanceSensor, NoSensor
from mrcomm.specs import NoParams, VariantSpec

if TYPE_CHECKING:
    from mrcomm.net.signal.table import RssiTable
    from mrcomm.net.signal.trace import RssiTrace
    from mrcomm.ports import LinkSensor
    from mrcomm.world.scenario import Scenario

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


@functools.lru_cache(maxsize=4)
def upper_pairs(n: int) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """The unordered pairs of ``n`` nodes, (a, b) with a < b in row order, as two index
    arrays: one read-only copy per size, for whatever walks a team's pairs (the link
    recorder's pair states): 800 MB for 10,000 robots, so made only when first needed."""
    first, second = np.triu_indices(n, k=1)
    first.flags.writeable = False
    second.flags.writeable = False
    return first, second


class PairLayout:
    """The unordered pairs (a < b) of ``n`` nodes, in the row-major order of the upper
    triangle, and how one value per pair spreads into the symmetric (n, n) matrix in one
    gather. Both are built when first asked for: a large team whose links need no pair
    one by one never holds them (50 million pairs at 10,000 robots)."""

    def __init__(self, n: int) -> None:
        self.n = n
        self.count = n * (n - 1) // 2
        self._ends: tuple[NDArray[np.int64], NDArray[np.int64]] | None = None
        self._gather: NDArray[np.intp] | None = None

    @property
    def ends(self) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """Each pair's first and second node."""
        if self._ends is None:
            first, second = np.triu_indices(self.n, k=1)
            self._ends = (first.astype(np.int64), second.astype(np.int64))
        return self._ends

    def matrix(self, values: list[float], diagonal: float) -> FloatArray:
        """The (n, n) matrix whose (a, b) and (b, a) hold ``values[k]`` for pair k."""
        if self._gather is None:
            first, second = self.ends
            # Index n*(n-1)/2 is the diagonal's value, appended below.
            gather = np.full((self.n, self.n), self.count, dtype=np.intp)
            order = np.arange(self.count, dtype=np.intp)
            gather[first, second] = order
            gather[second, first] = order
            self._gather = gather
        return np.array([*values, diagonal])[self._gather]


@dataclass(frozen=True)
class PairGeometry:
    """The geometry of every pair at one step: the distance matrix (NaN for a node
    without a position), the same distances once per unordered pair (in ``layout``'s
    order; None for a large team whose model casts no rays, which only has the matrix),
    and — for thresholds that need it — line of sight per pair. Per-pair plain lists
    because a team has a handful of pairs: a Python loop over them is cheaper than a
    chain of small numpy operations, and one gather makes the matrix."""

    distance: FloatArray
    layout: PairLayout
    pair_distance: list[float] | None
    pair_sight: list[bool] | None = None
    #: (n, n) received power of each link, dBm, when the network model has a radio.
    power: FloatArray | None = None


class SignalResources(Protocol):
    """What a threshold may take from the run's shared per-scenario resources."""

    @property
    def scenario(self) -> Scenario: ...

    def signal_table(self, model_path: Path | None) -> RssiTable: ...

    def rssi_trace(self, path: Path) -> RssiTrace: ...


class Threshold:
    """Base class: evaluates RSSI and warnings for all pairs at once (network side),
    and makes each robot's link sensor (agent side)."""

    name: ClassVar[str] = ""
    #: Whether :meth:`evaluate` needs the line-of-sight matrix (costly: ray casts).
    needs_line_of_sight: ClassVar[bool] = False

    def evaluate(self, pairs: PairGeometry, now: float) -> tuple[FloatArray | None, BoolArray]:
        """Return (rssi or None, warning), both (n, n), for the pairs' geometry."""
        raise NotImplementedError

    def describe(self) -> dict[str, Any]:
        return {"threshold": self.name}

    @classmethod
    def build(cls, params: BaseModel, resources: SignalResources, ids: Sequence[str]) -> Threshold:
        """The network-side threshold for the nodes ``ids`` (in link-model order)."""
        raise NotImplementedError

    @classmethod
    def sensor(cls, params: BaseModel, resources: SignalResources) -> LinkSensor:
        """A new link sensor for one robot's agent."""
        raise NotImplementedError


class NoThreshold(Threshold):
    """No threshold: links never warn."""

    name = "none"

    @classmethod
    def build(cls, params: BaseModel, resources: SignalResources, ids: Sequence[str]) -> Threshold:
        return cls()

    @classmethod
    def sensor(cls, params: BaseModel, resources: SignalResources) -> LinkSensor:
        return NoSensor()

    def evaluate(self, pairs: PairGeometry, now: float) -> tuple[FloatArray | None, BoolArray]:
        return None, np.zeros(pairs.distance.shape, dtype=np.bool_)


class SltParams(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")

    warning_m: float = Field(
        4.0,
        gt=0.0,
        allow_inf_nan=False,
        description="a link warns beyond this distance",
        json_schema_extra={"unit": "m"},
    )


class DistanceThreshold(Threshold):
    """SLT — simulated loss threshold: distance stands in for signal strength
    (warning beyond 4.0 m by default; the limit is the network's range)."""

    name = "slt"

    @classmethod
    def build(cls, params: BaseModel, resources: SignalResources, ids: Sequence[str]) -> Threshold:
        assert isinstance(params, SltParams)
        return cls(params.warning_m)

    @classmethod
    def sensor(cls, params: BaseModel, resources: SignalResources) -> LinkSensor:
        assert isinstance(params, SltParams)
        return DistanceSensor(params.warning_m)

    def __init__(self, warning_m: float = 4.0) -> None:
        self.warning_m = warning_m

    def evaluate(self, pairs: PairGeometry, now: float) -> tuple[FloatArray | None, BoolArray]:
        return None, pairs.distance > self.warning_m  # NaN (virtual node) never warns

    def describe(self) -> dict[str, Any]:
        return {"threshold": self.name, "warning_m": self.warning_m}


NONE_SPEC = VariantSpec(
    kind="threshold",
    name="none",
    entry=NoThreshold,
    params=NoParams,
    summary="no signal threshold: links never warn",
)
SLT_SPEC = VariantSpec(
    kind="threshold",
    name="slt",
    entry=DistanceThreshold,
    params=SltParams,
    summary="SLT, simulated loss threshold: distance stands in for signal strength",
)
