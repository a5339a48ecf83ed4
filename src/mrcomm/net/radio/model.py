"""The ``radio`` network model: received power of every link from distance, walls and
shadowing; which links are in range; the bit error rate of each (see
:mod:`mrcomm.net.radio.profile` for the formulas and their parameters).

Per step the link model hands it the geometry of every unordered pair (distance, walls
crossed) and the positions; it returns the (n, n) received power (reciprocal mean plus
a fixed per-direction offset), whether each link is in range and the bit error rate.
The per-message part — the sender's queue, packet error from the message's size, fast
fading — is :class:`mrcomm.net.radio.channel.RadioChannel`, which the bus consults.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any, ClassVar, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import BaseModel, Field

from mrcomm.errors import InputError
from mrcomm.net import pair_loops
from mrcomm.net.network import NetworkModel
from mrcomm.net.radio.channel import RadioChannel, fading_gain_db
from mrcomm.net.radio.links import RadioLinks
from mrcomm.net.radio.medium import SharedMedium
from mrcomm.net.radio.profile import DEFAULT_PROFILE, RadioProfile, load_profile, profile_path
from mrcomm.net.radio.reception import bit_error_rate_at, packet_error_rate
from mrcomm.net.radio.shadowing import ShadowingField
from mrcomm.net.relay import RelayParams
from mrcomm.net.signal.pathloss import log_distance_range, log_distance_rssi
from mrcomm.seeding import stream
from mrcomm.specs import VariantSpec

FloatArray = NDArray[np.float64]

#: Distances below the 1 m reference distance count as 1 m (near field).
REFERENCE_DISTANCE_M = 1.0
#: The link model casts rays (walls, line of sight) only within the distance at which
#: the mean power in line of sight is this far above the sensitivity (beyond it the link
#: is out of range even with a strong shadowing draw and no wall).
REACH_MARGIN_SIGMAS = 4.0


#: Below this line-of-sight distance an ESD warning level is doubtful (the AH limit).
ESD_ADVICE_M = 8.0
#: A warning level on the bundled office profile's scale: mean power ~20 m away.
ESD_RADIO_WARNING_DBM = -70.0


class RadioParams(RelayParams):
    profile: str = Field(
        DEFAULT_PROFILE,
        min_length=1,
        description="radio profile: a bundled name (mrcomm radio show) or a YAML file",
    )
    channel: Literal["queue", "shared"] = Field(
        "queue",
        description=(
            "queue: each sender has the air to itself; shared: senders contend for it "
            "(802.11 CSMA/CA), and frames on the air together interfere (simulation only)"
        ),
    )

    def input_files(self) -> dict[str, Path]:
        """The profile's file, for the run's provenance."""
        return {"profile": profile_path(self.profile)}


def _loss_at_1m(profile: RadioProfile) -> float:
    """The log-distance model's A: minus the power received at the 1 m reference."""
    return profile.reference_loss_db - profile.tx_power_dbm


def mean_power_dbm(profile: RadioProfile, distance: ArrayLike, walls: ArrayLike) -> FloatArray:
    """Mean received power without shadowing, dBm: the log-distance law (distances
    below the 1 m reference count as 1 m) less the walls' loss."""
    d = np.maximum(np.asarray(distance, dtype=np.float64), REFERENCE_DISTANCE_M)
    line_of_sight = log_distance_rssi(d, _loss_at_1m(profile), profile.exponent)
    return np.asarray(line_of_sight - profile.wall_loss_db * np.asarray(walls, dtype=np.float64))


def line_of_sight_distance(profile: RadioProfile, power_dbm: float) -> float:
    """How far away (m, at least the 1 m reference) the mean power in line of sight
    falls to ``power_dbm``."""
    d = float(log_distance_range(power_dbm, _loss_at_1m(profile), profile.exponent))
    return max(d, REFERENCE_DISTANCE_M)


def bit_error_rate(profile: RadioProfile, power_dbm: FloatArray | float) -> FloatArray:
    """BER at each received power by the profile's rule (:mod:`~mrcomm.net.radio.reception`):
    erfc(√SNR) for QPSK, SNR = power − noise floor."""
    snr_db = np.asarray(power_dbm, dtype=np.float64) - profile.noise_floor_dbm
    return bit_error_rate_at(profile, snr_db)


