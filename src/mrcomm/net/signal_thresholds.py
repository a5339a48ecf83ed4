"""Signal-strength thresholds: SSD and ESD, registered with the threshold
registry of :mod:`mrcomm.net.thresholds`.

* SSD — simulated signal degradation: RSSI predicted from each pair's distance by the
  line-of-sight or the obstructed SVR model (chosen by ray casting on the map),
  evaluated through a precomputed lookup table (never scikit-learn per step); warning
  below -42 dBm by default; ad-hoc networks only.
* ESD — effective signal degradation: the RSSI each robot measured of each peer (its
  pulse process on a real robot; in simulation a recorded trace replayed, or — with the
  ``radio`` network model — the modelled received power of each link, rounded to the
  card's 1 dBm). Its warning level by default means what the original robots' did:
  -41 dBm, their cards' reading where a peer was about 4 m away in line of sight
  (Table 6.2 of the original study: 3.5-4.2 m), when a trace of such cards is replayed;
  on the radio, the power the radio's profile gives 4 m away in line of sight
  (:func:`esd_warning_dbm`). A pair without a reading yet never warns.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from mrcomm.net.link_sensors import STALE_AFTER_S, MeasuredSensor, ModelSensor
from mrcomm.net.signal.table import RssiTable
from mrcomm.net.signal.trace import RssiTrace
from mrcomm.net.thresholds import (
    BoolArray,
    FloatArray,
    PairGeometry,
    SignalResources,
    Threshold,
)
from mrcomm.specs import VariantSpec

if TYPE_CHECKING:
    from mrcomm.ports import LinkSensor


class SsdParams(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")

    warning_dbm: float = Field(
        -42.0,
        allow_inf_nan=False,
        description="a link warns below this predicted RSSI",
        json_schema_extra={"unit": "dBm"},
    )
    model: Path | None = Field(
        None, description="SSD signal model JSON (`mrcomm signal fit`); default: bundled"
    )


class ModelThreshold(Threshold):
    """SSD: RSSI from the signal model's lookup table."""

    name = "ssd"
    needs_line_of_sight = True

    @classmethod
    def build(cls, params: BaseModel, resources: SignalResources, ids: Sequence[str]) -> Threshold:
        assert isinstance(params, SsdParams)
        return cls(resources.signal_table(params.model), params.warning_dbm)

    @classmethod
    def sensor(cls, params: BaseModel, resources: SignalResources) -> LinkSensor:
        assert isinstance(params, SsdParams)
        table = resources.signal_table(params.model)
        return ModelSensor(resources.scenario.grid, table, params.warning_dbm)

    def __init__(self, table: RssiTable, warning_dbm: float = -42.0) -> None:
        self.table = table
        self.warning_dbm = warning_dbm
        # Beyond these distances the curves are flat (saturated): no lookup needed.
        self._flat = {los: (table.flat_from(los), table.rssi_at(1e9, los)) for los in (False, True)}

    def evaluate(self, pairs: PairGeometry, now: float) -> tuple[FloatArray | None, BoolArray]:
        assert pairs.pair_sight is not None and pairs.pair_distance is not None
        # RSSI is symmetric (same distance, same model): one lookup per unordered pair.
        rssi_at = self.table.rssi_at
        flat = self._flat
        values: list[float] = []
        for dist, sight in zip(pairs.pair_distance, pairs.pair_sight, strict=True):
            if dist != dist:
                values.append(math.nan)  # a virtual node has no RSSI
                continue
            start, saturated = flat[sight]
            values.append(saturated if dist >= start else rssi_at(dist, sight))
        rssi = pairs.layout.matrix(values, math.nan)
        return rssi, rssi < self.warning_dbm  # NaN never warns

    def describe(self) -> dict[str, Any]:
        return {"threshold": self.name, "warning_dbm": self.warning_dbm}


#: The original robots' ESD warning level (their Wi-Fi cards' reading, dBm) ...
ORIGINAL_ESD_WARNING_DBM = -41.0
#: ... and how far from a peer in line of sight it fell (m; Table 6.2: 3.5-4.2 m, the
#: distance of SLT's warning too).
ESD_WARNING_DISTANCE_M = 4.0


