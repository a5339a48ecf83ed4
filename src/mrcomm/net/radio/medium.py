"""The shared radio channel: 802.11's distributed coordination function (CSMA/CA) for
broadcast frames, simulated event by event between two deliveries of the bus.

With ``network.channel: shared`` every message is one broadcast frame of its sender
(bits at the profile's ``rate_bps`` plus the PHY preamble, ``preamble_s``) and all
senders share the air:

* **Carrier sense.** A node hears the air busy while a frame of a node whose power at it
  is at least ``carrier_sense_dbm`` (default: the sensitivity, i.e. it can detect the
  frame's preamble) is on the air, or while it transmits itself.
* **Access (DCF without acknowledgements: broadcast).** A node transmits the frame at
  the head of its queue once the air has been idle for DIFS (EIFS after a frame it
  received with errors) and its backoff counter — a uniform draw from 0 to ``cw_min``
  slots — has counted down; the counter freezes while the air is busy. A new counter is
  drawn after every transmission (post-backoff), and when a frame arrives at an empty
  queue while the air is busy, so a frame that finds the air idle long enough goes out
  at once. Broadcast frames are not acknowledged, so the window never doubles and a
  frame is sent once. Two nodes whose counters reach zero in the same slot collide.
* **Reception.** A receiver locks on the first frame it hears (power at least the
  sensitivity) that starts while it neither transmits nor receives — of frames starting
  in the same instant, the strongest (the nearest: the first to arrive) — provided its
  preamble's SINR, against every
  frame on the air then, reaches the profile's ``preamble_snr_db`` (when it has one).
  Frames that start while it is locked or transmits, or after a preamble it could not
  detect, are lost to it (collision; no capture). A frame it locked on is lost with the
  packet error rate at its SINR: the noise floor plus the power of every other frame on
  the air at any time during it (hidden terminals collide here). A receiver that
  transmits at any time during the frame loses it.
* **Queue.** A frame older than ``max_queue_s`` is dropped when it reaches the head of
  the queue or when a newer one arrives behind it, so a queue holds at most
  ``max_queue_s`` of its sender's traffic.

The bus submits each message with :meth:`SharedMedium.submit` and, at each delivery,
takes the frames finished by then from :meth:`SharedMedium.advance` (in the order they
ended) with, per receiver, whether it was blocked and the interference it had; the
packet error draws stay the bus's (one per message and receiver from the receiver's
stream, as with the per-sender queue). The power matrix is the step's mean received
power (:meth:`SharedMedium.set_power`); a frame keeps the links of the step it started
in (who it kept busy, who could hear it, the power it brought as interference) until it
ends.

Not modelled: acknowledged unicast and retransmissions (the bus broadcasts), RTS/CTS,
frame capture, rate adaptation, energy-detection carrier sense below the preamble.
"""

from __future__ import annotations

import heapq
import math
from collections import deque
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mrcomm.net.radio.profile import RadioProfile
from mrcomm.net.radio.reception import bit_error_rate_at

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

#: Two instants closer than this (s) are the same instant (slot boundaries are sums).
_SAME_TIME_S = 1e-12


class Frame:
    """One message on the shared channel, from its submission to the end of its
    transmission (or its drop from the queue)."""

    __slots__ = ("bits", "blocked", "dropped", "end", "heard_by", "interference_mw",
                 "power_dbm", "power_mw", "sender", "sensed_by", "start", "submitted",
                 "token")  # fmt: skip

    def __init__(self, sender: int, submitted: float, bits: int, token: Any) -> None:
        self.sender = sender
        self.submitted = submitted
        self.bits = bits
        self.token = token
        self.start = math.nan
        self.end = math.nan
        self.dropped = False
        #: Receivers that could not receive it: transmitting during it, or locked on
        #: another frame when it started (set when it starts).
        self.blocked: BoolArray = np.zeros(0, dtype=np.bool_)
        #: Power of the other frames on the air during it, mW per receiver.
        self.interference_mw: FloatArray = np.zeros(0)
        # Its links as they were when it started (robots move between steps: the nodes
        # it kept busy are the ones to release, its power the one others received).
        self.sensed_by: BoolArray = np.zeros(0, dtype=np.bool_)
        self.heard_by: BoolArray = np.zeros(0, dtype=np.bool_)
        self.power_mw: FloatArray = np.zeros(0)
        self.power_dbm: FloatArray = np.zeros(0)

    @property
    def delay(self) -> float:
        """Queue wait, contention and airtime, s."""
        return self.end - self.submitted

    @property
    def airtime(self) -> float:
        return self.end - self.start


