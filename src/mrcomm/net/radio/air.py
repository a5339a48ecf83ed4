"""The shared channel's event loop over arrays: 802.11's DCF between two deliveries of
the bus, compiled when numba is there (:mod:`mrcomm.compiled`).

:class:`~mrcomm.net.radio.medium.SharedMedium` keeps the channel's state in the arrays
below and calls :func:`advance` once per delivery; everything between two deliveries —
frames arriving at their senders' queues, carrier sense, backoff, frames starting and
ending, who each receiver locks on, the interference each frame met — runs here in one
call. The rules are the module docstring of :mod:`~mrcomm.net.radio.medium`. The loops
are plain Python over arrays and scalars, so the compiled and the plain forms compute
the same arithmetic in the same order (``tests/net/test_air.py``).

The state, grouped in tuples so that the functions stay readable:

* ``nodes`` (per node): the submission instant of its queue's head (inf: empty), when
  it last heard the air turn idle, its interframe space (DIFS or EIFS), until when it is
  locked on a frame, how many frames on the air it senses, its backoff counter (slots),
  its frames not yet sent, whether it transmits, whether it has a radio; its queue (a
  ring of frame slots: buffer, head, length); its random stream, drawn ahead by the
  caller (:mod:`mrcomm.net.radio.draws`: the last five).
* ``links`` (per sender and receiver, this step): received power in mW and dBm, who
  senses whom, who can hear whom.
* ``store`` (per frame slot): sender, arrival at the MAC, bits, start, end, dropped, and
  per receiver whether it was blocked, the links of its start step (who it keeps busy,
  who can hear it, its power in mW and dBm) and its errors (alone and with the other
  frames).
* ``chunks``: each ended frame's payload cut at the instants other frames started or
  ended during it — per slot its first chunk and how many; per chunk its bits and the
  power of the other frames on the air then (mW per receiver) — in a pool filled
  during one call (:func:`advance` asks for a larger one when it could run short).
* ``lists``: the frames on the air and the recently ended ones (in the order they
  started / ended: interference is summed in this order), the frames finished and the
  slots released during this call, their counts (and the chunks used in the pool), the
  frames submitted since the last call and those waiting to arrive at their queues (in
  the order they will).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from mrcomm.compiled import compiled
from mrcomm.net.radio.chunks import SAME_TIME_S, chunked_error, cut
from mrcomm.net.radio.draws import bounded, uniform
from mrcomm.net.radio.reception import bit_error, decibels, per

#: ``settings``: slot, DIFS, EIFS, preamble airtime, seconds per bit, queue limit (s),
#: noise floor (mW and dBm), preamble SINR threshold (dB; NaN: none), modulation (0
#: QPSK, 1 DSSS), the largest backoff counter (slots).
SLOT, DIFS, EIFS, PREAMBLE, PER_BIT, MAX_QUEUE, NOISE_MW, NOISE_DBM, PREAMBLE_SNR = range(9)
MODULATION, CW = 9, 10
#: ``counts``: frames on the air, recently ended, finished and released during the call,
#: submitted since the last call, arrived at no queue yet; chunks used in the pool.
ON_AIR, RECENT, FINISHED, RELEASED, FRESH, PENDING, CHUNKS = range(7)


@compiled
def _expire(node: int, now: float, settings: Any, nodes: Any, store: Any, lists: Any) -> None:
    """Drop the frames at the head of ``node``'s queue older than the queue limit."""
    head_arrival, _, _, _, _, _, waiting, _, _, qbuf, qhead, qlen = nodes[:12]
    arrival = store[1]
    dropped, end = store[5], store[4]
    finished, released, counts = lists[2], lists[3], lists[4]
    capacity = qbuf.shape[1]
    limit = settings[MAX_QUEUE]
    while qlen[node] > 0:
        slot = qbuf[node, qhead[node]]
        if not now - arrival[slot] > limit + SAME_TIME_S:
            break
        qhead[node] = (qhead[node] + 1) % capacity
        qlen[node] -= 1
        waiting[node] -= 1
        dropped[slot] = True
        end[slot] = now
        finished[counts[FINISHED]] = slot
        counts[FINISHED] += 1
        released[counts[RELEASED]] = slot
        counts[RELEASED] += 1
    head_arrival[node] = arrival[qbuf[node, qhead[node]]] if qlen[node] > 0 else math.inf


