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
  detect, are lost to it (collision; no capture). A frame it locked on survives its
  payload chunk by chunk, as ns-3 judges a frame: the payload is cut at the instants
  other frames start or end during it, and each chunk's bits meet the packet error rate
  at that chunk's SINR — the noise floor plus the power of the other frames on the air
  then (hidden terminals collide here). A receiver that transmits at any time during the
  frame loses it.
* **Queue.** A frame older than ``max_queue_s`` is dropped when it reaches the head of
  the queue or when a newer one arrives behind it, so a queue holds at most
  ``max_queue_s`` of its sender's traffic.

The bus submits each message with :meth:`SharedMedium.submit` and, at each delivery,
takes the frames finished by then from :meth:`SharedMedium.advance` (in the order they
ended) with, per receiver, whether it was blocked and the interference it met; the
packet error draws stay the bus's (one per message and receiver from the receiver's
stream, as with the per-sender queue). The power matrix is the step's mean received
power (:meth:`SharedMedium.set_power`); a frame keeps the links of the step it started
in (who it kept busy, who could hear it, the power it brought as interference) until it
ends.

The event loop itself is :mod:`mrcomm.net.radio.air`, over arrays and compiled where
numba is installed; this class keeps its state, hands it the frames and gives back the
finished ones.

Not modelled: acknowledged unicast and retransmissions (the bus broadcasts), RTS/CTS,
frame capture, rate adaptation, energy-detection carrier sense below the preamble.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mrcomm.net.radio import air
from mrcomm.net.radio.profile import RadioProfile
from mrcomm.net.radio.reception import rule_of

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

#: Frame slots, queue places, backoff draws per node and chunks in the pool to begin
#: with (each grows by doubling when needed).
_FIRST_SLOTS = 64
_FIRST_CHUNKS = 256
_FIRST_PLACES = 4
_FIRST_DRAWS = 64
#: 64-bit draws kept for rejections in the bounded draws beyond the most a call can use
#: (for an 802.11 window, 2^k slots, there are none).
_MARGIN = 16


# What a frame has per receiver until it has been on the air (read-only: shared).
_NO_RECEIVERS: BoolArray = np.zeros(0, dtype=np.bool_)
_NO_VALUES: FloatArray = np.zeros(0)
_NO_RECEIVERS.flags.writeable = _NO_VALUES.flags.writeable = False


class Frame:
    """One message on the shared channel, from its submission to the end of its
    transmission (or its drop from the queue)."""

    __slots__ = ("alone", "bits", "blocked", "chunk_bits", "chunk_mw", "dropped", "end",
                 "sender", "shared", "start", "submitted", "token")  # fmt: skip

    def __init__(self, sender: int, submitted: float, bits: int, token: Any) -> None:
        self.sender = sender
        self.submitted = submitted  # then its arrival at the MAC queue
        self.bits = bits
        self.token = token
        self.start = math.nan
        self.end = math.nan
        self.dropped = False
        #: Receivers that could not receive it: transmitting during it, or locked on
        #: another frame when it started (empty for a dropped frame).
        self.blocked: BoolArray = _NO_RECEIVERS
        #: Its payload cut at the instants other frames started or ended during it: the
        #: bits of each chunk, and the power of the other frames on the air through it
        #: (mW; a row per chunk, a column per receiver).
        self.chunk_bits: FloatArray = _NO_VALUES
        self.chunk_mw: FloatArray = _NO_VALUES.reshape(0, 0)
        #: Probability that it is lost at each receiver without and with the other
        #: frames, at the mean power of the step it ended in (1 where blocked).
        self.alone: FloatArray = _NO_VALUES
        self.shared: FloatArray = _NO_VALUES

    @property
    def delay(self) -> float:
        """Queue wait, contention and airtime, s."""
        return self.end - self.submitted

    @property
    def airtime(self) -> float:
        return self.end - self.start


