"""Whether a frame survives its SNR: the reception rule of a radio profile.

BER = erfc(√SNR) (QPSK, the form of DARPA SubT's virtual comms model), or with
``modulation: dsss`` ½·exp(−22·SNR) (802.11b's DBPSK at 1 Mbit/s spread over 22 MHz, as
ns-3's DsssErrorRateModel computes it); below the profile's ``preamble_snr_db`` the
frame is not detected at all (BER 1). A frame of b bits is lost with PER = 1 − (1 − BER)^b.
The scalar forms serve the per-message decisions, :func:`bit_error_rate_at` the arrays
(the shared channel, the delivery curves).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.special import erfc

from mrcomm.compiled import compiled
from mrcomm.net.radio.profile import RadioProfile

#: 802.11b at 1 Mbit/s spreads each bit over 22 MHz: Eb/N0 = SNR · 22 MHz / 1 Mbit/s
#: (ns-3's DsssErrorRateModel for DBPSK).
DSSS_GAIN = 22.0


@compiled
def decibels(x: float) -> float:
    """10·log10(x) as numpy gives it (−inf at 0, NaN below)."""
    if x > 0.0:
        return 10.0 * math.log10(x)
    if x == 0.0:
        return -math.inf
    return math.nan


@compiled
def bit_error(snr_db: float, dsss: bool, preamble_snr_db: float, detect: bool) -> float:
    """BER at ``snr_db`` (dB): erfc(√SNR), or ½·exp(−22·SNR) with ``dsss``; 1 (nothing
    received) below ``preamble_snr_db`` (NaN: no such threshold) when ``detect``. The one
    scalar form of the rule: the per-message decisions and the shared channel's loop
    (compiled, :mod:`mrcomm.compiled`) use it."""
    if detect and snr_db < preamble_snr_db:
        return 1.0
    snr = 10.0 ** (snr_db / 10.0)
    rate = 0.5 * math.exp(-DSSS_GAIN * snr) if dsss else math.erfc(math.sqrt(snr))
    if rate > 0.5:  # (NaN stays NaN)
        rate = 0.5
    return rate


def rule_of(profile: RadioProfile) -> tuple[bool, float]:
    """The profile's reception rule as :func:`bit_error` takes it: whether DSSS, and the
    preamble SNR threshold (NaN: none)."""
    threshold = math.nan if profile.preamble_snr_db is None else profile.preamble_snr_db
    return profile.modulation == "dsss", threshold


def ber(
    power_dbm: float,
    noise_floor_dbm: float,
    profile: RadioProfile | None = None,
    detect: bool = True,
) -> float:
    """BER of one link (0 for NaN: a node without a position has no radio): erfc(√SNR),
    or the profile's modulation; 1 (nothing received) below its preamble SNR. The
    scalar form of :func:`bit_error_rate_at`; ``detect=False`` for a frame whose preamble
    was already detected (the shared channel judges it at the frame's start)."""
    if power_dbm != power_dbm:
        return 0.0
    snr_db = power_dbm - noise_floor_dbm
    if profile is None:
        return float(bit_error(snr_db, False, math.nan, False))
    return float(bit_error(snr_db, *rule_of(profile), detect))


def bit_error_rate_at(
    profile: RadioProfile, snr_db: NDArray[np.float64], detect: bool = True
) -> NDArray[np.float64]:
    """BER at each SNR (dB) by the profile's rule (see the module docstring; ``detect``:
    as in :func:`ber`)."""
    snr = 10.0 ** (np.asarray(snr_db, dtype=np.float64) / 10.0)
    if profile.modulation == "dsss":
        rate = np.minimum(0.5 * np.exp(-DSSS_GAIN * snr), 0.5)
    else:
        rate = np.minimum(erfc(np.sqrt(snr)), 0.5)
    if detect and profile.preamble_snr_db is not None:
        rate = np.where(snr_db < profile.preamble_snr_db, 1.0, rate)
    return np.asarray(rate)


@compiled
def _ber_loop(
    power_dbm: NDArray[np.float64], noise_floor_dbm: float, dsss: bool, preamble_snr_db: float,
    detect: bool, out: NDArray[np.float64],
) -> None:  # fmt: skip
    for s in range(power_dbm.shape[0]):
        for r in range(power_dbm.shape[1]):
            power = power_dbm[s, r]
            if math.isnan(power):
                out[s, r] = 0.0
            else:
                out[s, r] = bit_error(power - noise_floor_dbm, dsss, preamble_snr_db, detect)


def ber_matrix(
    power_dbm: NDArray[np.float64], noise_floor_dbm: float, profile: RadioProfile | None = None
) -> NDArray[np.float64]:
    """:func:`ber` of every link of a (senders, receivers) power matrix, in one call."""
    out = np.empty(power_dbm.shape)
    if profile is None:
        _ber_loop(power_dbm, noise_floor_dbm, False, math.nan, False, out)
    else:
        _ber_loop(power_dbm, noise_floor_dbm, *rule_of(profile), True, out)
    return out


@compiled
def per(ber: float, bits: int) -> float:
    """PER = 1 − (1 − BER)^bits; the scalar form of :func:`packet_error_rate`."""
    if ber <= 0.0:
        return 0.0
    if ber >= 1.0:
        return 1.0
    return -math.expm1(bits * math.log1p(-ber))


def packet_error_rate(
    ber: NDArray[np.float64] | float, bits: NDArray[np.float64] | float
) -> NDArray[np.float64]:
    """PER = 1 − (1 − BER)^bits (1 where BER is 1: not detected)."""
    b = np.asarray(ber, dtype=np.float64)
    with np.errstate(divide="ignore"):  # BER 1: log1p(-1) = -inf, PER 1
        return np.asarray(-np.expm1(np.asarray(bits, dtype=np.float64) * np.log1p(-b)))