@compiled
def _arrive_within(now: float, nodes: Any, store: Any, lists: Any, scratch: Any) -> None:
    """Give the frames submitted since the last call their arrival at the MAC.

    A step publishes all its messages at one instant, where robots publish at instants
    of their own: frames that arrived together at idle nodes would all collide. Each
    frame therefore arrives at a uniform instant of the interval up to ``now`` (from its
    sender's stream; one sender's frames keep their order). The frames waiting to arrive
    are kept in the order of their arrival (ties: of submission)."""
    sender_of, arrival = store[0], store[1]
    fresh, pending, counts = lists[5], lists[6], lists[4]
    n = nodes[0].shape[0]
    if counts[FRESH] == 0:
        return
    # The frames by sender (each sender's in the order submitted).
    per_sender, offsets, grouped, uniforms = scratch[6], scratch[7], scratch[8], scratch[9]
    per_sender[:] = 0
    for j in range(counts[FRESH]):
        per_sender[sender_of[fresh[j]]] += 1
    total = 0
    for s in range(n):
        offsets[s] = total
        total += per_sender[s]
    for j in range(counts[FRESH]):
        s = sender_of[fresh[j]]
        grouped[offsets[s]] = fresh[j]
        offsets[s] += 1
    first = counts[PENDING]
    position = 0
    for s in range(n):
        k = per_sender[s]
        if k == 0:
            continue
        begin = arrival[grouped[position]]
        span = max(now - begin, 0.0)
        for j in range(k):
            uniforms[j] = uniform(s, nodes[12:])
        drawn = np.sort(uniforms[:k]) * span
        for j in range(k):
            slot = grouped[position + j]
            arrival[slot] = begin + drawn[j]
            pending[counts[PENDING]] = slot
            counts[PENDING] += 1
        position += k
    counts[FRESH] = 0
    if first < counts[PENDING]:
        waiting = pending[: counts[PENDING]].copy()
        order = np.argsort(arrival[waiting], kind="mergesort")
        for j in range(waiting.shape[0]):
            pending[j] = waiting[order[j]]


@compiled
def _arrive(slot: int, settings: Any, nodes: Any, store: Any, lists: Any) -> None:
    """Frame ``slot`` reaches its sender's MAC queue."""
    head_arrival, _, _, _, busy, backoff, _, transmitting, _, qbuf, qhead, qlen = nodes[:12]
    sender = store[0][slot]
    arrival = store[1][slot]
    _expire(sender, arrival, settings, nodes, store, lists)
    if qlen[sender] == 0:
        head_arrival[sender] = arrival
        # 802.11: a frame that finds the air busy (and no counter running) backs off.
        if backoff[sender] == 0 and (busy[sender] > 0 or transmitting[sender]):
            backoff[sender] = bounded(sender, nodes[12:], int(settings[CW]))
    capacity = qbuf.shape[1]
    qbuf[sender, (qhead[sender] + qlen[sender]) % capacity] = slot
    qlen[sender] += 1


@compiled
def _next_access(settings: Any, nodes: Any, starters: Any) -> tuple[float, int]:
    """When the next frames go on the air, and whose (written to ``starters``; their
    number returned)."""
    head_arrival, idle_since, ifs, _, busy, backoff, _, transmitting = nodes[:8]
    slot = settings[SLOT]
    first = math.inf
    for node in range(busy.shape[0]):
        if busy[node] == 0 and not transmitting[node] and head_arrival[node] < math.inf:
            counted = idle_since[node] + ifs[node] + backoff[node] * slot
            access = max(counted, head_arrival[node])
            if access < first:
                first = access
    count = 0
    if first == math.inf:
        return first, 0
    for node in range(busy.shape[0]):
        if busy[node] == 0 and not transmitting[node] and head_arrival[node] < math.inf:
            counted = idle_since[node] + ifs[node] + backoff[node] * slot
            if max(counted, head_arrival[node]) <= first + SAME_TIME_S:
                starters[count] = node
                count += 1
    return first, count