def reach_m(profile: RadioProfile) -> float:
    """Distance beyond which even a line-of-sight link with a 4σ shadowing gain is
    below the sensitivity."""
    margin = REACH_MARGIN_SIGMAS * (profile.shadowing_sigma_db + profile.asymmetry_db)
    return line_of_sight_distance(profile, profile.sensitivity_dbm - margin)


class RadioNetwork(NetworkModel):
    """A radio that follows the building (see the module docstring)."""

    name = "radio"
    needs_walls: ClassVar[bool] = True

    def __init__(
        self,
        params: RadioParams,
        *,
        profile: RadioProfile | None = None,
        extent: tuple[float, float, float, float] = (0.0, 1.0, 0.0, 1.0),
        seed: int = 0,
    ) -> None:
        if not isinstance(params, RadioParams):  # no fallback to defaults
            raise TypeError(f"RadioNetwork takes RadioParams, got {type(params).__name__}")
        self.params = params
        self.profile = profile if profile is not None else load_profile(params.profile)
        self.reach_m = reach_m(self.profile)
        self.seed = seed
        self.field = ShadowingField(
            self.profile.shadowing_sigma_db,
            self.profile.decorrelation_m,
            extent,
            stream(seed, "radio", "shadowing"),
        )
        self._offsets: dict[int, FloatArray] = {}

    @classmethod
    def build(cls, params: BaseModel, resources: Any, seed: int) -> RadioNetwork:
        """The run's radio: its profile, and a shadowing field over the scenario's map
        drawn from the run's seed."""
        assert isinstance(params, RadioParams), type(params)  # the spec's model
        return cls(params, extent=resources.scenario.grid.extent, seed=seed)

    @classmethod
    def measured_power_dbm(cls, params: Any, distance_m: float) -> float | None:
        """The profile's mean received power ``distance_m`` away in line of sight."""
        assert isinstance(params, RadioParams), type(params)
        return float(mean_power_dbm(load_profile(params.profile), [distance_m], [0])[0])

    @classmethod
    def live_refusal(cls, params: Any) -> str | None:
        """The shared channel needs every frame on the air in one place; live processes
        each judge only the frames that reach them."""
        if getattr(params, "channel", "queue") == "shared":
            return (
                "the shared channel is simulation only (each live process sees only the "
                "frames that reach it, not the air they share); use channel: queue"
            )
        return None

    @classmethod
    def advice(cls, config: Any) -> list[str]:
        """A pulse threshold (ESD) measures this radio: a warning level the radio passes
        within a few metres (the original robots' -41 dBm) would keep an LF team
        huddled together."""
        warning_dbm = getattr(config.variant_params("threshold"), "warning_dbm", None)
        if not config.spec("threshold").pulse or warning_dbm is None:
            return []
        warning = float(warning_dbm)
        params = config.variant_params("network")
        profile = load_profile(params.profile)
        reach = line_of_sight_distance(profile, warning)
        if reach >= ESD_ADVICE_M:
            return []
        return [
            f"ESD warns below {warning:g} dBm, which the radio ({profile.name}) passes "
            f"{reach:.1f} m away in line of sight: set threshold.warning_dbm to this "
            f"radio's scale (e.g. {ESD_RADIO_WARNING_DBM:g})"
        ]

    def offsets(self, n: int) -> FloatArray:
        """The fixed per-direction offsets of n nodes, dB ((n, n), antisymmetric so the
        two directions of a link differ by twice the offset; zeros without asymmetry)."""
        cached = self._offsets.get(n)
        if cached is None:
            sigma = self.profile.asymmetry_db
            draw = stream(self.seed, "radio", "asymmetry").normal(0.0, sigma, (n, n))
            cached = np.triu(draw, 1) - np.triu(draw, 1).T if sigma > 0 else np.zeros((n, n))
            self._offsets[n] = cached
        return cached

    def pair_power(
        self,
        xy: Sequence[Sequence[float]],
        pairs: tuple[NDArray[np.int64], NDArray[np.int64]],
        distance: NDArray[np.float64],
        walls: NDArray[np.int64],
    ) -> FloatArray:
        """Mean received power of each unordered pair with its shadowing, dBm (NaN for
        a pair with a node without a position)."""
        p = self.profile
        # The field once per node (a pair's shadowing is the scaled sum of its ends').
        at = self.field.at
        field = np.array([at(x, y) if x == x else math.nan for x, y in xy])
        out = np.empty(len(distance))
        pair_loops.pair_power(
            distance, walls, pairs[0], pairs[1], field, p.tx_power_dbm - p.reference_loss_db,
            10.0 * p.exponent, p.wall_loss_db, REFERENCE_DISTANCE_M, out,
        )  # fmt: skip
        return out

    def channel(self, ids: Sequence[str]) -> Any:
        rngs = {a: stream(self.seed, "radio", "fading", a) for a in ids}
        medium = None
        if self.params.channel == "shared":
            backoff = [stream(self.seed, "radio", "backoff", a) for a in ids]
            medium = SharedMedium(self.profile, len(ids), backoff)
        return RadioChannel(self.profile, ids, rngs, medium)

    def live_links(self, grid: Any, node_ids: Sequence[str], aliases: Any) -> RadioLinks:
        refusal = self.live_refusal(self.params)
        if refusal is not None:
            raise InputError(refusal, field="network.channel")
        return RadioLinks(self, grid, node_ids, aliases)

    def in_range_power(self, power: FloatArray) -> NDArray[np.bool_]:
        """Which links are in range (power at or above the sensitivity; NaN — a node
        without a position — is always in range)."""
        return np.asarray(~(power < self.profile.sensitivity_dbm))

    def describe(self) -> dict[str, float | str]:
        return {"network": self.name, "profile": self.profile.name}


