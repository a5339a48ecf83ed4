"""A throwaway network of Linux network namespaces for the real-network tests.

One namespace per process, each joined by a veth link to a bridge in a hub namespace;
addresses ``10.77.0.<k>/24`` exist only inside these namespaces (nothing is added to
the host's own network). Kernel-level faults are nftables rules on each namespace's
input hook: random drop with ``numgen random`` (tc netem is not available), or an
outage (drop everything, optionally one way only). Packets from ``spared`` addresses
(the world process: the stand-in for each robot's own body, local on a real robot) are
never dropped.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from collections.abc import Iterable

import pytest

IFACE = "m0"


def _run(*args: str, stdin: str | None = None) -> None:
    subprocess.run(args, check=True, capture_output=True, text=True, input=stdin, timeout=30)


def skip_unless_possible() -> None:
    """Skip (with the reason) where namespaces or nftables cannot be used, or when
    ``MRCOMM_SKIP_NETNS=1`` asks for a quicker run."""
    if os.environ.get("MRCOMM_SKIP_NETNS") == "1":
        pytest.skip("MRCOMM_SKIP_NETNS=1: real-network tests skipped on request")
    if os.geteuid() != 0:
        pytest.skip("network namespaces need root")
    for tool in ("ip", "nft"):
        if shutil.which(tool) is None:
            pytest.skip(f"'{tool}' is not installed (apt-get install iproute2 nftables)")
    probe = f"mrcprobe{os.getpid()}"
    try:
        _run("ip", "netns", "add", probe)
    except subprocess.CalledProcessError as err:
        pytest.skip(f"cannot create a network namespace: {err.stderr.strip()}")
    try:
        _run("ip", "netns", "exec", probe, "nft", "add", "table", "inet", "probe")
    except subprocess.CalledProcessError as err:
        pytest.skip(f"nftables unusable in a namespace: {err.stderr.strip()}")
    finally:
        subprocess.run(["ip", "netns", "del", probe], capture_output=True, timeout=30)


class Netns:
    """Namespaces for ``names``; use as a context manager (everything is removed)."""

    def __init__(self, names: Iterable[str], spared: Iterable[str] = ()) -> None:
        self.names = tuple(names)
        tag = f"mrc{os.getpid() % 100000}"
        self.hub = f"{tag}hub"
        self.ns = {name: f"{tag}n{i}" for i, name in enumerate(self.names)}
        self.ip = {name: f"10.77.0.{i + 1}" for i, name in enumerate(self.names)}
        self.spared = tuple(spared)
        self._created: list[str] = []

    def __enter__(self) -> Netns:
        try:
            self._create()
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _create(self) -> None:
        _run("ip", "netns", "add", self.hub)
        self._created.append(self.hub)
        _run("ip", "-n", self.hub, "link", "add", "br0", "type", "bridge")
        _run("ip", "-n", self.hub, "link", "set", "br0", "up")
        for i, name in enumerate(self.names):
            ns = self.ns[name]
            _run("ip", "netns", "add", ns)
            self._created.append(ns)
            peer = f"p{i}"
            # Both ends are created inside the namespaces: nothing appears on the host.
            _run(
                "ip", "-n", ns, "link", "add", IFACE, "type", "veth",
                "peer", "name", peer, "netns", self.hub,
            )  # fmt: skip
            _run("ip", "-n", self.hub, "link", "set", peer, "master", "br0", "up")
            _run("ip", "-n", ns, "addr", "add", f"{self.ip[name]}/24", "dev", IFACE)
            _run("ip", "-n", ns, "link", "set", IFACE, "up")
            _run("ip", "-n", ns, "link", "set", "lo", "up")
            self.set_faults(name)

    def wrapper(self, name: str) -> list[str]:
        return ["ip", "netns", "exec", self.ns[name]]

    def set_faults(self, name: str, *, loss: float = 0.0, down: bool = False) -> None:
        """Replace ``name``'s input rules: drop ``loss`` % of packets at random, or
        everything while ``down``; packets from spared addresses always pass."""
        spare = " ".join(f"ip saddr != {self.ip[s]}" for s in self.spared if s != name)
        rules = ""
        if down:
            rules = f'iifname "{IFACE}" {spare} drop'
        elif loss > 0:
            rules = f'iifname "{IFACE}" {spare} numgen random mod 100 < {round(loss)} drop'
        script = (
            "table inet mrcomm\ndelete table inet mrcomm\n"
            "table inet mrcomm {\n chain input {\n"
            "  type filter hook input priority 0; policy accept;\n"
            f"  {rules}\n }}\n}}\n"
        )
        _run("ip", "netns", "exec", self.ns[name], "nft", "-f", "-", stdin=script)

    def close(self) -> None:
        for ns in reversed(self._created):
            subprocess.run(["ip", "netns", "del", ns], capture_output=True, timeout=30)
        self._created.clear()
