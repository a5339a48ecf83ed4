"""The Zenoh and security options of a live process, declared once for every command
that joins a team (``mrcomm world``, ``mrcomm agent``, ``mrcomm pulse``; ``mrcomm
live`` takes a few of them), as zenoh-python's examples share one set of connection
options: each option's type, default and help here, and :class:`ZenohCli`, what a
command receives of them, which turns them into the process's security and Zenoh
session options.

A command asks for them with one parameter, ``net: ZenohCli``, under
:func:`with_zenoh_options`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from mrcomm.cli.run_options import expand_parameter
from mrcomm.net.zenoh_config import ZenohOptions, make_options

if TYPE_CHECKING:
    from collections.abc import Callable

    from mrcomm.live.identity import Security
    from mrcomm.world.scenario import Scenario

TeamOpt = Annotated[str, typer.Option(help="Team name: the key space mrcomm/<team>/.")]
ListenOpt = Annotated[
    list[str] | None, typer.Option("--listen", help="Endpoint to listen on (repeatable).")
]
ConnectOpt = Annotated[
    list[str] | None, typer.Option("--connect", help="Peer endpoint to connect to (repeatable).")
]
MulticastOpt = Annotated[
    bool, typer.Option("--multicast/--no-multicast", help="Multicast scouting for peers.")
]
ProtocolOpt = Annotated[str, typer.Option(help="Transport: tcp | udp.")]
TeamDirOpt = Annotated[
    Path | None,
    typer.Option(
        "--team-dir",
        help="Team directory (mrcomm team init): mutual TLS with this process's "
        "certificate, and an access-control list that lets each member publish only "
        "under its own keys.",
    ),
]
InsecureOpt = Annotated[
    bool,
    typer.Option(
        "--insecure",
        help="Run without authentication or encryption: anyone on the network can read "
        "and forge the team's messages (prints a warning).",
    ),
]
TlsCaOpt = Annotated[Path | None, typer.Option(help="Team CA certificate (PEM): enables mTLS.")]
TlsCertOpt = Annotated[Path | None, typer.Option(help="This node's certificate (PEM).")]
TlsKeyOpt = Annotated[Path | None, typer.Option(help="This node's private key (PEM).")]
AclOpt = Annotated[
    str | None,
    typer.Option(
        help="With --tls-*: comma-separated member certificate names; each may publish "
        "only under its own keys (ACL)."
    ),
]
ZenohConfigOpt = Annotated[Path | None, typer.Option(help="Zenoh JSON5 config file.")]
LinkLeaseOpt = Annotated[float, typer.Option(help="Zenoh link lease, wall s.")]


@dataclass(frozen=True)
class ZenohCli:
    """What a command was given of the Zenoh options (see the module docstring). Its
    fields are the options' one declaration: their command-line types, help and
    defaults."""

    team: TeamOpt = "team"
    listen: ListenOpt = None
    connect: ConnectOpt = None
    multicast: MulticastOpt = False
    protocol: ProtocolOpt = "tcp"
    team_dir: TeamDirOpt = None
    insecure: InsecureOpt = False
    tls_ca: TlsCaOpt = None
    tls_cert: TlsCertOpt = None
    tls_key: TlsKeyOpt = None
    acl: AclOpt = None
    zenoh_config: ZenohConfigOpt = None
    link_lease: LinkLeaseOpt = 10.0

    @property
    def joins(self) -> bool:
        """Whether any option says how to reach a team (a pulse without one prints)."""
        return bool(self.listen or self.connect or self.multicast or self.zenoh_config)

    def security(self, identity: str, scenario: Scenario | None) -> Security:
        """The process's security, as member ``identity`` (one-line errors)."""
        from mrcomm.live.identity import choose_security

        return choose_security(
            identity=identity,
            team_dir=self.team_dir,
            insecure=self.insecure,
            tls_files=(self.tls_ca, self.tls_cert, self.tls_key),
            acl=self.acl,
            scenario=scenario,
            explicit_config=self.zenoh_config is not None,
        )

    def options(self, security: Security) -> ZenohOptions:
        """The Zenoh options of the process's team session."""
        return self._options(security, self.listen, self.connect, self.multicast)

    def world_options(self, endpoints: list[str], security: Security) -> ZenohOptions:
        """The options of a session of its own to the world process at ``endpoints``
        (its clock and bases; no scouting, no config file)."""
        return self._options(security, None, endpoints, False, config=False)

    def _options(
        self,
        security: Security,
        listen: list[str] | None,
        connect: list[str] | None,
        multicast: bool,
        *,
        config: bool = True,
    ) -> ZenohOptions:
        tls = security.tls
        return make_options(
            team=self.team,
            listen=listen or [],
            connect=connect or [],
            multicast=multicast,
            protocol=self.protocol,
            tls_ca=tls.ca if tls is not None else None,
            tls_cert=tls.cert if tls is not None else None,
            tls_key=tls.key if tls is not None else None,
            acl_grants=security.grants,
            config_file=self.zenoh_config if config else None,
            link_lease=self.link_lease,
        )


def with_zenoh_options(command: Callable[..., None]) -> Callable[..., None]:
    """Give a command the Zenoh options in place of its parameter ``net``, which
    receives them as one :class:`ZenohCli`."""
    # The class declares the options (its fields) and makes what the command receives.
    return expand_parameter(command, "net", ZenohCli, ZenohCli, {"ZenohCli": ZenohCli})


def warn_insecure(insecure: bool) -> None:
    """The one warning line of ``--insecure``: printed once every input is checked,
    just before the process joins the network."""
    if insecure:
        from mrcomm.live.identity import INSECURE_WARNING

        typer.echo(INSECURE_WARNING, err=True)