class EsdParams(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")

    warning_dbm: float | None = Field(
        None,
        allow_inf_nan=False,
        description="a link warns below this measured RSSI (none: what the original's "
        "-41 dBm meant, a peer about 4 m away in line of sight: -41 dBm replaying a trace, "
        "on the radio the power its profile gives at 4 m)",
        json_schema_extra={"unit": "dBm"},
    )
    trace: Path | None = Field(
        None,
        description="recorded RSSI trace CSV (time,from,to,rssi) replayed by the pulses; "
        "needed in simulation unless the network model is radio (then the pulses measure "
        "the radio)",
    )


def esd_warning_dbm(params: EsdParams, network: str, network_params: BaseModel) -> float:
    """ESD's warning level on ``network``: the one given, else what the original robots'
    -41 dBm meant, a peer :data:`ESD_WARNING_DISTANCE_M` away in line of sight: -41 dBm
    for a replayed trace (cards like theirs), or the power at that distance of the
    network the pulses measure (the radio's profile)."""
    if params.warning_dbm is not None:
        return params.warning_dbm
    if params.trace is None:
        from mrcomm.specs import get_spec

        measured = (
            get_spec("network", network)
            .load()
            .measured_power_dbm(network_params, ESD_WARNING_DISTANCE_M)
        )
        if measured is not None:
            return float(round(measured))
    return ORIGINAL_ESD_WARNING_DBM


class MeasuredThreshold(Threshold):
    """ESD: measured RSSI replayed from a trace (time, from, to, rssi), or without a
    trace the radio's received power of each link as the card reports it (1 dBm)."""

    name = "esd"

    @classmethod
    def build(cls, params: BaseModel, resources: SignalResources, ids: Sequence[str]) -> Threshold:
        assert isinstance(params, EsdParams)
        trace = resources.rssi_trace(params.trace) if params.trace is not None else None
        return cls(trace, ids, _resolved(params))

    @classmethod
    def sensor(cls, params: BaseModel, resources: SignalResources) -> LinkSensor:
        assert isinstance(params, EsdParams)
        return MeasuredSensor(_resolved(params))

    def __init__(
        self, trace: RssiTrace | None, ids: Sequence[str], warning_dbm: float = -41.0
    ) -> None:
        self.trace = trace
        self.ids = tuple(ids)
        self.warning_dbm = warning_dbm

    def evaluate(self, pairs: PairGeometry, now: float) -> tuple[FloatArray | None, BoolArray]:
        if self.trace is None:
            if pairs.power is None:
                raise ValueError("ESD without a trace measures the radio: use --network radio")
            # rssi[a, b]: what a measures of b, i.e. the power of b's packets at a.
            rssi = np.round(pairs.power.T)
            return rssi, rssi < self.warning_dbm  # NaN never warns
        if now > self.trace.t1 + STALE_AFTER_S:
            rssi = np.full((len(self.ids), len(self.ids)), np.nan)  # recording ended
        else:
            rssi = self.trace.matrix_at(now, self.ids)
        return rssi, rssi < self.warning_dbm

    def describe(self) -> dict[str, Any]:
        return {"threshold": self.name, "warning_dbm": self.warning_dbm}


def _resolved(params: EsdParams) -> float:
    """The warning level: given, or the original's for a replayed trace; on a measured
    network the run's wiring resolves it first (``run.wiring.threshold_params``)."""
    if params.warning_dbm is not None:
        return params.warning_dbm
    if params.trace is not None:
        return ORIGINAL_ESD_WARNING_DBM
    raise ValueError("ESD's warning level on a measured network is resolved by the wiring")


SSD_SPEC = VariantSpec(
    kind="threshold",
    name="ssd",
    entry=ModelThreshold,
    params=SsdParams,
    summary="SSD, simulated signal degradation: RSSI predicted by the SVR signal model",
    network_types=frozenset({"ah", "radio"}),
)
ESD_SPEC = VariantSpec(
    kind="threshold",
    name="esd",
    entry=MeasuredThreshold,
    params=EsdParams,
    summary="ESD, effective signal degradation: RSSI measured by each robot's pulse",
    pulse=True,
)