class SharedMedium:
    """The shared channel of one run's nodes (see the module docstring)."""

    def __init__(self, profile: RadioProfile, n: int, rngs: Sequence[np.random.Generator]) -> None:
        self.profile = profile
        self.n = n
        self._rngs = list(rngs)
        # The loop turns 64-bit draws into numpy's values as PCG64 (numpy's default)
        # serves them (net/radio/draws.py): another bit generator would differ.
        if any(not isinstance(r.bit_generator, np.random.PCG64) for r in self._rngs):
            raise ValueError("the shared channel's streams must be PCG64 generators")
        self._seconds_per_bit = 1.0 / profile.rate_bps
        difs = profile.sifs_s + 2.0 * profile.slot_s
        eifs = difs + profile.sifs_s + profile.ack_s
        dsss, threshold = rule_of(profile)
        self._settings = np.array([
            profile.slot_s, difs, eifs, profile.preamble_s, self._seconds_per_bit,
            profile.max_queue_s, 10.0 ** (profile.noise_floor_dbm / 10.0),
            profile.noise_floor_dbm, threshold, 1.0 if dsss else 0.0, profile.cw_min,
        ])  # fmt: skip
        self._nodes = (
            np.full(n, np.inf),  # submission of each queue's head
            np.zeros(n),  # when each node last heard the air turn idle
            np.full(n, difs),  # interframe space
            np.full(n, -np.inf),  # end of the frame each receiver is on
            np.zeros(n, dtype=np.int64),  # frames on the air each node senses
            np.zeros(n, dtype=np.int64),  # backoff counters (slots)
            np.zeros(n, dtype=np.int64),  # each sender's frames not yet sent or dropped
            np.zeros(n, dtype=np.bool_),  # transmitting
            np.ones(n, dtype=np.bool_),  # has a radio
            np.zeros((n, _FIRST_PLACES), dtype=np.int64),  # queues: rings of slots
            np.zeros(n, dtype=np.int64),  # queue heads
            np.zeros(n, dtype=np.int64),  # queue lengths
            # Each node's stream, drawn ahead: 64-bit draws, how many used, how many
            # there are, and the half of one kept for the next 32 bits (PCG64's).
            np.zeros((n, _FIRST_DRAWS), dtype=np.uint64),
            np.zeros(n, dtype=np.int64),
            np.zeros(n, dtype=np.int64),
            np.array([r.bit_generator.state["has_uint32"] for r in rngs], dtype=np.bool_),
            np.array([r.bit_generator.state["uinteger"] for r in rngs], dtype=np.uint64),
        )
        sense = profile.carrier_sense_dbm
        self._sense_dbm = profile.sensitivity_dbm if sense is None else sense
        empty = np.zeros((n, n), dtype=np.bool_)
        self._links: tuple[Any, ...] = (None, None, empty, empty.copy())
        self._short = np.zeros(n, dtype=np.int64)
        self.set_power(np.full((n, n), np.nan))
        self._frames: list[Frame | None] = []
        self._free: list[int] = []
        self._store: tuple[Any, ...] = ()
        self._lists: tuple[Any, ...] = ()
        self._scratch: tuple[Any, ...] = ()
        self._chunks: tuple[Any, ...] = ()
        self._grow(_FIRST_SLOTS)
        self._clock = 0.0
        self._unfinished = 0

    # -- inputs ----------------------------------------------------------------------
    def set_power(self, power_dbm: FloatArray) -> None:
        """The step's mean received power ``power_dbm[s, r]`` (dBm; NaN: no radio)."""
        power_dbm = np.ascontiguousarray(power_dbm, dtype=np.float64)
        senses, hears = self._links[2], self._links[3]
        power_mw = np.empty_like(power_dbm)
        air.set_links(
            power_dbm, self._sense_dbm, self.profile.sensitivity_dbm, senses, hears,
            self._nodes[8], power_mw,
        )  # fmt: skip
        self._links = (power_mw, power_dbm, senses, hears)

    def airtime(self, bits: int) -> float:
        """Seconds on the air of a frame of ``bits``: preamble and bits at the rate."""
        return self.profile.preamble_s + bits * self._seconds_per_bit

    def submit(self, sender: int, stamp: float, bits: int, token: Any) -> None:
        """Hand a frame of ``sender`` published at ``stamp`` (the last :meth:`advance`)
        to the channel; ``token`` comes back with it when it has finished."""
        if not self._free:
            self._grow(2 * len(self._frames))
        slot = self._free.pop()
        frame = Frame(sender, max(stamp, self._clock), bits, token)
        self._frames[slot] = frame
        store = self._store
        store[0][slot] = sender
        store[2][slot] = bits
        store[1][slot] = frame.submitted
        store[5][slot] = False
        lists = self._lists
        lists[5][lists[4][air.FRESH]] = slot
        lists[4][air.FRESH] += 1
        self._nodes[6][sender] += 1
        self._unfinished += 1

    # -- outputs ---------------------------------------------------------------------
    def pending(self) -> int:
        """Frames submitted, queued or on the air."""
        return self._unfinished

    def queued(self, sender: int) -> int:
        """Frames of ``sender`` waiting: submitted, not yet on the air or dropped."""
        return int(self._nodes[6][sender])

    def sensed(self, node: int) -> int:
        """How many frames on the air ``node`` senses (it hears the air busy if any)."""
        return int(self._nodes[4][node])

    def advance(self, now: float) -> list[Frame]:
        """Simulate the channel up to ``now``; the frames that ended (or were dropped)
        since the last call, in the order they did."""
        short, most = air.shortfall(self._nodes, _MARGIN, self._short)
        if most > self._nodes[9].shape[1]:
            self._fit_queues(most)
        if short:
            self._draw_ahead(self._short[:short].tolist())
        counts = self._lists[4]
        counts[air.FINISHED] = counts[air.RELEASED] = counts[air.CHUNKS] = 0
        while not air.advance(
            now, self._settings, self._nodes, self._links, self._store, self._lists,
            self._scratch, self._chunks,
        ):  # fmt: skip
            self._widen_pool()
        self._clock = max(self._clock, now)
        return self._collect()

    def frame_errors(
        self, frame: Frame, power_dbm: FloatArray, receivers: NDArray[np.intp],
        alone: FloatArray, shared: FloatArray,
    ) -> None:  # fmt: skip
        """``frame``'s errors at ``receivers`` (into ``alone`` and ``shared``) at
        received powers ``power_dbm`` (the step's with this packet's fast fading), by
        the rule the channel uses for frames without fading."""
        air.frame_errors(
            power_dbm, frame.chunk_bits, frame.chunk_mw[:, receivers],
            frame.blocked[receivers], frame.bits, self._settings, alone, shared,
        )  # fmt: skip

    # -- between the loop and the frames ----------------------------------------------
    def _fit_queues(self, need: int) -> None:
        """Make every queue's ring hold ``need`` frames (its sender's unsent frames)."""
        qbuf, qhead, qlen = self._nodes[9], self._nodes[10], self._nodes[11]
        places = qbuf.shape[1]
        while places < need:
            places *= 2
        wider = np.zeros((self.n, places), dtype=np.int64)
        for node in range(self.n):
            ring = [qbuf[node, (qhead[node] + k) % qbuf.shape[1]] for k in range(qlen[node])]
            wider[node, : len(ring)] = ring
        qhead[:] = 0
        self._nodes = (*self._nodes[:9], wider, *self._nodes[10:])

    def _draw_ahead(self, short: list[int]) -> None:
        """Draw ahead from the streams of the ``short`` nodes (:func:`air.shortfall`).
        The channel alone draws from these streams, and ``air`` takes from them what
        numpy's ``random`` and ``integers`` would, in the same order."""
        waiting = self._nodes[6]
        raw, used, length = self._nodes[12], self._nodes[13], self._nodes[14]
        for node in short:
            kept = raw[node, used[node] : length[node]]
            need = 2 * int(waiting[node]) + 1 + _MARGIN
            block = self._rngs[node].bit_generator.random_raw(max(_FIRST_DRAWS, need))
            row = np.concatenate((kept, block))
            if len(row) > raw.shape[1]:
                wider = np.zeros((self.n, max(len(row), 2 * raw.shape[1])), dtype=np.uint64)
                wider[:, : raw.shape[1]] = raw
                raw = wider
                self._nodes = (*self._nodes[:12], raw, *self._nodes[13:])
            raw[node, : len(row)] = row
            used[node] = 0
            length[node] = len(row)

    def _collect(self) -> list[Frame]:
        """The frames finished during the last call, with their outcome; the slots it
        released become free."""
        store, lists = self._store, self._lists
        counts = lists[4]
        arrival, start, end, dropped, blocked, alone, shared = (
            store[1], store[3], store[4], store[5], store[6], store[11], store[12]
        )  # fmt: skip
        first, many, chunk_bits, chunk_mw = self._chunks
        finished: list[Frame] = []
        for slot in lists[2][: counts[air.FINISHED]].tolist():
            frame = self._frames[slot]
            assert frame is not None
            frame.submitted = float(arrival[slot])
            frame.end = float(end[slot])
            if dropped[slot]:
                frame.dropped = True
            else:
                frame.start = float(start[slot])
                frame.blocked = blocked[slot].copy()
                lo, hi = first[slot], first[slot] + many[slot]
                frame.chunk_bits = chunk_bits[lo:hi].copy()
                frame.chunk_mw = chunk_mw[lo:hi].copy()
                frame.alone = alone[slot].copy()
                frame.shared = shared[slot].copy()
            finished.append(frame)
        for slot in lists[3][: counts[air.RELEASED]].tolist():
            self._frames[slot] = None
            self._free.append(slot)
        self._unfinished -= len(finished)
        return finished

    def _grow(self, slots: int) -> None:
        """Room for ``slots`` frames (the state of the ones there is kept)."""
        n, old = self.n, len(self._frames)
        kinds = (np.int64, np.float64, np.int64, np.float64, np.float64, np.bool_)
        wide = (np.bool_, np.bool_, np.bool_, *[np.float64] * 4)
        store = tuple(np.zeros(slots, dtype=k) for k in kinds) + tuple(
            np.zeros((slots, n), dtype=k) for k in wide
        )
        lists = (
            *(np.zeros(slots, dtype=np.int64) for _ in range(4)),
            np.zeros(7, dtype=np.int64),
            *(np.zeros(slots, dtype=np.int64) for _ in range(2)),
        )
        if old:
            for new, was in zip(store, self._store, strict=True):
                new[:old] = was
            for new, was in zip(lists, self._lists, strict=True):
                new[: len(was)] = was
        chunks = air.new_chunks(slots, self._chunks[2].shape[0] if old else _FIRST_CHUNKS, n)
        if old:
            for new, was in zip(chunks, self._chunks, strict=True):
                new[: len(was)] = was
        self._chunks = chunks
        scratch = air.new_scratch(n, slots)
        if self._scratch:
            scratch[3][0] = self._scratch[3][0]  # the longest airtime so far
        self._store, self._lists, self._scratch = store, lists, scratch
        self._frames.extend([None] * (slots - old))
        # Lowest slots first (a stack: pop from the end).
        self._free = list(range(slots - 1, old - 1, -1)) + self._free

    def _widen_pool(self) -> None:
        """Twice the chunks in the pool (the ones of this call kept)."""
        first, many, chunk_bits, chunk_mw = self._chunks
        wider = air.new_chunks(len(first), 2 * len(chunk_bits), self.n)
        wider[2][: len(chunk_bits)] = chunk_bits
        wider[3][: len(chunk_bits)] = chunk_mw
        self._chunks = (first, many, wider[2], wider[3])
