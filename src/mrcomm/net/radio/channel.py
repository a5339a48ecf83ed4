"""The per-message part of the radio: each sender's transmit queue, and whether one
message reaches one receiver given the link's received power, the message's size and
(optionally) fast fading.

* **Queue.** A sender transmits its messages one after another at the profile's
  ``rate_bps``; a message takes ``(bytes + header_bytes) · 8 / rate_bps`` seconds of
  airtime and waits for the messages before it. Its delay is the wait plus its airtime;
  a message that would wait longer than ``max_queue_s`` is dropped (queue overflow).
  One transmission serves every receiver (broadcast, as publish/subscribe over the
  radio). Contention between senders is not modelled here: each has the channel to
  itself, unless the run has the shared channel (:mod:`mrcomm.net.radio.medium`,
  ``medium``), which then takes the frames instead of the queue.
* **Packet error.** PER = 1 − (1 − BER)^bits at the link's power this step, drawn from
  the receiver's own loss stream (so the radio's draws, like SPL's, are the
  receiver's).
* **Fading** (profile ``fading: rician``): the power of each packet is the link's power
  plus a fast-fading gain, Rician with the profile's K factor in line of sight and
  Rayleigh when obstructed, drawn from the receiver's fading stream.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from mrcomm.messaging.messages import Message, encode
from mrcomm.net.radio.medium import Frame, SharedMedium
from mrcomm.net.radio.profile import RadioProfile
from mrcomm.net.radio.reception import ber as _ber
from mrcomm.net.radio.reception import ber_matrix
from mrcomm.net.radio.reception import per as _per

FloatArray = NDArray[np.float64]


def fading_gain_db(rng: np.random.Generator, k_db: float | None) -> float:
    """One fast-fading power gain, dB, with unit mean power: Rician with K factor
    ``k_db`` (dB), Rayleigh when ``k_db`` is None."""
    k = 0.0 if k_db is None else 10.0 ** (k_db / 10.0)
    # Complex gain: a fixed line-of-sight part of power K/(K+1) plus a scattered part.
    los = math.sqrt(k / (k + 1.0))
    scatter = math.sqrt(1.0 / (2.0 * (k + 1.0)))
    re, im = rng.standard_normal(2).tolist()
    power = (los + scatter * re) ** 2 + (scatter * im) ** 2
    return 10.0 * math.log10(max(power, 1e-12))


class RadioChannel:
    """Queue and packet error of one run's radio (see the module docstring)."""

    def __init__(
        self,
        profile: RadioProfile,
        ids: Sequence[str],
        fading_rngs: Mapping[str, np.random.Generator] | None = None,
        medium: SharedMedium | None = None,
    ) -> None:
        self.profile = profile
        self.medium = medium
        self.ids = tuple(ids)
        self._free_at = [0.0] * len(self.ids)
        self._seconds_per_bit = 1.0 / profile.rate_bps
        self._power: list[list[float]] | None = None
        self._power_array: FloatArray | None = None
        self._ber: list[list[float]] = []
        self._noise = profile.noise_floor_dbm
        # The profile's reception rule, or None for the plain QPSK one (the common case,
        # which then skips the checks).
        plain = profile.modulation == "qpsk" and profile.preamble_snr_db is None
        self._rule: RadioProfile | None = None if plain else profile
        self._sight: list[list[bool]] | None = None
        self._fading = (
            [fading_rngs[a] for a in self.ids]
            if fading_rngs is not None and profile.fading != "none"
            else None
        )

    def bits(self, message: Message) -> int:
        """Bits on the air for one message: its wire form plus the header."""
        return self.bits_of(len(encode(message)))

    def bits_of(self, wire_bytes: int) -> int:
        """Bits on the air for a message of ``wire_bytes`` already encoded."""
        return (wire_bytes + self.profile.header_bytes) * 8

    def transmit(self, sender: int, stamp: float, bits: int) -> float | None:
        """Queue one message of the sender at ``stamp``: its delay (wait + airtime), or
        None when the queue is too long and the message is dropped."""
        start = max(stamp, self._free_at[sender])
        if start - stamp > self.profile.max_queue_s:
            return None
        airtime = bits * self._seconds_per_bit
        self._free_at[sender] = start + airtime
        return start + airtime - stamp

    def backlog(self, sender: int, now: float) -> float:
        """Seconds of traffic still waiting in the sender's queue at ``now``."""
        return max(0.0, self._free_at[sender] - now)

    def set_links(self, power: FloatArray, sight: NDArray[np.bool_] | None) -> None:
        """The step's received power ``power[s, r]`` (dBm) and line of sight."""
        self._sight = sight.tolist() if sight is not None else None
        self._power_array = power
        if self.medium is not None:
            # The shared channel judges each frame at its SINR (frame_errors, on the
            # array), never from the links' BER alone: no lists, no table of it.
            self.medium.set_power(power)
            return
        self._power = power.tolist()
        self._ber = ber_matrix(np.ascontiguousarray(power), self._noise, self._rule).tolist()

    def packet_error(self, sender: int, receiver: int, bits: int) -> float:
        """Probability that one message of ``bits`` from ``sender`` is lost at
        ``receiver`` this step (0 for a node without a position)."""
        if self._power is None:
            return 0.0
        if self._fading is None:
            return _per(self._ber[sender][receiver], bits)
        in_sight = self._sight is None or self._sight[sender][receiver]
        return self.error_at(receiver, self._power[sender][receiver], in_sight, bits)

    @property
    def fades(self) -> bool:
        """Whether each packet has its own fast fading (the profile's ``fading``)."""
        return self._fading is not None

    def frame_errors(
        self, frame: Frame, receivers: NDArray[np.intp], judged: NDArray[np.bool_] | None
    ) -> tuple[FloatArray, FloatArray]:
        """Probability that the shared channel's ``frame`` is lost at each of
        ``receivers`` without and with the other frames on the air this step (1 for a
        receiver it was blocked at; 0 for a node without a position). Fast fading, where
        the profile has it, is drawn from the stream of each receiver in ``judged`` (the
        ones in range that take the frame; needed only when it :attr:`fades`), once for
        both."""
        assert self.medium is not None and self._power_array is not None
        if self._fading is None:  # (the channel computed them as the frame ended)
            return frame.alone[receivers], frame.shared[receivers]
        assert judged is not None
        power = self._power_array[frame.sender, receivers].copy()
        blocked = frame.blocked[receivers]
        sight = self._sight
        for j in np.flatnonzero(judged & ~blocked).tolist():
            r = int(receivers[j])
            in_sight = sight is None or sight[frame.sender][r]
            k_db = self.profile.rician_k_db if in_sight else None
            power[j] += fading_gain_db(self._fading[r], k_db)
        alone, shared = np.empty(len(receivers)), np.empty(len(receivers))
        self.medium.frame_errors(frame, power, receivers, alone, shared)
        return alone, shared

    def mean_error(self, power_dbm: float, bits: int) -> float:
        """Probability that a packet of ``bits`` is lost over a link of mean power
        ``power_dbm`` without fast fading (NaN: no position, never lost); the kernel's
        drop rate of an emulated link (``live.kernel_links``)."""
        if power_dbm != power_dbm:
            return 0.0
        return _per(_ber(power_dbm, self._noise, self._rule), bits)

    def error_at(self, receiver: int, power_dbm: float, in_sight: bool, bits: int) -> float:
        """Probability that one message of ``bits`` is lost at ``receiver`` over a link
        of mean power ``power_dbm`` (NaN: a node without a position, never lost), with
        this packet's fast fading drawn from the receiver's stream where the profile has
        fading. For a receiver that judges one link at a time (live mode)."""
        if power_dbm != power_dbm:
            return 0.0
        if self._fading is not None:
            k_db = self.profile.rician_k_db if in_sight else None
            power_dbm += fading_gain_db(self._fading[receiver], k_db)
        return _per(_ber(power_dbm, self._noise, self._rule), bits)
