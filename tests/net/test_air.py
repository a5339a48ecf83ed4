"""The shared channel's compiled event loop (net/radio/air.py, draws.py): the same air as the numpy
implementation it replaced, the same air compiled or plain, numpy's draws from the
channel's own streams, and the recorded missions."""

from __future__ import annotations

import hashlib
import json
import math
import os
import subprocess
import sys
from typing import Any

import numpy as np
import pytest

from mrcomm.net.radio import draws
from mrcomm.net.radio.channel import RadioChannel, fading_gain_db
from mrcomm.net.radio.medium import SharedMedium
from mrcomm.net.radio.profile import load_profile
from mrcomm.run.resources import ScenarioResources
from mrcomm.sim.mission import run_mission
from tests.golden.golden import ROOT, comparable

#: The C library's log10, element by element (see air_digest).
_LOG10 = np.vectorize(math.log10, otypes=[np.float64])


def air_digest(seed: int, n: int = 40, steps: int = 200, spread_m: float = 120.0,
               preamble_snr_db: float | None = None) -> tuple[str, int]:  # fmt: skip
    """A random team's air: ``n`` nodes (the last without a radio) wandering over
    ``spread_m`` (120 m: hidden terminals; 20 m: all in range), each submitting 0-3
    frames of 400-3,000 bits a step of 50 ms; a digest of every finished frame (sender,
    token, start, end, dropped, who it was blocked at, its chunks and errors) and their
    number."""
    profile = load_profile("office-2.4ghz")
    if preamble_snr_db is not None:
        profile = profile.model_copy(
            update={"preamble_snr_db": preamble_snr_db, "modulation": "dsss"}
        )
    rng = np.random.default_rng(seed)
    medium = SharedMedium(profile, n, [np.random.default_rng([seed, i]) for i in range(n)])
    xy = rng.uniform(0, spread_m, size=(n, 2))
    out = []
    for step in range(steps):
        xy += rng.normal(0, 0.5, size=xy.shape)
        # Only arithmetic that every machine rounds alike: numpy's hypot and log10 pick
        # their code by the processor (AVX-512 or not), and their last bits differ.
        delta = xy[:, None, :] - xy[None, :, :]
        d = np.sqrt(delta[..., 0] * delta[..., 0] + delta[..., 1] * delta[..., 1])
        p = -40 - 30 * _LOG10(np.maximum(d, 1.0)) + rng.normal(0, 2, size=(n, n))
        np.fill_diagonal(p, np.nan)
        p[n - 1, :] = p[:, n - 1] = np.nan
        medium.set_power(p)
        t = step * 0.05
        for f in medium.advance(t):
            out.append((f.sender, f.token, repr(f.start), repr(f.end), f.dropped,
                        np.asarray(f.blocked).tobytes().hex(),
                        [repr(x) for x in np.asarray(f.chunk_bits).tolist()],
                        [repr(x) for x in np.asarray(f.chunk_mw).ravel().tolist()],
                        [repr(x) for x in np.asarray(f.shared).tolist()]))  # fmt: skip
        for s in range(n):
            for k in range(int(rng.integers(0, 4))):
                medium.submit(s, t, int(rng.integers(400, 3000)), (s, step, k))
    return hashlib.sha256(json.dumps(out).encode()).hexdigest(), len(out)


#: Recorded with the numpy implementation of the channel, before the event loop moved
#: to net/radio/air.py; the compiled loop gave the same air to the last bit. Recorded
#: again when a frame became judged chunk by chunk (its payload cut where other frames
#: start or end, as ns-3 judges it) instead of against every frame that overlapped it
#: at once: the digest now holds each frame's chunks and errors, and the EIFS a
#: receiver waits after a frame it more likely lost follows the new errors. Recorded
#: again when the digests were found to depend on the machine: recorded on a host with
#: AVX-512, they failed on one without (the same frames, other last bits: numpy's
#: hypot, log10 and power choose their routines by the processor). The inputs here and
#: the channel's dBm-to-mW conversion now use the C library's functions only.
AIR_DIGESTS = {
    "hidden": ("1716bb52821262c4102a07ab76a969215ea6cce9cf291c43f48c869b43444326", 11781),
    "in range": ("150577a4023faffd35532d510de2b407ce1b1dec3d780c081dcb4a2685c3a6e6", 10819),
    "dsss, preamble": ("33959b1f115f46ee6a6b5f676cda1916c8568eeef2cca3c29a2f2d1aecfdec7a", 11913),
}
AIR_CASES = {
    "hidden": {"seed": 1},
    "in range": {"seed": 2, "spread_m": 20.0},
    "dsss, preamble": {"seed": 3, "preamble_snr_db": 4.0},
}


