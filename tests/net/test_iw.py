"""Parsing ``iw dev IFACE station dump`` output."""

from __future__ import annotations

from pathlib import Path

import pytest

from mrcomm.net.signal.iw import IwParseError, normalise_mac, parse_station_dump

FIXTURES = Path(__file__).parent / "fixtures"


def _read(name: str) -> str:
    return (FIXTURES / name).read_text(encoding="utf-8")


def test_parses_several_stations() -> None:
    stations = parse_station_dump(_read("iw_station_dump_adhoc.txt"))
    assert [s.mac for s in stations] == [
        "02:00:00:00:00:02",
        "02:00:00:00:00:03",
        "aa:bb:cc:dd:ee:01",
    ]
    first = stations[0]
    assert first.iface == "wlan0"
    assert first.signal_dbm == -38.0 and first.signal_avg_dbm == -39.0
    assert first.inactive_ms == 304.0
    assert first.tx_bitrate_mbps == 65.0 and first.rx_bitrate_mbps == 1.0
    assert stations[1].rssi == -57.0
    third = stations[2]  # older iw: no per-chain values, no average, unknown rx rate
    assert third.signal_dbm == -71.0 and third.signal_avg_dbm is None
    assert third.rx_bitrate_mbps is None


def test_missing_signal_field() -> None:
    stations = parse_station_dump(_read("iw_station_dump_no_signal.txt"))
    assert stations[0].signal_dbm is None and stations[0].rssi is None
    assert stations[0].inactive_ms == 9000.0
    assert stations[1].signal_dbm is None and stations[1].rssi == -49.0  # falls back to avg


def test_no_stations() -> None:
    assert parse_station_dump(_read("iw_station_dump_empty.txt")) == []
    assert parse_station_dump("\n\n") == []


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        (None, "line 1: expected 'Station <MAC>"),
        ("\tsignal: -40 dBm\n", "field before any 'Station' line"),
        ("Station 02:00:00:00:00:0Z (on wlan0)\n", "expected 'Station <MAC>"),
        ("Station 02:00:00:00:00:02 (on wlan0)\n\tsignal:\tstrong\n", "cannot read 'signal'"),
        ("Station 02:00:00:00:00:02 (on wlan0)\n\tno colon here\n", "expected 'name: value'"),
        ("command failed: No such device (-19)\n", "line 1"),
    ],
)
def test_garbage_raises_parse_error(text: str | None, expected: str) -> None:
    with pytest.raises(IwParseError, match=expected.replace("(", r"\(")):
        parse_station_dump(_read("iw_station_dump_garbage.txt") if text is None else text)


def test_normalise_mac() -> None:
    assert normalise_mac("AA-BB-CC-DD-EE-0F") == "aa:bb:cc:dd:ee:0f"
    assert normalise_mac(" 02:00:00:00:00:01 ") == "02:00:00:00:00:01"
    for bad in ("02:00:00:00:00", "02:00-00:00:00:01", "zz:00:00:00:00:01", "robot_1"):
        assert normalise_mac(bad) is None