@compiled
def _freeze(sensing: Any, now: float, settings: Any, nodes: Any) -> None:
    """The air turns busy at ``now`` for the ``sensing`` nodes that heard it idle: their
    counters keep the slots not yet counted down."""
    _, idle_since, ifs, _, busy, backoff, _, transmitting = nodes[:8]
    slot = settings[SLOT]
    for node in range(busy.shape[0]):
        if sensing[node] and busy[node] == 0 and not transmitting[node]:
            waited = now - idle_since[node] - ifs[node]
            counted = math.floor(max(waited, 0.0) / slot + 1e-9)
            backoff[node] = max(backoff[node] - counted, 0)


@compiled
def _start_frames(
    now: float, starters: Any, count: int, settings: Any, nodes: Any, links: Any, store: Any,
    lists: Any, scratch: Any,
) -> None:  # fmt: skip
    head_arrival, _, _, lock_until, busy, backoff, waiting, transmitting, radio = nodes[:9]
    qbuf, qhead, qlen = nodes[9], nodes[10], nodes[11]
    power_mw, power_dbm, senses, hears = links
    sender_of, _, bits, start, end = store[0], store[1], store[2], store[3], store[4]
    blocked, sensed_by, heard_by, frame_mw, frame_dbm = (
        store[6], store[7], store[8], store[9], store[10]
    )  # fmt: skip
    on_air, counts = lists[0], lists[4]
    n = busy.shape[0]
    capacity = qbuf.shape[1]
    frames, sensing, on_air_mw = scratch[0], scratch[1], scratch[2]
    started = 0
    for k in range(count):
        node = starters[k]
        _expire(node, now, settings, nodes, store, lists)
        if qlen[node] > 0:
            frames[started] = qbuf[node, qhead[node]]
            started += 1
            qhead[node] = (qhead[node] + 1) % capacity
            qlen[node] -= 1
            waiting[node] -= 1
            if qlen[node] > 0:
                head_arrival[node] = store[1][qbuf[node, qhead[node]]]
            else:
                head_arrival[node] = math.inf
    if started == 0:
        return
    # Who hears the air turn busy now (the senders' own counters are spent).
    for r in range(n):
        sensing[r] = False
    for k in range(started):
        s = sender_of[frames[k]]
        for r in range(n):
            if senses[s, r]:
                sensing[r] = True
    for k in range(started):
        sensing[sender_of[frames[k]]] = True
    _freeze(sensing, now, settings, nodes)
    longest = scratch[3]
    for k in range(started):
        f = frames[k]
        s = sender_of[f]
        start[f] = now
        end[f] = now + (settings[PREAMBLE] + bits[f] * settings[PER_BIT])
        for r in range(n):
            sensed_by[f, r] = senses[s, r]
            heard_by[f, r] = hears[s, r] and radio[r]
            frame_mw[f, r] = power_mw[s, r]
            frame_dbm[f, r] = power_dbm[s, r]
        if end[f] - now > longest[0]:
            longest[0] = end[f] - now
    # Receivers busy now cannot take any of these frames; who starts now too.
    for k in range(started):
        transmitting[sender_of[frames[k]]] = True
    for j in range(counts[ON_AIR]):
        other = on_air[j]
        if radio[sender_of[other]]:  # (nothing stops a frame without a radio)
            for k in range(started):
                s = sender_of[frames[k]]
                blocked[other, s] = blocked[other, s] or radio[s]
    # Every frame on the air now is noise to the preamble of each new one (summed in
    # the order they started).
    for r in range(n):
        on_air_mw[r] = 0.0
    for j in range(counts[ON_AIR]):
        for r in range(n):
            on_air_mw[r] += frame_mw[on_air[j], r]
    for k in range(started):
        for r in range(n):
            on_air_mw[r] += frame_mw[frames[k], r]
    threshold = settings[PREAMBLE_SNR]
    noise = settings[NOISE_MW]
    for r in range(n):
        # Of the frames that start in the same instant a receiver takes the first to
        # reach it, the nearest: here the strongest (no capture beyond that).
        strongest = -1
        strength = -1.0
        for k in range(started):
            s = sender_of[frames[k]]
            value = power_mw[s, r] if hears[s, r] else -1.0
            if strongest < 0 or value > strength:
                strongest, strength = k, value
        busy_now = transmitting[r] or lock_until[r] > now + SAME_TIME_S
        free = not busy_now and radio[r] and strength >= 0.0
        for k in range(started):
            f = frames[k]
            s = sender_of[f]
            mine = free and strongest == k
            if mine and not math.isnan(threshold):
                # The preamble is detected above its SINR only.
                signal = frame_mw[f, r]
                rest = noise + on_air_mw[r] - signal
                ratio = signal / rest if rest != 0.0 else (math.inf if signal > 0 else math.nan)
                mine = decibels(ratio) >= threshold
            blocked[f, r] = (busy_now or (heard_by[f, r] and not mine)) and radio[r] and radio[s]
            if mine:
                lock_until[r] = end[f]
    for k in range(started):
        f = frames[k]
        backoff[sender_of[f]] = 0
        for r in range(n):
            if sensed_by[f, r]:
                busy[r] += 1
        on_air[counts[ON_AIR]] = f
        counts[ON_AIR] += 1


