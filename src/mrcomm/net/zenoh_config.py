"""Zenoh session configuration of the live mode (DESIGN ``live``; issue 7 §1).

Turns the command-line choices (listen / connect endpoints, multicast scouting on or
off, TCP or UDP, optional mutual TLS and an access-control list) or a Zenoh JSON5
config file into a ``zenoh.Config`` for a *peer* (no router: every robot its own
node), and fixes the quality of service of every topic (the lanes of
:mod:`mrcomm.messaging.topics`). Every bad
value is a one-line :class:`~mrcomm.errors.InputError` naming the option, raised
before any session is opened.

With TLS, every node presents a certificate signed by the team's CA and requires one
from its peers (mutual authentication), so a process without the team's certificate
cannot even connect. The access-control list then binds identity to keys: every node
accepts from a member (by certificate common name) publications and liveliness tokens
only under that member's own key chunks ``mrcomm/<team>/<chunk>/**`` (its *grants*: a
robot its id and its pulse's, the world ``world``), and lets members subscribe to and
query the team's keys; everything else is denied. Each node enforces this on what it
receives (ingress), so a member certificate cannot pose as another robot or the world,
whatever its holder configures on its own node.
"""

from __future__ import annotations

import json
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mrcomm.errors import InputError

#: Transport protocols a live node may use.
PROTOCOLS = ("tcp", "udp", "tls")
_ENDPOINT = re.compile(
    r"^(?P<proto>[a-z0-9-]+)/(?P<host>\[[0-9a-fA-F:.]+\]|[^/:\s]+):(?P<port>\d+)$"
)
#: Characters that would change the meaning of a Zenoh key expression; at most 48 of
#: them (an id names a certificate: X.509 names hold 64 characters).
_KEY_CHUNK = re.compile(r"^[A-Za-z0-9_.\-]{1,48}$")
#: Message kinds that speak *as* their sender (Zenoh 1.x vocabulary): a member may send
#: them only under its own key chunks.
_ACL_AUTHORED = ["put", "delete", "liveliness_token"]
#: Message kinds that ask or answer about keys (subscriptions, queries, the replies to
#: them): any member, anywhere under the team's keys.
_ACL_READING = [
    "declare_subscriber",
    "query",
    "declare_queryable",
    "reply",
    "declare_liveliness_subscriber",
    "liveliness_query",
]


@dataclass(frozen=True)
class TlsFiles:
    """PEM files of one node: the team CA, this node's certificate and its key."""

    ca: Path
    cert: Path
    key: Path


@dataclass(frozen=True)
class ZenohOptions:
    """How one live process joins the team's Zenoh network."""

    team: str = "team"
    listen: tuple[str, ...] = ()
    connect: tuple[str, ...] = ()
    multicast: bool = False
    protocol: str = "tcp"
    tls: TlsFiles | None = None
    #: Access control (needs ``tls``): certificate common name -> the key chunks under
    #: ``mrcomm/<team>/`` it may publish under (:func:`acl_json`).
    acl_grants: tuple[tuple[str, tuple[str, ...]], ...] | None = None
    config_file: Path | None = None
    #: Seconds without any traffic after which a peer link is declared dead.
    link_lease: float = 10.0
    extra: dict[str, Any] = field(default_factory=dict)

    def prefix(self) -> str:
        return f"mrcomm/{self.team}"


def check_key_chunk(value: str, option: str) -> str:
    """A team or agent id must be one plain Zenoh key chunk (no ``/``, ``*``, ``$``)."""
    if not _KEY_CHUNK.match(value):
        raise InputError(
            f"{value[:60]!r} is not a valid id (1-48 letters, digits, '_', '-', '.')",
            field=option,
        )
    return value


def normalise_endpoint(value: str, protocol: str, option: str) -> str:
    """``host:port`` -> ``<protocol>/host:port``; a full locator is checked as given."""
    text = value.strip()
    if "/" not in text:
        text = f"{protocol}/{text}"
    match = _ENDPOINT.match(text)
    if match is None:
        raise InputError(
            f"bad endpoint {value!r}; expected PROTOCOL/HOST:PORT, e.g. tcp/127.0.0.1:7447",
            field=option,
        )
    proto = match.group("proto")
    if proto not in PROTOCOLS:
        raise InputError(
            f"unsupported protocol {proto!r} in {value!r}; choose from {', '.join(PROTOCOLS)}",
            field=option,
        )
    port = int(match.group("port"))
    if not 0 <= port <= 65535:
        raise InputError(f"port {port} out of range in {value!r}", field=option)
    return text