def _dbm_to_mw(dbm: FloatArray) -> FloatArray:
    """Power in mW (0 for NaN: a node without a position has no radio)."""
    mw = 10.0 ** (dbm / 10.0)
    return np.where(np.isnan(mw), 0.0, mw)


class SharedMedium:
    """The shared channel of one run's nodes (see the module docstring)."""

    def __init__(self, profile: RadioProfile, n: int, rngs: Sequence[np.random.Generator]) -> None:
        self.profile = profile
        self.n = n
        self._rngs = list(rngs)
        self._seconds_per_bit = 1.0 / profile.rate_bps
        self._slot = profile.slot_s
        self._difs = profile.sifs_s + 2.0 * profile.slot_s
        self._eifs = self._difs + profile.sifs_s + profile.ack_s
        self._cw = profile.cw_min
        self._queues: list[deque[Frame]] = [deque() for _ in range(n)]
        self._head_arrival = np.full(n, np.inf)  # submission of each queue's head
        self._busy = np.zeros(n, dtype=np.int64)  # frames on the air each node senses
        self._transmitting = np.zeros(n, dtype=np.bool_)
        self._idle_since = np.zeros(n)
        self._ifs = np.full(n, self._difs)
        self._backoff = np.zeros(n, dtype=np.int64)
        self._lock_until = np.full(n, -np.inf)  # end of the frame each receiver is on
        self._on_air: list[Frame] = []
        self._recent: list[Frame] = []  # ended, still within one airtime of the clock
        self._finished: list[Frame] = []
        self._submitted: list[Frame] = []  # since the last advance
        self._waiting = np.zeros(n, dtype=np.int64)  # each sender's frames not yet sent
        self._arrivals: list[tuple[float, int, Frame]] = []  # a heap by arrival
        self._sequence = 0
        self._clock = 0.0
        self._power_dbm = np.full((n, n), np.nan)
        self._power_mw = np.zeros((n, n))
        self._senses = np.zeros((n, n), dtype=np.bool_)
        self._hears = np.zeros((n, n), dtype=np.bool_)
        self._radio = np.ones(n, dtype=np.bool_)
        self._noise_mw = 10.0 ** (profile.noise_floor_dbm / 10.0)
        sense = profile.carrier_sense_dbm
        self._sense_dbm = profile.sensitivity_dbm if sense is None else sense
        self._longest = 0.0

    # -- inputs ----------------------------------------------------------------------
    def set_power(self, power_dbm: FloatArray) -> None:
        """The step's mean received power ``power_dbm[s, r]`` (dBm; NaN: no radio)."""
        self._power_dbm = power_dbm
        self._power_mw = _dbm_to_mw(power_dbm)
        off_diagonal = ~np.eye(self.n, dtype=np.bool_)
        with np.errstate(invalid="ignore"):
            self._senses = (power_dbm >= self._sense_dbm) & off_diagonal
            self._hears = (power_dbm >= self.profile.sensitivity_dbm) & off_diagonal
        # A node with no power to anyone (the operator's virtual node) has no radio: it
        # is never blocked, and its frames are neither sensed nor interfere.
        without = (np.isnan(power_dbm) | ~off_diagonal).all(axis=0)
        self._radio = np.asarray(~without | (self.n == 1), dtype=np.bool_)

    def airtime(self, bits: int) -> float:
        """Seconds on the air of a frame of ``bits``: preamble and bits at the rate."""
        return self.profile.preamble_s + bits * self._seconds_per_bit

    def submit(self, sender: int, stamp: float, bits: int, token: Any) -> None:
        """Hand a frame of ``sender`` published at ``stamp`` (the last :meth:`advance`)
        to the channel; ``token`` comes back with it when it has finished."""
        self._submitted.append(Frame(sender, max(stamp, self._clock), bits, token))
        self._waiting[sender] += 1

    # -- outputs ---------------------------------------------------------------------
    def pending(self) -> int:
        """Frames submitted, queued or on the air."""
        queued = sum(len(q) for q in self._queues)
        return len(self._submitted) + len(self._arrivals) + queued + len(self._on_air)

    def queued(self, sender: int) -> int:
        """Frames of ``sender`` waiting: submitted, not yet on the air or dropped."""
        return int(self._waiting[sender])

    def advance(self, now: float) -> list[Frame]:
        """Simulate the channel up to ``now``; the frames that ended (or were dropped)
        since the last call, in the order they did."""
        self._arrive_within(now)
        while True:
            end = min((f.end for f in self._on_air), default=math.inf)
            start, starters = self._next_access()
            arrival = self._arrivals[0][0] if self._arrivals else math.inf
            first = min(end, start, arrival)
            if first > now + _SAME_TIME_S:
                break
            if arrival <= first:
                self._arrive(heapq.heappop(self._arrivals)[2])
            elif end <= start:
                self._end_frames(end)
            else:
                self._start_frames(start, starters)
        self._clock = max(self._clock, now)
        finished, self._finished = self._finished, []
        return finished

    def _arrive_within(self, now: float) -> None:
        """Give the frames submitted since the last call their arrival at the MAC.

        A step publishes all its messages at one instant, where robots publish at
        instants of their own: frames that arrived together at idle nodes would all
        collide. Each frame therefore arrives at a uniform instant of the interval up
        to ``now`` (from its sender's stream; one sender's frames keep their order)."""
        if not self._submitted:
            return
        by_sender: dict[int, list[Frame]] = {}
        for frame in self._submitted:
            by_sender.setdefault(frame.sender, []).append(frame)
        self._submitted = []
        for sender, frames in sorted(by_sender.items()):
            begin = frames[0].submitted
            span = max(now - begin, 0.0)
            offsets = np.sort(self._rngs[sender].random(len(frames))) * span
            for frame, offset in zip(frames, offsets.tolist(), strict=True):
                frame.submitted = begin + offset
                heapq.heappush(self._arrivals, (frame.submitted, self._sequence, frame))
                self._sequence += 1

    def _arrive(self, frame: Frame) -> None:
        """``frame`` reaches its sender's MAC queue."""
        sender = frame.sender
        queue = self._queues[sender]
        self._expire(sender, frame.submitted)
        if not queue:
            self._head_arrival[sender] = frame.submitted
            # 802.11: a frame that finds the air busy (and no counter running) backs off.
            if self._backoff[sender] == 0 and self._air_busy(sender):
                self._backoff[sender] = self._draw(sender)
        queue.append(frame)

    # -- the DCF ---------------------------------------------------------------------
    def _draw(self, node: int) -> int:
        return int(self._rngs[node].integers(0, self._cw + 1))

    def _air_busy(self, node: int) -> bool:
        return bool(self._busy[node] > 0 or self._transmitting[node])

    def _expire(self, node: int, now: float) -> None:
        """Drop the frames at the head of ``node``'s queue older than ``max_queue_s``."""
        queue = self._queues[node]
        limit = self.profile.max_queue_s
        while queue and now - queue[0].submitted > limit + _SAME_TIME_S:
            frame = queue.popleft()
            self._waiting[node] -= 1
            frame.dropped = True
            frame.end = now
            self._finished.append(frame)
        self._head_arrival[node] = queue[0].submitted if queue else np.inf

    def _next_access(self) -> tuple[float, NDArray[np.intp]]:
        """When the next frames go on the air, and whose."""
        ready = (self._busy == 0) & ~self._transmitting & np.isfinite(self._head_arrival)
        if not ready.any():
            return math.inf, np.empty(0, dtype=np.intp)
        nodes = np.flatnonzero(ready)
        counted = self._idle_since[nodes] + self._ifs[nodes] + self._backoff[nodes] * self._slot
        access = np.maximum(counted, self._head_arrival[nodes])
        first = float(access.min())
        return first, nodes[access <= first + _SAME_TIME_S]

    def _freeze(self, nodes: BoolArray, now: float) -> None:
        """The air turns busy at ``now`` for ``nodes`` that heard it idle: their
        counters keep the slots not yet counted down."""
        idle = nodes & (self._busy == 0) & ~self._transmitting
        if idle.any():
            waited = now - self._idle_since[idle] - self._ifs[idle]
            counted = np.floor(np.maximum(waited, 0.0) / self._slot + 1e-9).astype(np.int64)
            self._backoff[idle] = np.maximum(self._backoff[idle] - counted, 0)

    def _start_frames(self, now: float, starters: NDArray[np.intp]) -> None:
        frames: list[Frame] = []
        for node in starters.tolist():
            self._expire(node, now)
            if self._queues[node]:
                frames.append(self._queues[node].popleft())
                self._waiting[node] -= 1
                queue = self._queues[node]
                self._head_arrival[node] = queue[0].submitted if queue else np.inf
        if not frames:
            return
        senders = np.array([f.sender for f in frames], dtype=np.intp)
        sensing = np.asarray(self._senses[senders].any(axis=0), dtype=np.bool_)
        sensing[senders] = True  # a sender's own counter is spent
        self._freeze(sensing, now)
        for frame in frames:
            frame.start = now
            frame.end = now + self.airtime(frame.bits)
            frame.sensed_by = self._senses[frame.sender]
            frame.heard_by = self._hears[frame.sender] & self._radio
            frame.power_mw = self._power_mw[frame.sender]
            frame.power_dbm = self._power_dbm[frame.sender]
            self._longest = max(self._longest, frame.end - now)
        # Receivers busy now cannot take any of these frames; who starts now too.
        self._transmitting[senders] = True
        for other in self._on_air:
            if self._radio[other.sender]:  # (nothing stops a frame without a radio)
                other.blocked[senders] |= self._radio[senders]
        blocked = self._transmitting | (self._lock_until > now + _SAME_TIME_S)
        # Every frame on the air now is noise to the preamble of each new one.
        on_air_mw = np.sum([f.power_mw for f in (*self._on_air, *frames)], axis=0)
        # Of the frames that start in the same instant a receiver takes the first to
        # reach it, the nearest: here the strongest (no capture beyond that).
        strength = np.where(self._hears[senders], self._power_mw[senders], -1.0)
        strongest = strength.argmax(axis=0)
        free = ~blocked & self._radio & (strength.max(axis=0) >= 0.0)
        threshold = self.profile.preamble_snr_db
        for k, frame in enumerate(frames):
            hears = frame.heard_by
            mine = free & (strongest == k)
            if threshold is not None:  # the preamble is detected above its SINR only
                signal = frame.power_mw
                with np.errstate(divide="ignore"):
                    sinr_db = 10.0 * np.log10(signal / (self._noise_mw + on_air_mw - signal))
                mine &= sinr_db >= threshold
            frame.blocked = (blocked | (hears & ~mine)) & self._radio & self._radio[frame.sender]
            self._lock_until[mine] = frame.end
            self._backoff[frame.sender] = 0
        self._busy += np.sum([f.sensed_by for f in frames], axis=0)
        self._on_air.extend(frames)

    def _end_frames(self, now: float) -> None:
        ending = [f for f in self._on_air if f.end <= now + _SAME_TIME_S]
        self._on_air = [f for f in self._on_air if f.end > now + _SAME_TIME_S]
        window = self._on_air + self._recent + ending
        for frame in ending:
            overlapping = [
                g.power_mw
                for g in window
                if g is not frame and g.start < frame.end - _SAME_TIME_S
                and g.end > frame.start + _SAME_TIME_S
            ]  # fmt: skip
            frame.interference_mw = np.sum(overlapping, axis=0) if overlapping else np.zeros(self.n)
            self._finished.append(frame)
        senders = np.array([f.sender for f in ending], dtype=np.intp)
        self._busy -= np.sum([f.sensed_by for f in ending], axis=0)
        self._transmitting[senders] = False
        for frame in ending:
            self._backoff[frame.sender] = self._draw(frame.sender)  # post-backoff
            # 802.11 waits EIFS, not DIFS, after a frame received in error: here one
            # its receiver more likely than not lost (the bus draws the real outcome).
            locked = frame.heard_by & ~frame.blocked
            lost = self._sinr_error(frame) > 0.5
            self._ifs[locked & lost] = self._eifs
            self._ifs[locked & ~lost] = self._difs
        sensed = np.asarray(np.any([f.sensed_by for f in ending], axis=0), dtype=np.bool_)
        sensed[senders] = True
        now_idle = sensed & (self._busy == 0) & ~self._transmitting
        self._idle_since[now_idle] = now
        self._recent = [f for f in self._recent + ending if f.end > now - self._longest]

    def _sinr_error(self, frame: Frame) -> FloatArray:
        """Packet error of ``frame`` at every receiver at its SINR (no fading)."""
        noise_dbm = 10.0 * np.log10(self._noise_mw + frame.interference_mw)
        power = frame.power_dbm
        sinr_dbm = np.where(np.isnan(power), -np.inf, power)
        with np.errstate(divide="ignore", invalid="ignore"):
            ber = bit_error_rate_at(self.profile, sinr_dbm - noise_dbm, detect=False)
            return np.asarray(-np.expm1(frame.bits * np.log1p(-np.minimum(ber, 1.0))))
