"""A network of Linux network namespaces on this host, for live missions over an
emulated radio (``mrcomm live --emulate``) and the real-network tests.

One namespace per process, each joined by a veth link to a bridge in a hub namespace;
addresses ``10.77.0.<k>/24`` exist only inside these namespaces (nothing is added to
the host's own network). Kernel-level faults of one namespace are nftables rules on its
input hook: random drop with ``numgen random`` (tc netem is not available), or an
outage (drop everything, optionally one way only). Packets from ``spared`` addresses
(the world process: the stand-in for each robot's own body, local on a real robot) are
never dropped. Per-pair drops between namespaces are rules on the hub's bridge
(``live.kernel_links``). Needs root, ``ip`` (iproute2) and ``nft`` (nftables).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from collections.abc import Iterable

IFACE = "m0"


#: Namespaces of a run are named ``mrc<pid of the launcher>hub`` and ``...n<k>``.
NETNS_PREFIX = "mrc"
_NETNS_NAME = re.compile(rf"^{NETNS_PREFIX}(\d+)(hub|n\d+)$")


def remove_stale_namespaces() -> list[str]:
    """Delete the namespaces (and with them their links and nftables tables) of runs
    whose launcher has gone (killed before it could delete them); their names."""
    from mrcomm.live.leftovers import alive

    try:
        listing = run_tool("ip", "netns", "list")
    except (OSError, subprocess.SubprocessError):
        return []
    removed = []
    for line in listing.splitlines():
        name = line.split(" ", 1)[0]
        match = _NETNS_NAME.match(name)
        if match is not None and not alive(int(match.group(1))):
            subprocess.run(["ip", "netns", "del", name], capture_output=True, timeout=30)
            removed.append(name)
    return removed


def run_tool(*args: str, stdin: str | None = None) -> str:
    """Run ``ip`` / ``nft``; their stderr in the exception when they fail."""
    done = subprocess.run(args, check=True, capture_output=True, text=True, input=stdin, timeout=30)
    return done.stdout


def netns_missing() -> str | None:
    """Why namespaces with nftables cannot be used here (None when they can)."""
    if os.geteuid() != 0:
        return "network namespaces need root"
    for tool, package in (("ip", "iproute2"), ("nft", "nftables")):
        if shutil.which(tool) is None:
            return f"'{tool}' is not installed (apt-get install {package})"
    probe = f"mrcprobe{os.getpid()}"
    try:
        run_tool("ip", "netns", "add", probe)
    except subprocess.CalledProcessError as err:
        return f"cannot create a network namespace: {err.stderr.strip()}"
    try:
        run_tool("ip", "netns", "exec", probe, "nft", "add", "table", "inet", "probe")
    except subprocess.CalledProcessError as err:
        return f"nftables unusable in a namespace: {err.stderr.strip()}"
    finally:
        subprocess.run(["ip", "netns", "del", probe], capture_output=True, timeout=30)
    return None


class Netns:
    """Namespaces for ``names``; use as a context manager (everything is removed)."""

    def __init__(self, names: Iterable[str], spared: Iterable[str] = ()) -> None:
        self.names = tuple(names)
        tag = f"{NETNS_PREFIX}{os.getpid()}"  # unique on this host while we run
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
        run_tool("ip", "netns", "add", self.hub)
        self._created.append(self.hub)
        run_tool("ip", "-n", self.hub, "link", "add", "br0", "type", "bridge")
        run_tool("ip", "-n", self.hub, "link", "set", "br0", "up")
        for i, name in enumerate(self.names):
            ns = self.ns[name]
            run_tool("ip", "netns", "add", ns)
            self._created.append(ns)
            peer = f"p{i}"
            # Both ends are created inside the namespaces: nothing appears on the host.
            run_tool(
                "ip", "-n", ns, "link", "add", IFACE, "type", "veth",
                "peer", "name", peer, "netns", self.hub,
            )  # fmt: skip
            run_tool("ip", "-n", self.hub, "link", "set", peer, "master", "br0", "up")
            run_tool("ip", "-n", ns, "addr", "add", f"{self.ip[name]}/24", "dev", IFACE)
            run_tool("ip", "-n", ns, "link", "set", IFACE, "up")
            run_tool("ip", "-n", ns, "link", "set", "lo", "up")
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
        run_tool("ip", "netns", "exec", self.ns[name], "nft", "-f", "-", stdin=script)

    def close(self) -> None:
        for ns in reversed(self._created):
            subprocess.run(["ip", "netns", "del", ns], capture_output=True, timeout=30)
        self._created.clear()
