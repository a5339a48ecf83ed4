"""Network models: which links can carry a message at all.

* ``wlan`` — infrastructure (access points): coverage of the operating area is complete
  and uniform, distance never cuts a link.
* ``ah`` — ad-hoc, peer to peer: a hard communication limit (8.0 m by default) between
  two nodes; beyond it nothing is delivered, and a node that comes back into range
  rejoins by itself.
* ``radio`` (:mod:`mrcomm.net.radio.model`) — received power from distance, walls and
  shadowing decides range, packet error and the senders' queues.

Each is a registered variant (:data:`WLAN_SPEC`, :data:`AH_SPEC`); a new model is a
:class:`NetworkModel` subclass with its parameter model and spec, in one module.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from enum import StrEnum
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, Field

from mrcomm.net.relay import RelayParams
from mrcomm.specs import NoParams, VariantSpec

#: Hard communication limit of the ad-hoc network, metres.
AH_RANGE_M = 8.0


class NetworkType(StrEnum):
    """The built-in network models' names."""

    WLAN = "wlan"
    AH = "ah"


class NetworkModel:
    """Decides which node pairs are connected, from their distances."""

    name: ClassVar[str] = ""
    #: Beyond this distance nothing is delivered (inf: no distance limit).
    reach_m: float = math.inf
    #: Whether range is decided from received power, which needs the walls between
    #: nodes (:class:`~mrcomm.net.radio.model.RadioNetwork`); otherwise from distance.
    needs_walls: ClassVar[bool] = False

    def __init__(self, params: BaseModel | None = None) -> None:
        """``params``: the model's validated parameters (its spec's parameter model)."""

    @classmethod
    def build(cls, params: BaseModel, resources: Any, seed: int) -> NetworkModel:
        """The model of one run: ``resources`` are the run's per-scenario resources
        (the map), ``seed`` the run's seed. Models that need neither take only their
        parameters."""
        return cls(params)

    @classmethod
    def measured_power_dbm(cls, params: Any, distance_m: float) -> float | None:
        """The power (dBm) a robot's card would measure of a peer ``distance_m`` away in
        line of sight on this network, for a pulse threshold (ESD) that measures it;
        None when the network has no signal to measure."""
        return None

    @classmethod
    def live_refusal(cls, params: Any) -> str | None:
        """Why this model's ``params`` cannot run in live mode (one line), or None."""
        return None

    @classmethod
    def advice(cls, config: Any) -> list[str]:
        """Warnings about a run configuration with this model (one line each)."""
        return []

    def channel(self, ids: Sequence[str]) -> Any:
        """The per-message part of the model for the nodes ``ids`` (a
        :class:`~mrcomm.net.radio.channel.RadioChannel`), or None when messages are
        decided by range and loss alone."""
        return None

    def live_links(self, grid: Any, node_ids: Sequence[str], aliases: Any) -> Any:
        """Live mode: how one process judges each link a message came over — for a
        model that decides range and loss per message from received power (a
        :class:`~mrcomm.net.radio.links.RadioLinks` on the map ``grid``); None for a
        model whose decisions need only distance (``in_range``)."""
        return None

    def connected(self, distance: NDArray[np.float64]) -> NDArray[np.bool_]:
        """(n, n) connectivity from the (n, n) distances (NaN: a node without a
        position, e.g. a virtual task assigner, is always connected)."""
        return np.ones(distance.shape, dtype=np.bool_)

    def in_range(self, distance: float) -> bool:
        """Whether one link of this length can carry a message."""
        return True

    # -- models that decide range from received power (needs_walls) ----------------
    def pair_power(
        self,
        xy: Sequence[Sequence[float]],
        pairs: tuple[NDArray[np.int64], NDArray[np.int64]],
        distance: NDArray[np.float64],
        walls: NDArray[np.int64],
    ) -> NDArray[np.float64]:
        """Received power of each unordered pair of nodes (``pairs``: their first and
        second nodes, rows of ``xy``), dBm, the same both ways (NaN for a pair with a
        node without a position)."""
        raise NotImplementedError(f"network model {self.name!r} does not model power")

    def offsets(self, n: int) -> NDArray[np.float64]:
        """(n, n) fixed per-direction offsets added to the pairs' power, dB."""
        return np.zeros((n, n))

    def in_range_power(self, power: NDArray[np.float64]) -> NDArray[np.bool_]:
        """(n, n) range from the (n, n) received power (NaN: always in range)."""
        raise NotImplementedError(f"network model {self.name!r} does not model power")

    def describe(self) -> dict[str, float | str]:
        return {"network": self.name}


class Wlan(NetworkModel):
    """Infrastructure WLAN: every link connected."""

    name = "wlan"


class AdHocParams(RelayParams):
    range_m: float = Field(
        AH_RANGE_M,
        gt=0.0,
        allow_inf_nan=False,
        description="communication limit between two nodes",
        json_schema_extra={"unit": "m"},
    )


class AdHoc(NetworkModel):
    """Ad-hoc network with a hard range limit."""

    name = "ah"

    def __init__(self, params: AdHocParams) -> None:
        if not isinstance(params, AdHocParams):  # no fallback to defaults
            raise TypeError(f"AdHoc takes AdHocParams, got {type(params).__name__}")
        self.reach_m = params.range_m

    def connected(self, distance: NDArray[np.float64]) -> NDArray[np.bool_]:
        return ~(distance > self.reach_m)  # NaN (virtual) stays connected

    def in_range(self, distance: float) -> bool:
        return distance <= self.reach_m

    def describe(self) -> dict[str, float | str]:
        return {"network": self.name, "range_m": self.reach_m}


WLAN_SPEC = VariantSpec(
    kind="network",
    name="wlan",
    entry=Wlan,
    params=NoParams,
    summary="infrastructure WLAN: complete, uniform coverage; distance never cuts a link",
    aliases=("wifi", "infrastructure", "access-point"),
)
AH_SPEC = VariantSpec(
    kind="network",
    name="ah",
    entry=AdHoc,
    params=AdHocParams,
    summary="ad-hoc, peer to peer: nothing is delivered beyond range_m",
    aliases=("adhoc", "ad-hoc", "manet", "mesh", "peer-to-peer"),
)
