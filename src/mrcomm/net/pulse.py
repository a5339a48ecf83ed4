"""ESD pulse: polls the wireless card for the RSSI of each peer and publishes it.

A :class:`Pulse` runs beside a robot's agent (a separate process on a physical robot, so
it keeps running if the agent or navigation crashes). Like every agent it is stepped —
``step(now)`` — and acts only through its :class:`~mrcomm.ports.Bus` endpoint: every
``period`` seconds (0.5 s = 2 Hz) it polls ``iw dev IFACE station dump``, parses it and
publishes one :class:`~mrcomm.messaging.messages.RssiMsg` per known peer on
``TOPIC_RSSI``. Stations with unknown MAC addresses are skipped and counted (logged once
per MAC); a failed poll or unparsable output is counted and the pulse carries on.

A :class:`ReplayPulse` is the same pulse reading a recorded RSSI trace instead of the
card (ESD in live mode on one host, stepped on the world's shared clock). A pulse
publishes as :func:`pulse_id` ``(robot)`` = ``<robot>-pulse``.

Also here: :func:`load_peers` (the MAC ↔ robot id file) and :func:`iw_poller` (the
``iw`` subprocess, checked at start-up).
"""

from __future__ import annotations

import logging
import re
import shutil
import subprocess
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from mrcomm.errors import InputError
from mrcomm.messaging.messages import TOPIC_RSSI, RssiMsg
from mrcomm.net.signal.iw import IwParseError, normalise_mac, parse_station_dump
from mrcomm.net.signal.trace import RssiTrace
from mrcomm.ports import Bus

log = logging.getLogger(__name__)

_IFACE_RE = re.compile(r"^[A-Za-z0-9_.:-]{1,15}$")  # Linux IFNAMSIZ is 16 incl. NUL


class PollError(RuntimeError):
    """Reading the wireless card failed at run time (counted; the pulse keeps going)."""


@dataclass
class PulseStats:
    """What the pulse did, for logs and tests."""

    polls: int = 0
    published: int = 0
    poll_errors: int = 0
    parse_errors: int = 0
    no_signal: int = 0  # known peers whose station block had no signal field
    unknown: dict[str, int] = field(default_factory=dict)  # MAC -> times seen


#: A pulse publishes as ``<robot>-pulse``: one plain key chunk of the Zenoh key space
#: ``mrcomm/<team>/<agent>/<topic>``, apart from its robot's own agent id (the pulse is
#: not a team member and keeps running when the agent dies).
PULSE_SUFFIX = "-pulse"


def pulse_id(robot: str) -> str:
    """The id (and key chunk) a robot's pulse publishes under."""
    return f"{robot}{PULSE_SUFFIX}"


Reading = tuple[str, float]  # (peer robot id, RSSI dBm)


class PulseBase:
    """Stepped at any rate, reads every ``period`` seconds and publishes one
    :class:`RssiMsg` per reading; subclasses say where readings come from."""

    def __init__(
        self, bus: Bus, robot_id: str, period: float = 0.5, *, incarnation: int = 0
    ) -> None:
        if not period > 0:
            raise ValueError("period must be positive")
        self.bus = bus
        self.robot_id = robot_id
        self.period = period
        self.incarnation = incarnation
        self.stats = PulseStats()
        self._seq = 0
        self._next_due: float | None = None

    @property
    def next_due(self) -> float | None:
        """Time of the next poll (None before the first step)."""
        return self._next_due

    def step(self, now: float) -> int:
        """Poll if a period has elapsed; return how many messages were published."""
        if self._next_due is not None and now < self._next_due:
            return 0
        # Keep a steady cadence, but never try to catch up on polls missed while stalled.
        due = self._next_due + self.period if self._next_due is not None else now + self.period
        self._next_due = due if due > now else now + self.period
        return self._poll_once(now)

    def _read(self, now: float) -> list[Reading] | None:
        """The readings of one poll at ``now``; None when the poll failed (counted)."""
        raise NotImplementedError

    def _poll_once(self, now: float) -> int:
        self.stats.polls += 1
        readings = self._read(now)
        if not readings:
            return 0
        for peer, rssi in readings:
            self._seq += 1
            message = RssiMsg(
                sender=self.bus.owner,
                incarnation=self.incarnation,
                seq=self._seq,
                stamp=now,
                robot=self.robot_id,
                peer=peer,
                rssi=rssi,
            )
            self.bus.publish(TOPIC_RSSI, message)
        self.stats.published += len(readings)
        return len(readings)


class Pulse(PulseBase):
    """Publishes the RSSI the wireless card measured of every known peer."""

    def __init__(
        self,
        bus: Bus,
        robot_id: str,
        peers: Mapping[str, str],
        poll: Callable[[], str],
        period: float = 0.5,
        *,
        incarnation: int = 0,
    ) -> None:
        super().__init__(bus, robot_id, period, incarnation=incarnation)
        # MAC -> robot id; our own entry (a team-wide peers file) never shows up in a
        # station dump, so it is harmless to keep.
        self.peers = {normalise_mac(m) or m.lower(): rid for m, rid in peers.items()}
        self.poll = poll

    def _read(self, now: float) -> list[Reading] | None:
        try:
            stations = parse_station_dump(self.poll())
        except PollError as err:
            self.stats.poll_errors += 1
            log.warning("pulse %s: poll failed: %s", self.robot_id, err)
            return None
        except IwParseError as err:
            self.stats.parse_errors += 1
            log.warning("pulse %s: cannot parse iw output: %s", self.robot_id, err)
            return None
        readings: list[Reading] = []
        for station in stations:
            peer = self.peers.get(station.mac)
            if peer is None:
                seen = self.stats.unknown.get(station.mac, 0)
                if seen == 0:
                    log.warning("pulse %s: unknown station %s skipped", self.robot_id, station.mac)
                self.stats.unknown[station.mac] = seen + 1
                continue
            if station.rssi is None:
                self.stats.no_signal += 1
                continue
            readings.append((peer, station.rssi))
        return readings


