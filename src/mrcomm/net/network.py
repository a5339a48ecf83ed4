"""Network types (SPEC §3): infrastructure WLAN (no distance cut) and ad-hoc AH (hard
range limit, 8.0 m by default)."""

from __future__ import annotations

from enum import StrEnum


class NetworkType(StrEnum):
    WLAN = "wlan"
    AH = "ah"


#: Hard communication limit of the ad-hoc network, metres (SPEC §3).
AH_RANGE_M = 8.0