@pytest.mark.parametrize("case", sorted(AIR_DIGESTS))
def test_the_air_is_the_recorded_one(case: str) -> None:
    assert air_digest(**AIR_CASES[case]) == AIR_DIGESTS[case]  # type: ignore[arg-type]


def test_a_chunk_pool_that_runs_short_grows_without_changing_the_air(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The loop stops before it could run out of chunks and the medium calls it again
    with a larger pool: from one chunk up, the same air as with a pool never short."""
    from mrcomm.net.radio import medium

    case = {"seed": 5, "n": 16, "steps": 40, "spread_m": 60.0}
    monkeypatch.setattr(medium, "_FIRST_CHUNKS", 1_000_000)
    roomy = air_digest(**case)  # type: ignore[arg-type]
    widened = 0
    widen = medium.SharedMedium._widen_pool

    def counted(self: medium.SharedMedium) -> None:
        nonlocal widened
        widened += 1
        widen(self)

    monkeypatch.setattr(medium, "_FIRST_CHUNKS", 1)
    monkeypatch.setattr(medium.SharedMedium, "_widen_pool", counted)
    assert air_digest(**case) == roomy  # type: ignore[arg-type]
    assert widened >= 5


def test_the_plain_and_the_compiled_loop_give_the_same_air() -> None:
    """Without numba (MRCOMM_NO_NUMBA=1, in a process of its own) the same functions run
    as plain Python: the same air."""
    small: dict[str, Any] = {"seed": 4, "n": 12, "steps": 60, "spread_m": 60.0}
    script = (
        "import sys; sys.path.insert(0, sys.argv[1])\n"
        "from mrcomm.compiled import KERNEL\n"
        "from tests.net.test_air import air_digest\n"
        f"print(KERNEL, *air_digest(**{small!r}))\n"
    )
    env = {**os.environ, "MRCOMM_NO_NUMBA": "1"}
    plain = subprocess.run(
        [sys.executable, "-c", script, str(ROOT)], env=env, capture_output=True, text=True,
        check=True,
    ).stdout.split()  # fmt: skip
    digest, frames = air_digest(**small)
    assert plain == ["python", digest, str(frames)]
    assert frames > 1000


@pytest.mark.parametrize("largest", [31, 15, 1023, 20, 1, 0, 3_000_000_000])
def test_the_channel_draws_what_numpy_would(largest: int) -> None:
    """The loop takes its uniform draws and backoff counters from 64-bit draws made
    ahead: the same values as numpy's random() and integers(0, CW + 1) interleaved on the
    same stream (a window of 3·10⁹ makes Lemire's method reject about a third of its
    draws; a window of one value draws nothing)."""
    ours_rng = np.random.default_rng(7)
    numpy_rng = np.random.default_rng(7)
    raw = ours_rng.bit_generator.random_raw(3000)
    streams = (
        raw[None, :], np.zeros(1, dtype=np.int64), np.array([len(raw)], dtype=np.int64),
        np.zeros(1, dtype=np.bool_), np.zeros(1, dtype=np.uint64),
    )  # fmt: skip
    pattern = np.random.default_rng(0).integers(0, 3, size=1000)
    for kind in pattern.tolist():
        if kind == 0:
            assert draws.uniform(0, streams) == numpy_rng.random()
        else:
            assert draws.bounded(0, streams, largest) == int(numpy_rng.integers(0, largest + 1))
    # The stream is where numpy's is: what comes next agrees too.
    assert draws.uniform(0, streams) == numpy_rng.random()


#: Shared-channel missions (radio · LF or NB · SLT, with the channel shared): recorded
#: when the channel's loop was compiled. They differ from the numpy implementation's
#: only through the packet error of frames far below the noise: scipy's erfc gave 0
#: below 1e-308 where the C library's (the per-message decisions' all along) gives a
#: subnormal number, so a receiver draws once more from its stream (shown by running
#: the old code with the C library's erfc: the same digests). Two recorded again when a
#: mission stopped waiting for a step without a pose in flight: they end 0.1 s sooner,
#: and with the old end rule they give the old digests. S2's recorded again when frames
#: became judged chunk by chunk: one pose of its 6,000 is counted lost to SPL instead
#: of to a collision (its error with the other frames fell and the same draw fell to
#: SPL), all else the same; the S1 missions did not change.
MISSION_DIGESTS = {
    "s1 lf spl50 seed1": "0b16b71ae835d4bd7663b1a599524bb18298b7af7cb2666e5febdf235471542e",
    "s1 lf spl50 seed2": "f36f9900705cd9dfb1cc917036047e9d0ab79c6cc6a385f6af465e6ebd8f13b8",
    "s1 nb spl0 seed3": "8122261a072fa37f05cfae67f8279121cbdf396f91bb15d15b94ede822d548c5",
    "s2 lf spl25 seed1 120s": "683aa6d9eed2b6cb343381e15321dabb6e4a9620673058eab477ab03f30fe296",
}


@pytest.mark.parametrize("case", sorted(MISSION_DIGESTS))
def test_shared_channel_missions_are_the_recorded_ones(case: str) -> None:
    from mrcomm.run.config import make_config

    scenario, behaviour, spl, seed, *rest = case.split()
    path = ROOT / "data" / "scenarios" / ("s1.yaml" if scenario == "s1" else "s2/s2.yaml")
    extra = {"max_time": float(rest[0].rstrip("s"))} if rest else {}
    config = make_config(
        None, scenario=path, seed=int(seed.removeprefix("seed")),
        spl=int(spl.removeprefix("spl")), behaviour=behaviour, threshold="slt",
        network="radio", params={"network": {"channel": "shared"}}, **extra,
    )  # fmt: skip
    result = run_mission(config, ScenarioResources.load(path))
    blob = json.dumps(comparable(result), sort_keys=True)
    assert hashlib.sha256(blob.encode()).hexdigest() == MISSION_DIGESTS[case]


def test_with_fast_fading_a_frame_is_judged_at_each_packets_power() -> None:
    """A profile with fading: the receivers judged get the frame's errors at the step's
    power plus this packet's fading gain (drawn from their streams), by the same rule as
    frames without fading; the receivers not judged get exactly those of the frame."""
    profile = load_profile("office-2.4ghz").model_copy(update={"fading": "rician"})
    ids = ["a", "b", "c", "d"]
    medium = SharedMedium(profile, 4, [np.random.default_rng([9, i]) for i in range(4)])
    fading = {a: np.random.default_rng([8, i]) for i, a in enumerate(ids)}
    channel = RadioChannel(profile, ids, fading, medium)
    power = np.full((4, 4), -88.0)  # near the sensitivity: errors are neither 0 nor 1
    np.fill_diagonal(power, np.nan)
    channel.set_links(power, None)
    medium.submit(0, 0.0, 2000, "frame")
    (frame,) = medium.advance(0.1)
    receivers = np.array([1, 2, 3])
    judged = np.array([True, True, False])
    alone, shared = channel.frame_errors(frame, receivers, judged)
    assert alone[2] == frame.alone[3] and shared[2] == frame.shared[3]  # not judged
    assert 0.0 < frame.alone[1] < 1.0
    assert alone[0] != frame.alone[1] and alone[1] != frame.alone[2]  # faded
    # The same packet powers without fading give these errors: the one rule.
    check = np.random.default_rng([8, 1])
    faded = power[0, 1] + fading_gain_db(check, profile.rician_k_db)
    out_alone, out_shared = np.empty(1), np.empty(1)
    medium.frame_errors(frame, np.array([faded]), np.array([1]), out_alone, out_shared)
    assert (out_alone[0], out_shared[0]) == (alone[0], shared[0])


def test_the_channel_takes_only_pcg64_streams() -> None:
    """Its draws are numpy's values as PCG64 serves them: another bit generator is
    refused rather than drawn from wrongly."""
    profile = load_profile("office-2.4ghz")
    with pytest.raises(ValueError, match="PCG64"):
        SharedMedium(profile, 2, [np.random.Generator(np.random.Philox(i)) for i in range(2)])