class ReplayPulse(PulseBase):
    """Replays what ``robot_id`` measured in a recorded trace, on the clock it is
    stepped with (live mode: the world's shared clock), exactly as the simulation's
    :class:`~mrcomm.run.wiring.TracePulse` hands it to the robot's sensor: the latest
    reading of each peer at or before ``now``; nothing once the recording has ended."""

    def __init__(
        self,
        bus: Bus,
        robot_id: str,
        trace: RssiTrace,
        period: float = 0.5,
        *,
        incarnation: int = 0,
        source: str | Path | None = None,
    ) -> None:
        super().__init__(bus, robot_id, period, incarnation=incarnation)
        peers = sorted({b for a, b in trace.pairs if a == robot_id})
        if not peers:
            measuring = sorted({a for a, _ in trace.pairs})
            raise InputError(
                f"no readings measured by {robot_id!r} in the trace "
                f"(measuring robots: {', '.join(measuring)})",
                file=source,
                field="--robot",
            )
        self.trace = trace
        self.ids = (robot_id, *peers)

    def _read(self, now: float) -> list[Reading] | None:
        if now > self.trace.t1:
            return []  # the recording has ended: the pulse reports nothing more
        row = self.trace.matrix_at(now, self.ids)[0]
        return [
            (peer, float(row[j]))
            for j, peer in enumerate(self.ids)
            if j > 0 and row[j] == row[j]  # skip NaN: no reading yet
        ]


def load_peers(path: str | Path) -> dict[str, str]:
    """Read a YAML mapping between robot ids and MAC addresses -> ``{mac: robot_id}``.

    Either direction is accepted per entry (``robot_2: 02:00:00:00:00:02`` or
    ``"02:00:00:00:00:02": robot_2``); a robot may have several MACs, a MAC one robot.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError("file not found", file=p) from None
    except (OSError, UnicodeDecodeError) as err:
        raise InputError(f"cannot read: {err}", file=p) from None
    try:
        # BaseLoader keeps every scalar a string: YAML 1.1 would otherwise read an
        # all-digit MAC such as 10:20:30:40:50:59 as a base-60 integer.
        data = yaml.load(text, Loader=yaml.BaseLoader)
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f"line {mark.line + 1}" if mark is not None else None
        raise InputError(
            f"not valid YAML ({getattr(err, 'problem', err)})", file=p, field=where
        ) from None
    if not isinstance(data, dict) or not data:
        raise InputError(
            "expected a mapping of robot ids to MAC addresses, e.g. 'robot_2: 02:00:00:00:00:02'",
            file=p,
        )
    peers: dict[str, str] = {}
    for key, value in data.items():
        if not isinstance(value, str):
            raise InputError(
                "expected a MAC address or robot id, not a list/mapping", file=p, field=key
            )
        key_mac, value_mac = normalise_mac(key), normalise_mac(value)
        if key_mac is not None and value_mac is not None:
            raise InputError(f"both sides are MAC addresses ({key}, {value})", file=p, field=key)
        if key_mac is None and value_mac is None:
            raise InputError(
                f"neither {key!r} nor {value!r} is a MAC address "
                "(six hex pairs, e.g. 02:00:00:00:00:01)",
                file=p,
                field=key,
            )
        mac, robot = (key_mac, value) if key_mac is not None else (value_mac, key)
        assert mac is not None
        if not robot.strip():
            raise InputError("empty robot id", file=p, field=key)
        if mac in peers and peers[mac] != robot:
            raise InputError(
                f"MAC {mac} given for both {peers[mac]!r} and {robot!r}", file=p, field=key
            )
        peers[mac] = robot.strip()
    return peers


def iw_poller(iface: str, *, timeout: float = 2.0, iw: str = "iw") -> Callable[[], str]:
    """A poll function running ``iw dev IFACE station dump``.

    Checked once at start-up: a missing ``iw`` binary, a bad interface name or an
    interface ``iw`` cannot query raises a one-line :class:`InputError`. Later failures
    raise :class:`PollError` (the pulse counts them and keeps running).
    """
    if not _IFACE_RE.match(iface):
        raise InputError(f"{iface!r} is not a network interface name", field="--iface")
    binary = shutil.which(iw)
    if binary is None:
        raise InputError(
            f"the {iw!r} command was not found on PATH (install the 'iw' package)", field="--iface"
        )
    command = [binary, "dev", iface, "station", "dump"]

    def run() -> str:
        try:
            done = subprocess.run(
                command, capture_output=True, text=True, timeout=timeout, check=False
            )
        except subprocess.TimeoutExpired:
            raise PollError(
                f"'iw dev {iface} station dump' timed out after {timeout:g} s"
            ) from None
        except OSError as err:
            raise PollError(f"cannot run {binary}: {err}") from None
        if done.returncode != 0:
            detail = (done.stderr or done.stdout).strip().splitlines()
            reason = detail[0] if detail else f"exit status {done.returncode}"
            raise PollError(f"'iw dev {iface} station dump' failed: {reason}")
        return done.stdout

    try:
        run()
    except PollError as err:
        raise InputError(f"{err} (is {iface!r} a wireless interface?)", field="--iface") from None
    return run