def make_options(
    *,
    team: str = "team",
    listen: list[str] | tuple[str, ...] = (),
    connect: list[str] | tuple[str, ...] = (),
    multicast: bool = False,
    protocol: str = "tcp",
    tls_ca: Path | None = None,
    tls_cert: Path | None = None,
    tls_key: Path | None = None,
    acl_grants: Mapping[str, Sequence[str]] | None = None,
    config_file: Path | None = None,
    link_lease: float = 10.0,
) -> ZenohOptions:
    """Validate command-line choices into :class:`ZenohOptions` (one-line errors)."""
    check_key_chunk(team, "--team")
    if protocol not in ("tcp", "udp"):
        raise InputError(f"unknown protocol {protocol!r}; choose tcp or udp", field="--protocol")
    given = [p for p in (tls_ca, tls_cert, tls_key) if p is not None]
    tls: TlsFiles | None = None
    if given:
        if len(given) != 3:
            raise InputError("TLS needs all of --tls-ca, --tls-cert and --tls-key", field="--tls")
        assert tls_ca is not None and tls_cert is not None and tls_key is not None
        _check_pem(tls_ca, "--tls-ca", "CERTIFICATE")
        _check_pem(tls_cert, "--tls-cert", "CERTIFICATE")
        _check_pem(tls_key, "--tls-key", "PRIVATE KEY")
        tls = TlsFiles(tls_ca, tls_cert, tls_key)
        if protocol == "udp":
            raise InputError("TLS runs over TCP; drop --protocol udp", field="--protocol")
    if acl_grants is not None and tls is None:
        raise InputError(
            "an access-control list identifies members by certificate: it needs TLS",
            field="--acl",
        )
    wire = "tls" if tls is not None else protocol
    if config_file is not None and not config_file.is_file():
        raise InputError("file not found", file=config_file, field="--zenoh-config")
    if link_lease <= 0:
        raise InputError("must be positive", field="--link-lease")
    return ZenohOptions(
        team=team,
        listen=tuple(normalise_endpoint(e, wire, "--listen") for e in listen),
        connect=tuple(normalise_endpoint(e, wire, "--connect") for e in connect),
        multicast=multicast,
        protocol=wire,
        tls=tls,
        acl_grants=_check_grants(acl_grants) if acl_grants is not None else None,
        config_file=config_file,
        link_lease=link_lease,
    )


def _check_pem(path: Path, option: str, kind: str) -> None:
    if not path.is_file():
        raise InputError("file not found", file=path, field=option)
    try:
        text = path.read_text(errors="replace")
    except OSError as err:
        raise InputError(f"cannot read: {err.strerror}", file=path, field=option) from None
    if "-----BEGIN " not in text or kind not in text:
        raise InputError(f"not a PEM {kind.lower()} file", file=path, field=option)


def config_json(options: ZenohOptions) -> dict[str, Any]:
    """The settings we impose, as ``key -> JSON value`` for ``Config.insert_json5``."""
    settings: dict[str, Any] = {
        "mode": "peer",
        "scouting/multicast/enabled": options.multicast,
        # Processes start in any order and links come and go: never give up on a
        # configured peer, retry quickly (1 s at most between attempts).
        "connect/exit_on_failure": False,
        "connect/timeout_ms": -1,
        "connect/retry": {
            "period_init_ms": 250,
            "period_max_ms": 1000,
            "period_increase_factor": 2,
        },
        "transport/link/tx/lease": int(options.link_lease * 1000),
    }
    if options.listen:
        settings["listen/endpoints"] = list(options.listen)
    if options.connect:
        settings["connect/endpoints"] = list(options.connect)
    if options.tls is not None:
        tls = options.tls
        # TLS links only, both ways: without this a session that was given no listening
        # endpoint listens in the clear on Zenoh's default (tcp/[::]:0), and peers that
        # learn that locator by gossip connect to it over plain TCP, where no certificate
        # says who is speaking (the access-control list then refuses everything from it).
        settings["transport/link/protocols"] = ["tls"]
        if not options.listen:
            settings["listen/endpoints"] = []
        settings["transport/link/tls"] = {
            "root_ca_certificate": str(tls.ca),
            "listen_private_key": str(tls.key),
            "listen_certificate": str(tls.cert),
            "connect_private_key": str(tls.key),
            "connect_certificate": str(tls.cert),
            "enable_mtls": True,
            "verify_name_on_connect": True,
        }
    if options.acl_grants is not None:
        settings["access_control"] = acl_json(options.prefix(), dict(options.acl_grants))
    settings.update(options.extra)
    return settings