@compiled
def _error_above_half(f: int, settings: Any, store: Any, chunks: Any, r: int) -> bool:
    """Whether frame ``f`` is more likely lost than not at receiver ``r`` at its SINR
    (no fading): 802.11 then waits EIFS."""
    frame_dbm = store[10]
    first, many, chunk_bits, chunk_mw = chunks
    power = frame_dbm[f, r]
    received = -math.inf if math.isnan(power) else power
    lo, hi = first[f], first[f] + many[f]
    lost = chunked_error(
        received, chunk_bits[lo:hi], chunk_mw[lo:hi], r, settings[NOISE_MW],
        settings[MODULATION] == 1.0,
    )  # fmt: skip
    return bool(lost > 0.5)


@compiled
def frame_errors(
    power_dbm: Any, chunk_bits: Any, chunk_mw: Any, blocked: Any, bits: int, settings: Any,
    alone: Any, shared: Any,
) -> None:  # fmt: skip
    """Probability that a frame of ``bits`` is lost at each receiver, without (``alone``)
    and with (``shared``) the other frames on the air (its chunks: ``chunk_bits``, and
    ``chunk_mw`` with a column per receiver), at received powers ``power_dbm`` (NaN: a
    node without a position, never lost): 1 where it was ``blocked`` (and 0 alone). The
    preamble was judged when the frame started, so only the alone error applies the
    preamble rule."""
    dsss = settings[MODULATION] == 1.0
    threshold = settings[PREAMBLE_SNR]
    floor_dbm = settings[NOISE_DBM]
    for r in range(power_dbm.shape[0]):
        power = power_dbm[r]
        if blocked[r]:
            alone[r], shared[r] = 0.0, 1.0
        elif math.isnan(power):
            alone[r], shared[r] = 0.0, 0.0
        else:
            lost = per(bit_error(power - floor_dbm, dsss, threshold, True), bits)
            alone[r] = lost
            with_others = chunked_error(
                power, chunk_bits, chunk_mw, r, settings[NOISE_MW], dsss
            )  # fmt: skip
            shared[r] = max(with_others, lost)


