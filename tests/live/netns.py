"""The real-network tests' namespaces (``mrcomm.live.netns``) and their skip."""

from __future__ import annotations

import os

import pytest

from mrcomm.live.netns import IFACE, Netns, netns_missing, run_tool
from tests import needs

__all__ = ["IFACE", "Netns", "run_tool", "skip_unless_possible"]


def skip_unless_possible() -> None:
    """Skip (with the reason) where namespaces or nftables cannot be used, or when
    ``MRCOMM_SKIP_NETNS=1`` asks for a quicker run."""
    if os.environ.get("MRCOMM_SKIP_NETNS") == "1":
        pytest.skip("MRCOMM_SKIP_NETNS=1: real-network tests skipped on request")
    missing = needs.missing_commands("ip", "nft") or netns_missing()
    if missing is not None:
        pytest.skip(missing)
