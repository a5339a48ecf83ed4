"""KernelLinks: the network model's decisions applied by the Linux kernel to the
agents' real traffic (``mrcomm live --emulate``).

Every agent process runs in its own network namespace behind a bridge in a hub
namespace (``live.netns``). The world process, which evaluates every link of the team
on the robots' true positions anyway, sets each ordered pair's packet drop probability
on that bridge (one nftables table in the hub, ``bridge`` family, forward hook), at a
fixed rate of mission time (2 Hz by default, as the pulse; at ``--speed`` 10 that is
20 updates per wall second, a few milliseconds of ``nft`` each):

* out of range (the network model's ``connected`` is false: AH beyond its range, the
  radio below its sensitivity) — every packet dropped;
* in range — the run's SPL (static packet loss, %) at random (``numgen random``) and,
  with the ``radio`` network model, the link's packet error for a packet of
  :data:`PACKET_BYTES` at its mean received power (no fast fading: one rate per
  period), combined as independent losses;
* between two nodes of one process (an assigner hosted on its robot) — nothing to do.

The world's own traffic (the robots' bodies: local on a real robot) is never touched.
Each rule counts the packets it saw and those it dropped; at every update the counts of
the period that ends are read and journalled with the probabilities that were in force
(``kernel`` lines), so a run shows how the kernel's delivery followed the model.
Dropping happens per packet: what it does to messages depends on the transport (TCP
retransmits, so messages arrive late or the session breaks; UDP loses them).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

from mrcomm.errors import InputError
from mrcomm.live.netns import run_tool
from mrcomm.net.links import LinkState

TABLE = "mrcomm_links"
PERMILLE = 1000
#: The packet the radio's packet error is computed for: a pose message in one Zenoh
#: frame with its TCP/IP headers (~150 B); the profile adds its own header.
PACKET_BYTES = 150


@dataclass(frozen=True)
class Emulation:
    """Where the team's processes are: the hub namespace and each link node's address
    (robots, and the task assigner: its own process's, or its host robot's)."""

    hub: str
    addresses: dict[str, str]
    rate: float = 2.0  # updates per simulated second

    def write(self, path: Path) -> Path:
        data = {"hub": self.hub, "addresses": self.addresses, "rate": self.rate}
        path.write_text(json.dumps(data, indent=1))
        return path

    @classmethod
    def read(cls, path: Path) -> Emulation:
        try:
            data = json.loads(path.read_text())
            return cls(str(data["hub"]), dict(data["addresses"]), float(data["rate"]))
        except (OSError, ValueError, KeyError, TypeError) as error:
            message = f"not an emulation file: {error}"
            raise InputError(message, file=path, field="--emulate") from None


class KernelLinks:
    """Sets and measures the per-pair drop rules of the hub's bridge."""

    def __init__(
        self,
        emulation: Emulation,
        spl: float,
        write: Callable[..., None],
        tool: Callable[..., str] = run_tool,
        packet_error: Callable[[float], float] | None = None,
    ) -> None:
        """``write(kind, **data)``: the world's journal; ``tool``: runs ``ip``/``nft``;
        ``packet_error``: a packet's loss probability at a received power (dBm), with
        the ``radio`` network model."""
        self.emulation = emulation
        self.spl = spl / 100.0
        self.spl_permille = round(spl * PERMILLE / 100.0)
        self._packet_error = packet_error
        self._write = write
        self._tool = tool
        self._in_force: dict[tuple[str, str], int] = {}  # (from, to) -> drop permille
        self._since = 0.0
        self._next = 0.0  # mission time of the next update
        self.updates = 0
        #: The node whose links stand for each address: the first named (a robot before
        #: the task assigner it hosts; both share one process and one address).
        self.node_of: dict[str, str] = {}
        for node, address in emulation.addresses.items():
            self.node_of.setdefault(address, node)

    def due(self, now: float) -> bool:
        return now >= self._next - 1e-9

    def update(self, links: LinkState, now: float) -> None:
        """Journal the period that ends, then set the rules for the next one."""
        self._next = now + 1.0 / self.emulation.rate
        if self._in_force:
            self._journal(now)
        permille = self.permille(links)
        self._tool("ip", "netns", "exec", self.emulation.hub, "nft", "-f", "-",
                   stdin=self.script(permille))  # fmt: skip
        self._in_force = permille
        self._since = now
        self.updates += 1

    def close(self, now: float) -> None:
        """Journal the last period and remove the rules."""
        if self._in_force:
            self._journal(now)
        self._in_force = {}
        script = f"table bridge {TABLE}\ndelete table bridge {TABLE}\n"
        self._tool("ip", "netns", "exec", self.emulation.hub, "nft", "-f", "-", stdin=script)

    # -- the model's decisions -----------------------------------------------------------
    def permille(self, links: LinkState) -> dict[tuple[str, str], int]:
        """Each ordered pair's drop probability (‰) from the link state."""
        speaking = set(self.node_of.values())
        out: dict[tuple[str, str], int] = {}
        for i, a in enumerate(links.ids):
            for j, b in enumerate(links.ids):
                if i == j or a not in speaking or b not in speaking:
                    continue
                if not bool(links.connected[i, j]):
                    out[(a, b)] = PERMILLE
                elif self._packet_error is None or links.power is None:
                    out[(a, b)] = self.spl_permille
                else:
                    error = self._packet_error(float(links.power[i, j]))
                    loss = 1.0 - (1.0 - self.spl) * (1.0 - error)
                    out[(a, b)] = min(PERMILLE, round(loss * PERMILLE))
        return out

    def script(self, permille: Mapping[tuple[str, str], int]) -> str:
        """The whole table, replaced atomically by ``nft -f`` (counters start at 0)."""
        addresses = self.emulation.addresses
        rules = []
        for (a, b), p in sorted(permille.items()):
            match = f"ip saddr {addresses[a]} ip daddr {addresses[b]} counter"  # all seen
            if p >= PERMILLE:
                rules.append(f"  {match} counter drop")
            elif p > 0:
                rules.append(f"  {match} numgen random mod {PERMILLE} < {p} counter drop")
            else:
                rules.append(f"  {match}")
        return (
            f"table bridge {TABLE}\ndelete table bridge {TABLE}\n"
            f"table bridge {TABLE} {{\n chain forward {{\n"
            "  type filter hook forward priority 0; policy accept;\n"
            + "\n".join(rules)
            + "\n }\n}\n"
        )

    # -- what the kernel did -------------------------------------------------------------
    def counts(self) -> dict[tuple[str, str], tuple[int, int]]:
        """Packets seen and dropped per ordered pair since the rules were set."""
        listing = self._tool(
            "ip", "netns", "exec", self.emulation.hub, "nft", "-j", "list", "table", "bridge",
            TABLE,
        )  # fmt: skip
        by_address = self.node_of
        out: dict[tuple[str, str], tuple[int, int]] = {}
        for item in json.loads(listing).get("nftables", []):
            rule = item.get("rule")
            if rule is None:
                continue
            pair: list[str] = []
            counters: list[int] = []
            for expr in rule["expr"]:
                if "match" in expr:
                    pair.append(str(expr["match"]["right"]))
                elif "counter" in expr:
                    counters.append(int(expr["counter"]["packets"]))
            if len(pair) < 2 or not counters:
                continue
            seen, dropped = counters[0], (counters[1] if len(counters) > 1 else 0)
            out[(by_address[pair[0]], by_address[pair[1]])] = (seen, dropped)
        return out

    def _journal(self, now: float) -> None:
        counts = self.counts()
        pairs = [
            [a, b, p, *counts.get((a, b), (0, 0))] for (a, b), p in sorted(self._in_force.items())
        ]
        self._write("kernel", t0=round(self._since, 3), t1=round(now, 3), pairs=pairs)