@compiled
def _end_frames(
    now: float, settings: Any, nodes: Any, store: Any, lists: Any, scratch: Any, chunks: Any
) -> bool:
    """End the frames on the air that end at ``now``; False (nothing done) when the
    chunk pool might not hold their chunks: each has at most one more than twice the
    frames it can overlap."""
    idle_since, ifs, busy, backoff, transmitting = nodes[1], nodes[2], nodes[4], nodes[5], nodes[7]
    sender_of, start, end = store[0], store[3], store[4]
    blocked, sensed_by, heard_by = store[6], store[7], store[8]
    on_air, recent, finished, released, counts = lists[:5]
    n = busy.shape[0]
    ending, window, sensed, longest = scratch[0], scratch[4], scratch[1], scratch[3]
    ending_now = 0
    for j in range(counts[ON_AIR]):
        if end[on_air[j]] <= now + SAME_TIME_S:
            ending_now += 1
    room = ending_now * (2 * (counts[ON_AIR] + counts[RECENT]) + 1)
    if counts[CHUNKS] + room > chunks[2].shape[0]:
        return False
    # Split the frames on the air into those ending now and the rest (order kept).
    ended = 0
    kept = 0
    for j in range(counts[ON_AIR]):
        f = on_air[j]
        if end[f] <= now + SAME_TIME_S:
            ending[ended] = f
            ended += 1
        else:
            on_air[kept] = f
            kept += 1
    counts[ON_AIR] = kept
    # Every frame that overlapped one is its interference, chunk by chunk.
    size = 0
    for j in range(kept):
        window[size] = on_air[j]
        size += 1
    for j in range(counts[RECENT]):
        window[size] = recent[j]
        size += 1
    for j in range(ended):
        window[size] = ending[j]
        size += 1
    first, many, chunk_bits, chunk_mw = chunks
    for k in range(ended):
        f = ending[k]
        made = cut(
            f, start[f] + settings[PREAMBLE], window, size, start, end, store[2], store[9],
            chunk_bits, chunk_mw, counts[CHUNKS], scratch[10], scratch[11],
        )  # fmt: skip
        first[f] = counts[CHUNKS]
        many[f] = made
        counts[CHUNKS] += made
        finished[counts[FINISHED]] = f
        counts[FINISHED] += 1
    for r in range(n):
        sensed[r] = False
    for k in range(ended):
        f = ending[k]
        for r in range(n):
            if sensed_by[f, r]:
                busy[r] -= 1
                sensed[r] = True
        transmitting[sender_of[f]] = False
    for k in range(ended):
        f = ending[k]
        s = sender_of[f]
        backoff[s] = bounded(s, nodes[12:], int(settings[CW]))  # post-backoff
        sensed[s] = True
        # 802.11 waits EIFS, not DIFS, after a frame received in error: here one its
        # receiver more likely than not lost (the bus draws the real outcome).
        for r in range(n):
            if heard_by[f, r] and not blocked[f, r]:
                lost = _error_above_half(f, settings, store, chunks, r)
                ifs[r] = settings[EIFS] if lost else settings[DIFS]
    for r in range(n):
        if sensed[r] and busy[r] == 0 and not transmitting[r]:
            idle_since[r] = now
    # Keep the frames that ended within one longest airtime of now (they may have
    # overlapped a frame still on the air); release the others' slots.
    kept = 0
    horizon = now - longest[0]
    for j in range(counts[RECENT] + ended):
        f = recent[j] if j < counts[RECENT] else ending[j - counts[RECENT]]
        if end[f] > horizon:
            recent[kept] = f
            kept += 1
        else:
            released[counts[RELEASED]] = f
            counts[RELEASED] += 1
    counts[RECENT] = kept
    return True


@compiled
def advance(
    now: float, settings: Any, nodes: Any, links: Any, store: Any, lists: Any, scratch: Any,
    chunks: Any,
) -> bool:  # fmt: skip
    """Simulate the channel up to ``now``: the frames submitted since the last call get
    their arrival instants, frames reach their queues, start and end; each frame that
    finished gets its errors at this step's power (:func:`frame_errors`, without fast
    fading). False when it stopped before ``now`` because the chunk pool could run short:
    give it a larger pool (the chunks so far copied) and call again."""
    _arrive_within(now, nodes, store, lists, scratch)
    end = store[4]
    on_air, counts, pending = lists[0], lists[4], lists[6]
    starters = scratch[5]
    taken = 0
    room = True
    while True:
        first_end = math.inf
        for j in range(counts[ON_AIR]):
            if end[on_air[j]] < first_end:
                first_end = end[on_air[j]]
        start, count = _next_access(settings, nodes, starters)
        arrival = store[1][pending[taken]] if taken < counts[PENDING] else math.inf
        first = min(first_end, start, arrival)
        if first > now + SAME_TIME_S:
            break
        if arrival <= first:
            _arrive(pending[taken], settings, nodes, store, lists)
            taken += 1
        elif first_end <= start:
            room = _end_frames(first_end, settings, nodes, store, lists, scratch, chunks)
            if not room:
                break
        else:
            _start_frames(start, starters, count, settings, nodes, links, store, lists, scratch)
    for j in range(taken, counts[PENDING]):  # (arriving after now or not yet reached)
        pending[j - taken] = pending[j]
    counts[PENDING] -= taken
    # The errors of the frames that finished, at this step's power.
    power_dbm = links[1]
    sender_of, bits, dropped, blocked, alone, shared = (
        store[0], store[2], store[5], store[6], store[11], store[12]
    )  # fmt: skip
    first, many, chunk_bits, chunk_mw = chunks
    finished = lists[2]
    for j in range(counts[FINISHED]):
        f = finished[j]
        if not dropped[f]:
            lo, hi = first[f], first[f] + many[f]
            frame_errors(
                power_dbm[sender_of[f]], chunk_bits[lo:hi], chunk_mw[lo:hi], blocked[f],
                bits[f], settings, alone[f], shared[f],
            )  # fmt: skip
    return room


