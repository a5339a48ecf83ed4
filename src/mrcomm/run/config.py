"""Configuration of one mission run (a point of the experiment design, SPEC §7), as a
frozen, validated model shared by ``mrcomm run``, sweeps and live mode."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from mrcomm.agents.behaviours import behaviour_class
from mrcomm.errors import InputError, did_you_mean
from mrcomm.net.network import AH_RANGE_M, NetworkType
from mrcomm.net.thresholds import threshold_class


class RunConfig(BaseModel):
    """Everything that determines a run; same config + seed => same result."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    scenario: Path
    network: NetworkType = NetworkType.WLAN
    spl: float = Field(0.0, ge=0.0, le=100.0, description="simulated packet loss, %")
    threshold: str = "none"
    behaviour: str = "nb"
    seed: int = Field(1, ge=0)
    max_time: float = Field(1800.0, gt=0.0, description="mission time limit, simulated s")
    dt: float = Field(0.1, gt=0.0, le=0.5, description="simulation step, s")
    ah_range: float = Field(AH_RANGE_M, gt=0.0)
    slt_warning: float = Field(4.0, gt=0.0, description="SLT warning distance, m")
    ssd_warning: float = Field(-42.0, description="SSD warning RSSI, dBm")
    esd_warning: float = Field(-41.0, description="ESD warning RSSI, dBm")
    signal_model: Path | None = None
    rssi_trace: Path | None = None

    @model_validator(mode="after")
    def _combinations(self) -> RunConfig:
        # Registry look-ups raise InputError with a "did you mean" hint.
        threshold_class(self.threshold)
        behaviour_class(self.behaviour)
        if self.threshold == "ssd" and self.network is not NetworkType.AH:
            raise ValueError("threshold 'ssd' needs network 'ah' (SSD is ad-hoc only)")
        if self.threshold == "esd" and self.rssi_trace is None:
            raise ValueError("threshold 'esd' in simulation needs --rssi-trace CSV")
        return self

    def label(self) -> str:
        """Short configuration label, e.g. ``AH_NB_SPL25_SSD``."""
        spl = f"{self.spl:g}"
        parts = [self.network.value.upper(), self.behaviour.upper(), f"SPL{spl}"]
        if self.threshold != "none":
            parts.append(self.threshold.upper())
        return "_".join(parts)


def make_config(source: str | None = None, **values: Any) -> RunConfig:
    """Build a RunConfig, turning validation errors into a one-line InputError."""
    try:
        return RunConfig(**values)
    except ValidationError as err:
        first = err.errors()[0]
        loc = ".".join(str(p) for p in first["loc"]) or None
        message = first["msg"]
        if first["type"] == "extra_forbidden" and loc:
            message = f"unknown option{did_you_mean(loc, RunConfig.model_fields)}"
        raise InputError(message.removeprefix("Value error, "), file=source, field=loc) from None
