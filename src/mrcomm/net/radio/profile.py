"""Radio profiles: the parameters of the ``radio`` network model, read from YAML.

A profile describes one kind of radio in one kind of building. The bundled profiles
(``mrcomm radio show NAME``) live next to this module; any other profile is a YAML file
with the same keys. Every value is checked (finite, within physical limits, no unknown
key) and a bad one is a one-line error naming the file and the key.

The model (see :mod:`mrcomm.net.radio.model`):

* mean received power ``P = tx_power − reference_loss − 10·exponent·log10(d / 1 m)
  − wall_loss · walls`` dBm, walls counted along the straight line between the two
  antennas on the map (each run of occupied cells crossed is one wall);
* plus spatially correlated log-normal shadowing (σ ``shadowing_sigma_db``, exponential
  autocorrelation over ``decorrelation_m``), the same for both directions, plus a fixed
  per-direction offset (σ ``asymmetry_db``), plus optional fast fading per packet and
  per reading (Rician with ``rician_k_db`` in line of sight, Rayleigh when obstructed);
* below ``sensitivity_dbm`` nothing is received (the link is out of range); above it a
  message of b bits is lost with PER = 1 − (1 − BER)^b, BER = erfc(√SNR) (QPSK, the form
  of DARPA SubT's virtual comms model), SNR = P − ``noise_floor_dbm``; or, with
  ``modulation: dsss``, BER = ½·exp(−22·SNR) (802.11b's DBPSK spread over 22 MHz, as
  ns-3 computes it); a frame below ``preamble_snr_db`` (optional) is always lost;
* each sender transmits its messages one after another at ``rate_bps`` (message bytes +
  ``header_bytes``); a message that would wait longer than ``max_queue_s`` in the
  sender's queue is dropped;
* with the shared channel (``network.channel: shared``) the senders also share the air
  by 802.11's CSMA/CA, with the MAC timing ``slot_s``, ``sifs_s``, ``cw_min``,
  ``preamble_s``, ``ack_s`` and ``carrier_sense_dbm`` (optional; 802.11b's by default).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Any, Literal

import pydantic
from pydantic import BaseModel, ConfigDict, Field

from mrcomm.errors import InputError, did_you_mean
from mrcomm.world.yamlfile import read_yaml, validation_error

PROFILE_SUFFIXES = (".yaml", ".yml")
DEFAULT_PROFILE = "office-2.4ghz"


def _field(meaning: str, unit: str, **limits: Any) -> Any:
    """A required physical value: a profile states every one (no silent default)."""
    return Field(..., description=meaning, json_schema_extra={"unit": unit}, **limits)


class RadioProfile(BaseModel):
    """One radio in one kind of building (see the module docstring)."""

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)

    name: str = Field(min_length=1, description="the profile's name")
    source: str = Field("", description="where the values come from")
    frequency_ghz: float = Field(
        2.4, gt=0, le=100, description="carrier frequency, GHz (documentation only)"
    )
    tx_power_dbm: float = _field("transmit power", "dBm", ge=-30, le=36)
    reference_loss_db: float = _field("path loss at 1 m (L0)", "dB", ge=0, le=120)
    exponent: float = _field("path-loss exponent n", "", gt=0, le=8)
    wall_loss_db: float = _field("loss per wall crossed", "dB", ge=0, le=60)
    shadowing_sigma_db: float = _field("shadowing standard deviation", "dB", ge=0, le=20)
    decorrelation_m: float = _field("shadowing decorrelation distance", "m", gt=0, le=1000)
    asymmetry_db: float = Field(
        0.0, ge=0, le=20, description="per-direction offset, standard deviation (dB)"
    )
    fading: Literal["none", "rician"] = Field(
        "none", description="fast fading per packet and reading (rician: Rayleigh when obstructed)"
    )
    rician_k_db: float = Field(
        6.0, ge=-20, le=40, description="Rician K factor in line of sight (dB)"
    )
    noise_floor_dbm: float = _field("noise floor", "dBm", ge=-140, le=-30)
    sensitivity_dbm: float = _field("weakest signal received at all", "dBm", ge=-140, le=0)
    rate_bps: float = _field("channel rate of one sender", "bit/s", gt=0, le=1e10)
    header_bytes: int = Field(
        ..., ge=0, le=10_000, description="bytes added to every message (MAC/IP/UDP/transport)"
    )
    max_queue_s: float = _field("longest wait in a sender's queue", "s", gt=0, le=3600)
    modulation: Literal["qpsk", "dsss"] = Field(
        "qpsk",
        description=(
            "bit errors: qpsk BER = erfc(√SNR); dsss (802.11b at 1 Mbit/s, ns-3's "
            "DsssErrorRateModel) BER = ½·exp(−22·SNR)"
        ),
    )
    preamble_snr_db: float | None = Field(
        None, ge=-20, le=40,
        description="frames below this SNR (SINR on the shared channel) are not detected at all",
    )  # fmt: skip
    # The shared channel's MAC (network.channel: shared; see radio/medium.py). The
    # defaults are 802.11b's (DSSS, long preamble), the PHY of a 1 Mbit/s radio.
    slot_s: float = Field(20e-6, gt=0, le=0.01, description="backoff slot time (s)")
    sifs_s: float = Field(10e-6, ge=0, le=0.01, description="short interframe space (s)")
    cw_min: int = Field(31, ge=0, le=1023, description="contention window: backoff 0..cw_min slots")
    preamble_s: float = Field(
        192e-6, ge=0, le=0.01, description="PHY preamble and header of every frame (s)"
    )
    ack_s: float = Field(
        304e-6, ge=0, le=0.01,
        description="an acknowledgement's airtime, for EIFS = DIFS + SIFS + ack_s (s)",
    )  # fmt: skip
    carrier_sense_dbm: float | None = Field(
        None, ge=-140, le=0,
        description="power at which a node hears the air busy (default: the sensitivity)",
    )  # fmt: skip

    def describe(self) -> dict[str, float | str]:
        return self.model_dump()


def bundled_profiles() -> list[str]:
    """Names of the profiles that ship with MRComm."""
    folder = resources.files(__package__) / "profiles"
    return sorted(p.name.rsplit(".", 1)[0] for p in folder.iterdir() if p.name.endswith(".yaml"))


def profile_path(name_or_path: str | Path, field: str = "network.profile") -> Path:
    """The file of a bundled profile (by name) or of a profile given as a path;
    ``field``: what the user gave it as (an option, an argument), named in errors."""
    text = str(name_or_path)
    if text in bundled_profiles():
        return Path(str(resources.files(__package__) / "profiles" / f"{text}.yaml"))
    path = Path(text)
    if path.suffix.lower() not in PROFILE_SUFFIXES:
        hint = did_you_mean(text, bundled_profiles())
        raise InputError(
            f"unknown radio profile '{text}'{hint} (bundled: {', '.join(bundled_profiles())}; "
            "or a .yaml file)",
            field=field,
        )
    return path


def load_profile(name_or_path: str | Path, field: str = "network.profile") -> RadioProfile:
    """Read and check a profile; anything wrong is a one-line :class:`InputError`
    (``field``: see :func:`profile_path`)."""
    path = profile_path(name_or_path, field)
    data = read_yaml(path, field=field)
    if not isinstance(data, dict):
        raise InputError("a radio profile must be a mapping of keys to values", file=path)
    data.setdefault("name", path.stem)
    try:
        return RadioProfile.model_validate(data)
    except pydantic.ValidationError as err:
        raise validation_error(err, file=path, root=RadioProfile) from None
