"""Who may speak as whom on a live team: each process's certificate name and the key
chunks it may publish under (the grants of the access-control list,
:func:`mrcomm.net.zenoh_config.acl_json`), and how a live command line chooses between
a team directory, explicit TLS files and no security at all (``--insecure``).

Grants follow what each process publishes: a robot's agent under its own id (and the
task assigner's, when the scenario hosts the assigner on that robot), its pulse under
``<robot>-pulse`` with the robot's certificate; the world under ``world`` (the clock)
and every robot's pulse key (when it measures the modelled radio for them); a
stand-alone assigner under ``assigner``. A member certificate therefore cannot
forge another robot's statuses, the clock, or another robot's base commands.
"""

from __future__ import annotations

import contextlib
import shutil
import tempfile
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from mrcomm.agents.assigner import ASSIGNER_ID
from mrcomm.agents.commands import OPERATOR_ID
from mrcomm.errors import InputError
from mrcomm.live.leftovers import remove_stale_teams, team_prefix
from mrcomm.live.protocol import WORLD_ID
from mrcomm.net.pulse import pulse_id
from mrcomm.net.team_dir import init_team, load_team, member_files
from mrcomm.net.zenoh_config import TlsFiles

if TYPE_CHECKING:
    from mrcomm.world.scenario import Scenario

#: The one line a process prints when it runs without authentication.
INSECURE_WARNING = (
    "mrcomm: warning: --insecure: no authentication and no encryption; any process that "
    "reaches the team's network can read its traffic and forge any member's messages, "
    "the clock included (docs/LIVE.md, Security)"
)


def grants(members: Sequence[str], scenario: Scenario | None = None) -> dict[str, tuple[str, ...]]:
    """Certificate name -> key chunks it may publish under. Without a scenario (a pulse
    process) the robots are the members other than the world and the assigner, and no
    robot hosts the assigner (a pulse hears only the clock)."""
    if scenario is not None:
        robots = [r.id for r in scenario.robots]
        spec = scenario.assigner
        host = spec.host if spec.kind == "robot" else None
    else:
        robots = [m for m in members if m not in (WORLD_ID, ASSIGNER_ID, OPERATOR_ID)]
        host = None
    out: dict[str, tuple[str, ...]] = {}
    for member in members:
        if member == WORLD_ID:
            out[member] = (WORLD_ID, *(pulse_id(r) for r in robots))
        elif member in (ASSIGNER_ID, OPERATOR_ID):
            out[member] = (member,)
        else:
            out[member] = (member, pulse_id(member), *((ASSIGNER_ID,) if member == host else ()))
    return out


@dataclass(frozen=True)
class Security:
    """What a live process presents and enforces: TLS files and ACL grants, or neither."""

    tls: TlsFiles | None
    grants: dict[str, tuple[str, ...]] | None

    @property
    def insecure(self) -> bool:
        return self.tls is None


def choose_security(
    *,
    identity: str,
    team_dir: Path | None,
    insecure: bool,
    tls_files: tuple[Path | None, Path | None, Path | None],
    acl: str | None,
    scenario: Scenario | None,
    explicit_config: bool = False,
) -> Security:
    """Resolve a live command line's security options (one-line errors):

    * ``--team-dir DIR`` — TLS with this process's certificate (``identity``) and the
      ACL over the team's members: the default way;
    * ``--tls-ca/--tls-cert/--tls-key`` [``--acl m1,m2``] — the same from explicit files;
    * ``--insecure`` — neither, after one warning line (the caller prints it);
    * nothing — refused, unless a Zenoh config file (``explicit_config``) decides.
    """
    given_tls = any(p is not None for p in tls_files)
    if team_dir is not None:
        if given_tls or acl is not None:
            raise InputError(
                "--team-dir gives the certificates and the ACL: drop --tls-ca, --tls-cert, "
                "--tls-key and --acl",
                field="--team-dir",
            )
        if insecure:
            raise InputError("--insecure contradicts --team-dir", field="--insecure")
        team = load_team(team_dir.expanduser())
        return Security(member_files(team, identity), grants(team.members, scenario))
    if given_tls:
        if insecure:
            raise InputError("--insecure contradicts --tls-*", field="--insecure")
        ca, cert, key = tls_files
        if ca is None or cert is None or key is None:
            raise InputError("TLS needs all of --tls-ca, --tls-cert and --tls-key", field="--tls")
        members = [m.strip() for m in acl.split(",") if m.strip()] if acl is not None else None
        return Security(
            TlsFiles(ca, cert, key), grants(members, scenario) if members is not None else None
        )
    if acl is not None:
        raise InputError(
            "an access-control list identifies members by certificate: it needs TLS",
            field="--acl",
        )
    if not insecure and not explicit_config:
        raise InputError(
            "no team certificates: give --team-dir DIR (made by mrcomm team init) or, to "
            "run without any authentication, --insecure",
            field="--team-dir",
        )
    return Security(None, None)


def live_members(scenario: Scenario) -> tuple[str, ...]:
    """Every process of a live mission that presents a certificate: the world, each
    robot (its pulse uses the robot's), and the task assigner."""
    return (WORLD_ID, *(r.id for r in scenario.robots), ASSIGNER_ID)


def check_team_members(team_dir: Path, members: Sequence[str]) -> None:
    """A team directory for ``mrcomm live`` must hold every process's certificate."""
    team = load_team(team_dir.expanduser())
    for member in members:
        member_files(team, member)


@contextlib.contextmanager
def throwaway_team(
    team_dir: Path | None, insecure: bool, members: Sequence[str]
) -> Iterator[Path | None]:
    """The team directory ``mrcomm live`` runs with: the one given; none with
    ``--insecure``; otherwise a throwaway team (a fresh CA and certificates valid for a
    day) in a private temporary directory, removed with its keys when the run ends."""
    if team_dir is not None or insecure:
        yield team_dir
        return
    remove_stale_teams()  # of runs killed before they could remove theirs
    holder = Path(tempfile.mkdtemp(prefix=team_prefix()))  # mode 0700
    try:
        yield init_team(holder / "team", members, days=1, name="mrcomm throwaway team").path
    finally:
        shutil.rmtree(holder, ignore_errors=True)