RADIO_SPEC = VariantSpec(
    kind="network",
    name="radio",
    entry=RadioNetwork,
    params=RadioParams,
    summary=(
        "radio that follows the building: log-distance path loss, walls, correlated "
        "shadowing, packet error from SNR and size, a sender queue or a shared channel"
    ),
)


#: Wire size of a typical pose message (bytes, before the header): what
#: :func:`delivery_ratio` assumes unless told otherwise.
POSE_BYTES = 150
#: Standard normal points and weights for averaging over the shadowing: a dense grid
#: over ±5σ (packet error falls from 1 to 0 within a few dB, so a coarse quadrature
#: would make the curves ripple).
_NODES = np.linspace(-5.0, 5.0, 801)
_WEIGHTS = np.exp(-0.5 * _NODES**2) / np.exp(-0.5 * _NODES**2).sum()
#: Fast-fading draws averaged per point (fixed seed: the curve is the same every time).
_FADING_DRAWS = 100


def delivery_ratio(
    profile: RadioProfile,
    distance: FloatArray | Sequence[float],
    walls: int,
    message_bytes: int = POSE_BYTES,
) -> FloatArray:
    """Expected share of messages of ``message_bytes`` delivered over a link of each
    ``distance`` through ``walls`` walls: in range and free of packet error, averaged
    over the shadowing (and the per-direction offset and fast fading, where the profile
    has them)."""
    d = np.asarray(distance, dtype=np.float64)
    nodes, weights = _NODES, _WEIGHTS
    if profile.fading != "none":  # fading smooths the curve: a coarser grid will do
        nodes, weights = _NODES[::5], _WEIGHTS[::5] / _WEIGHTS[::5].sum()
    sigma = math.hypot(profile.shadowing_sigma_db, profile.asymmetry_db)
    power = mean_power_dbm(profile, d, walls)[..., None] + sigma * nodes  # (..., nodes)
    if profile.fading == "none":
        gains = np.zeros(1)
    else:
        rng = np.random.default_rng(0)
        k_db = profile.rician_k_db if walls == 0 else None
        gains = np.array([fading_gain_db(rng, k_db) for _ in range(_FADING_DRAWS)])
    bits = (message_bytes + profile.header_bytes) * 8
    received = power[..., None] + gains  # (..., nodes, draws)
    ok = (received >= profile.sensitivity_dbm) * (
        1.0 - packet_error_rate(bit_error_rate(profile, received), bits)
    )
    return np.asarray((ok.mean(axis=-1) * weights).sum(axis=-1))