def _check_grants(grants: Mapping[str, Sequence[str]]) -> tuple[tuple[str, tuple[str, ...]], ...]:
    if not grants:
        raise InputError("the access-control list names no member", field="--acl")
    out = []
    for member, chunks in grants.items():
        check_key_chunk(member, "--acl")
        out.append((member, tuple(check_key_chunk(c, "--acl") for c in chunks)))
    return tuple(out)


def acl_json(prefix: str, grants: Mapping[str, Sequence[str]]) -> dict[str, Any]:
    """Deny by default. Every member may subscribe to and query the team's keys and
    receive anything on them (egress); what a node accepts *from* a member (ingress)
    as a publication or a liveliness token must lie under one of its granted chunks."""
    members = list(grants)
    rules: list[dict[str, Any]] = [
        {
            "id": "read",
            "messages": _ACL_READING,
            "flows": ["egress", "ingress"],
            "permission": "allow",
            "key_exprs": [f"{prefix}/**"],
        },
        {
            # What this node sends to a member: everything on the team's keys (what it
            # may send at all is for the receivers to judge, on their ingress).
            "id": "deliver",
            "messages": _ACL_AUTHORED,
            "flows": ["egress"],
            "permission": "allow",
            "key_exprs": [f"{prefix}/**"],
        },
    ]
    subjects: list[dict[str, Any]] = [{"id": "members", "cert_common_names": members}]
    policies: list[dict[str, Any]] = [{"rules": ["read", "deliver"], "subjects": ["members"]}]
    for index, (member, chunks) in enumerate(grants.items()):
        if not chunks:
            continue
        rule = f"own{index}"
        rules.append(
            {
                "id": rule,
                "messages": _ACL_AUTHORED,
                "flows": ["ingress"],
                "permission": "allow",
                "key_exprs": [f"{prefix}/{chunk}/**" for chunk in chunks],
            }
        )
        subjects.append({"id": f"member{index}", "cert_common_names": [member]})
        policies.append({"rules": [rule], "subjects": [f"member{index}"]})
    return {
        "enabled": True,
        "default_permission": "deny",
        "rules": rules,
        "subjects": subjects,
        "policies": policies,
    }


def build_config(options: ZenohOptions) -> Any:
    """A ``zenoh.Config`` for these options (imports zenoh only when called)."""
    import zenoh

    if options.config_file is not None:
        try:
            config = zenoh.Config.from_file(str(options.config_file))
        except zenoh.ZError as err:
            raise InputError(
                f"not a valid Zenoh config: {_first_line(err)}",
                file=options.config_file,
                field="--zenoh-config",
            ) from None
    else:
        config = zenoh.Config()
    for key, value in config_json(options).items():
        if options.config_file is not None and key in _FILE_OWNED and not _given(options, key):
            continue  # the file decides what the command line did not set
        try:
            config.insert_json5(key, json.dumps(value))
        except zenoh.ZError as err:
            message = f"bad Zenoh setting {key}: {_first_line(err)}"
            raise InputError(message, field="zenoh") from None
    return config


#: Settings a config file may own unless the command line sets them explicitly.
_FILE_OWNED = frozenset({"listen/endpoints", "connect/endpoints", "scouting/multicast/enabled"})


def _given(options: ZenohOptions, key: str) -> bool:
    if key == "listen/endpoints":
        return bool(options.listen)
    if key == "connect/endpoints":
        return bool(options.connect)
    return False


def _first_line(err: BaseException) -> str:
    text = str(err).strip().splitlines()
    return text[0] if text else type(err).__name__