@compiled
def set_links(
    power_dbm: Any, sense_dbm: float, sensitivity_dbm: float, senses: Any, hears: Any,
    radio: Any, power_mw: Any,
) -> None:  # fmt: skip
    """Who senses whom and who can hear whom at the step's ``power_dbm[s, r]`` (never
    oneself), and who has a radio: a node with no power to anyone (NaN: the operator's
    virtual node) has none, so it is never blocked and its frames neither are sensed nor
    interfere (a node alone keeps its radio). Also ``power_mw``, the power in mW (0 for
    NaN) by the C library's ``pow``: numpy's own power picks its routine by the
    processor (AVX-512's give other last bits), so the air would depend on the machine."""
    n = power_dbm.shape[0]
    for r in range(n):
        anyone = False
        for s in range(n):
            power = power_dbm[s, r]
            other = s != r
            senses[s, r] = other and power >= sense_dbm
            hears[s, r] = other and power >= sensitivity_dbm
            if other and not math.isnan(power):
                anyone = True
            power_mw[s, r] = 0.0 if math.isnan(power) else 10.0 ** (power / 10.0)
        radio[r] = anyone or n == 1


@compiled
def shortfall(nodes: Any, margin: int, short: Any) -> tuple[int, int]:
    """Before a call: the nodes whose drawn-ahead streams may run short (into ``short``;
    how many returned) — a uniform draw per frame submitted, and at most one backoff
    counter per frame arriving at an empty queue and per frame ending, so
    2·(frames not yet sent) + 1 (the one on the air) + ``margin`` — and the most frames
    any node has waiting (its queue must hold them)."""
    waiting, transmitting, used, length = nodes[6], nodes[7], nodes[13], nodes[14]
    count = 0
    most = 0
    for node in range(waiting.shape[0]):
        most = max(most, waiting[node])
        sending = waiting[node] > 0 or transmitting[node]
        if sending and length[node] - used[node] < 2 * waiting[node] + 1 + margin:
            short[count] = node
            count += 1
    return count, most


def new_scratch(n: int, slots: int) -> tuple[Any, ...]:
    """Work arrays of :func:`advance` for ``n`` nodes and ``slots`` frame slots."""
    return (
        np.zeros(slots, dtype=np.int64),  # frames starting / ending now
        np.zeros(n, dtype=np.bool_),  # nodes sensing a change of the air
        np.zeros(n),  # power on the air at each receiver
        np.zeros(1),  # the longest airtime so far
        np.zeros(3 * slots, dtype=np.int64),  # the interference window
        np.zeros(n, dtype=np.int64),  # the nodes whose frames start next
        np.zeros(n, dtype=np.int64),  # frames submitted per sender
        np.zeros(n, dtype=np.int64),  # where each sender's frames go in the next
        np.zeros(slots, dtype=np.int64),  # frames submitted, by sender
        np.zeros(slots),  # one sender's uniform draws
        np.zeros(6 * slots),  # the instants a frame is cut at
        np.zeros(3 * slots, dtype=np.int64),  # the frames overlapping it
    )


def new_chunks(slots: int, pool: int, n: int) -> tuple[Any, ...]:
    """A chunk pool of ``pool`` chunks for ``slots`` frame slots and ``n`` receivers."""
    return (
        np.zeros(slots, dtype=np.int64),  # each frame's first chunk
        np.zeros(slots, dtype=np.int64),  # and how many
        np.zeros(pool),  # bits in each chunk
        np.zeros((pool, n)),  # the other frames' power in it, mW per receiver
    )
