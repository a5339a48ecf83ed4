"""Parse ``iw dev IFACE station dump`` output (Linux nl80211) into stations (ESD).

The output is one block per station::

    Station 02:00:00:00:00:02 (on wlan0)
        inactive time:	304 ms
        signal:  	-38 [-40, -41] dBm
        signal avg:	-39 [-41, -42] dBm
        tx bitrate:	65.0 MBit/s MCS 7
        ...

Only the fields ESD needs are kept; unknown fields are ignored (their set changes
between iw and kernel versions). Empty output means no stations. Anything that is not
this structure raises :class:`IwParseError` (a runtime condition the pulse counts, not
bad user input).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

MAC_RE = re.compile(r"^[0-9a-fA-F]{2}([:-])(?:[0-9a-fA-F]{2}\1){4}[0-9a-fA-F]{2}$")
_STATION_RE = re.compile(r"^Station\s+(\S+)(?:\s+\(on\s+(\S+)\))?\s*$")
_DBM_RE = re.compile(r"^(-?\d+(?:\.\d+)?)\s*(?:\[[^\]]*\]\s*)?dBm\b")
_MS_RE = re.compile(r"^(\d+)\s*ms\b")
_RATE_RE = re.compile(r"^(\d+(?:\.\d+)?)\s*MBit/s\b")


class IwParseError(ValueError):
    """The text is not ``iw station dump`` output."""


@dataclass(frozen=True)
class Station:
    """One peer as the wireless card sees it. ``None``: field absent in the dump."""

    mac: str  # lower case, colon separated
    iface: str | None = None
    signal_dbm: float | None = None
    signal_avg_dbm: float | None = None
    inactive_ms: float | None = None
    rx_bitrate_mbps: float | None = None
    tx_bitrate_mbps: float | None = None

    @property
    def rssi(self) -> float | None:
        """The reading ESD uses: last-frame signal, else the average, else None."""
        return self.signal_dbm if self.signal_dbm is not None else self.signal_avg_dbm


def normalise_mac(text: str) -> str | None:
    """``AA-BB-...`` / ``aa:bb:...`` -> ``aa:bb:...``; None if not a MAC address."""
    text = text.strip()
    if not MAC_RE.match(text):
        return None
    return text.lower().replace("-", ":")


def parse_station_dump(text: str) -> list[Station]:
    """All stations in ``iw dev IFACE station dump`` output (empty text: none)."""
    stations: list[Station] = []
    current: dict[str, object] | None = None
    for lineno, raw in enumerate(text.splitlines(), start=1):
        if not raw.strip():
            continue
        if not raw[0].isspace():
            match = _STATION_RE.match(raw.strip())
            mac = normalise_mac(match.group(1)) if match else None
            if match is None or mac is None:
                raise IwParseError(f"line {lineno}: expected 'Station <MAC> (on <iface>)'")
            if current is not None:
                stations.append(Station(**current))  # type: ignore[arg-type]
            current = {"mac": mac, "iface": match.group(2)}
            continue
        if current is None:
            raise IwParseError(f"line {lineno}: field before any 'Station' line")
        key, sep, value = raw.strip().partition(":")
        if not sep:
            raise IwParseError(f"line {lineno}: expected 'name: value'")
        _read_field(current, key.strip(), value.strip(), lineno)
    if current is not None:
        stations.append(Station(**current))  # type: ignore[arg-type]
    return stations


_FIELDS = {
    "signal": ("signal_dbm", _DBM_RE),
    "signal avg": ("signal_avg_dbm", _DBM_RE),
    "inactive time": ("inactive_ms", _MS_RE),
    "rx bitrate": ("rx_bitrate_mbps", _RATE_RE),
    "tx bitrate": ("tx_bitrate_mbps", _RATE_RE),
}


def _read_field(station: dict[str, object], key: str, value: str, lineno: int) -> None:
    spec = _FIELDS.get(key)
    if spec is None:
        return
    name, pattern = spec
    match = pattern.match(value)
    if match is None:
        if name.endswith("bitrate_mbps"):
            # Some drivers print "unknown" rates; the bitrate is optional information.
            return
        raise IwParseError(f"line {lineno}: cannot read {key!r} value {value!r}")
    station[name] = float(match.group(1))
